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
from scipy.spatial import cKDTree

from swarm_envs.geometry import wrap_angle

__all__ = [
    "pack_nearest",
    "directed_links",
    "largest_component_fraction",
    "ir_directed_pairs",
    "occluder_lists",
    "occluder_frames",
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


# -- IR layer (swarm_envs.ir.layer, kernels in swarm_envs.ir.kernels) ------------------------------------------
def ir_directed_pairs(
    pairs: np.ndarray, positions: np.ndarray, headings: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Reference of :func:`swarm_envs.ir.kernels.directed_pairs_kernel` (``swarm_envs.ir.layer._directed_pairs``):
    both directions of the unordered ``pairs`` (U, 2) sorted by (rx, tx) with one argsort, and their frames.
    Returns (rx, tx, row of ``pairs``, tx centre in rx's frame (P, 2) (m), (cos, sin) of tx's heading in
    rx's frame (P, 2) from the robots' own cosines and sines, that heading (P,) (rad, :func:`wrap_angle`),
    centre distance (P,) (m))."""
    c, s = np.cos(headings), np.sin(headings)
    U, N = pairs.shape[0], positions.shape[0]
    rx = np.concatenate([pairs[:, 0], pairs[:, 1]]).astype(np.intp)
    tx = np.concatenate([pairs[:, 1], pairs[:, 0]]).astype(np.intp)
    order = np.argsort(rx.astype(np.int64) * N + tx)  # by (rx, tx); the keys are unique, so any sort agrees
    rx, tx = rx[order], tx[order]
    d = positions[tx] - positions[rx]
    c, s = c[rx], s[rx]
    rel = np.stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]], axis=-1)
    ct, st = np.cos(headings)[tx], np.sin(headings)[tx]
    rel_cs = np.stack([ct * c + st * s, st * c - ct * s], axis=-1)
    return rx, tx, order % U, rel, rel_cs, wrap_angle(headings[tx] - headings[rx]), np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1])


def occluder_lists(
    positions: np.ndarray, a: np.ndarray, b: np.ndarray, width: float, tree: cKDTree | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Reference of the occluder search (:func:`swarm_envs.ir.kernels.occluders_kernel` on the neighbour
    lists of ``swarm_envs.ir.layer._occluder_lists``; the robots :func:`swarm_envs.ir.layer.pair_occluders`
    and :func:`swarm_envs.ir.layer.line_of_sight` find): the third robots closer than ``width`` (m) to
    segment a[p]-b[p], as CSR (offsets (P + 1,), robots (K,) sorted per pair). The candidates are the
    KD-tree neighbours of both ends within ``sqrt(longest^2 / 4 + width^2)``, tested as flat (pair,
    candidate) arrays."""
    from swarm_envs.ir.layer import _neighbour_csr

    positions = np.ascontiguousarray(positions, dtype=float).reshape(-1, 2)
    a = np.ascontiguousarray(a, dtype=np.int64).reshape(-1)
    b = np.ascontiguousarray(b, dtype=np.int64).reshape(-1)
    P, N = a.shape[0], positions.shape[0]
    if P == 0 or N < 3:
        return np.zeros(P + 1, dtype=np.int64), np.zeros(0, dtype=np.int64)
    if tree is None:
        tree = cKDTree(positions)
    seg = positions[b] - positions[a]
    length = np.hypot(seg[:, 0], seg[:, 1])
    reach = float(np.sqrt(0.25 * float(length.max()) ** 2 + float(width) ** 2 + 2e-9))
    starts, counts, nbrs = _neighbour_csr(positions, reach, tree)
    pairs, cands = [], []
    L2 = np.where(length > 0, length * length, 1.0)
    for end in (a, b):  # two vectorised passes: neighbours of a, then of b
        c = counts[end]
        pair = np.repeat(np.arange(P), c)
        offset = np.arange(int(c.sum())) - np.repeat(np.cumsum(c) - c, c)
        cand = nbrs[np.repeat(starts[end], c) + offset]
        keep = (cand != a[pair]) & (cand != b[pair])
        cand, pair = cand[keep], pair[keep]
        ap = positions[cand] - positions[a[pair]]
        sp = seg[pair]
        t = np.clip((ap[:, 0] * sp[:, 0] + ap[:, 1] * sp[:, 1]) / L2[pair], 0.0, 1.0)
        qx, qy = ap[:, 0] - t * sp[:, 0], ap[:, 1] - t * sp[:, 1]
        near = qx * qx + qy * qy < width * width
        pairs.append(pair[near])
        cands.append(cand[near])
    key = np.unique(np.concatenate(pairs).astype(np.int64) * N + np.concatenate(cands))
    offsets = np.concatenate([[0], np.cumsum(np.bincount(key // N, minlength=P))]).astype(np.int64)
    return offsets, (key % N).astype(np.int64)


def occluder_frames(
    positions: np.ndarray, headings: np.ndarray, rx: np.ndarray, pair_of: np.ndarray, offsets: np.ndarray, idx: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Reference of :func:`swarm_envs.ir.kernels.occluder_frames_kernel`: the occluders of pair
    ``pair_of[p]`` (CSR ``offsets``, ``idx``) as centres in receiver ``rx[p]``'s frame. Returns (offsets
    (P + 1,), centres (K, 2))."""
    rx = np.ascontiguousarray(rx, dtype=np.int64)
    pair_of = np.ascontiguousarray(pair_of, dtype=np.int64)
    counts = np.diff(offsets)[pair_of]
    out = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    row = np.repeat(np.arange(rx.shape[0]), counts)
    k = idx[np.repeat(offsets[pair_of], counts) + np.arange(int(out[-1])) - np.repeat(out[:-1], counts)]
    d = positions[k] - positions[rx[row]]
    c, s = np.cos(headings[rx[row]]), np.sin(headings[rx[row]])
    return out, np.stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]], axis=-1).reshape(-1, 2)
