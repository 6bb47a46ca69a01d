"""Plain numpy references of the compiled kernels, for the tests that compare the two.

The simulator runs the numba kernels only; each function here computes what one kernel (or the function
that calls it) computes, in straightforward vectorised numpy (scipy where a graph or a KD-tree is the
plain tool), and its docstring names that kernel. The tests check the kernels against these functions,
most of them bit for bit. Nothing in the package calls this module.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components

__all__ = [
    "pack_nearest",
    "directed_links",
    "largest_component_fraction",
]


# -- observations (swarm_envs.observation) -------------------------------------------------------------------
def pack_nearest(n_rows: int, row: np.ndarray, key: np.ndarray, values: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Reference of :func:`swarm_envs.observation.pack_nearest` (kernels ``_pack_nearest_kernel`` and
    ``_nearest_slots_kernel`` of :mod:`swarm_envs.observation`, whose ``order`` is
    :func:`~swarm_envs.observation.nearest_slots`): a stable sort of the links by row, then key (NaN last),
    and the first ``k`` of each row. Returns ``(packed (n_rows, k, F), order (n_rows, k))``."""
    values = np.asarray(values, dtype=np.float64)
    if values.ndim == 1:
        values = values[:, None]
    packed = np.zeros((n_rows, k, values.shape[1]))
    order = np.full((n_rows, k), -1, dtype=np.int64)
    if len(row) == 0 or k == 0:
        return packed, order
    idx = np.lexsort((key, row))
    sorted_rows = row[idx]
    starts = np.searchsorted(sorted_rows, sorted_rows, side="left")
    rank = np.arange(len(idx)) - starts
    keep = rank < k
    packed[sorted_rows[keep], rank[keep]] = values[idx[keep]]
    order[sorted_rows[keep], rank[keep]] = idx[keep]
    return packed, order


# -- ideal sensing and metrics (swarm_envs.sensing.ideal, swarm_envs.metrics) ----------------------------------
def directed_links(pairs: np.ndarray, n_rows: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Reference of :func:`swarm_envs.sensing.ideal.directed_links` (kernel ``_directed_links_kernel``):
    both directions of sorted (P, 2) pairs i < j, sorted by (rx, tx) with one argsort of a unique key, and
    the index of each link's pair. Returns (rx, tx, pair index)."""
    pairs = np.ascontiguousarray(pairs, dtype=np.int64).reshape(-1, 2)
    if len(pairs) == 0:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty, empty
    rx = np.concatenate([pairs[:, 0], pairs[:, 1]])
    tx = np.concatenate([pairs[:, 1], pairs[:, 0]])
    order = np.argsort(rx * int(n_rows) + tx)
    return rx[order], tx[order], np.concatenate([np.arange(len(pairs))] * 2)[order]


def largest_component_fraction(positions: np.ndarray, link_distance: float, pairs: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Reference of :func:`swarm_envs.metrics.largest_component_fraction` (kernel
    ``_component_stats_kernel``, a union-find): for (B, N, 2) positions, scipy's connected components of
    one graph over all copies (the KD-tree's pairs, :func:`swarm_envs.sensing.ideal.candidate_pairs`, unless
    ``pairs`` are given). Returns (largest-component fraction (B,), number of components (B,))."""
    from swarm_envs.sensing.ideal import candidate_pairs

    B, N = positions.shape[:2]
    copy = np.repeat(np.arange(B), N)
    if pairs is None:
        pairs = candidate_pairs(positions.reshape(B * N, 2), link_distance, copy)
    n = B * N
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    labels = connected_components(graph, directed=False)[1]
    sizes = np.bincount(labels, minlength=n)
    # components never span copies: each label belongs to the copy of its robots
    label_copy = np.full(sizes.size, -1)
    label_copy[labels] = copy
    present = sizes > 0
    largest = np.zeros(B)
    np.maximum.at(largest, label_copy[present], sizes[present])
    count = np.bincount(label_copy[present], minlength=B)
    return largest / N, count
