"""Swarm-level task metrics computed from ground truth (they feed rewards and ``infos``, never observations)."""

from __future__ import annotations

import numpy as np

from swarm_envs._compile._numba import njit

__all__ = ["largest_component_fraction", "neighbourhood_sums"]


def largest_component_fraction(
    positions: np.ndarray, link_distance: float, pairs: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """For (B, N, 2) positions of B env copies: (largest-component fraction (B,), number of components
    (B,)), linking centres of one copy closer than ``link_distance`` (m), chained. One graph for all copies
    (pairs never cross copies), its components found by a compiled union-find (plain reference with scipy's
    connected components: :func:`swarm_envs._compile.reference.largest_component_fraction`). ``pairs``: those links
    if the caller already has them (``copy_pairs`` over the B x N rows)."""
    from swarm_envs.sensing.ideal import copy_pairs

    B, N = positions.shape[:2]
    if pairs is None:
        pairs = copy_pairs(positions.reshape(B * N, 2), link_distance, N)
    largest, count = _component_stats_kernel(np.ascontiguousarray(pairs, dtype=np.int64).reshape(-1, 2), B, N)
    return largest / N, count


@njit(cache=True, nogil=True)
def _neighbourhood_sums_kernel(values: np.ndarray, pairs: np.ndarray):  # pragma: no cover - compiled
    """:func:`neighbourhood_sums`: pairs in (i, j) order reach row r first from pairs (i, r), i < r
    increasing, then from pairs (r, j), j increasing."""
    sums = values.copy()
    counts = np.empty(values.shape[0], np.int64)
    counts[:] = 1
    for p in range(pairs.shape[0]):
        i, j = pairs[p, 0], pairs[p, 1]
        for f in range(values.shape[1]):
            sums[i, f] += values[j, f]
            sums[j, f] += values[i, f]
        counts[i] += 1
        counts[j] += 1
    return sums, counts


@njit(cache=True, nogil=True)
def _component_stats_kernel(pairs: np.ndarray, B: int, N: int):  # pragma: no cover - compiled
    """(largest component size (B,) float, number of components (B,) int) of the graph of ``pairs``
    over B copies of N rows, by union-find (union by index, path halving)."""
    n = B * N
    parent = np.arange(n)
    for p in range(pairs.shape[0]):
        a, b = pairs[p, 0], pairs[p, 1]
        while parent[a] != a:
            parent[a] = parent[parent[a]]
            a = parent[a]
        while parent[b] != b:
            parent[b] = parent[parent[b]]
            b = parent[b]
        if a < b:
            parent[b] = a
        elif b < a:
            parent[a] = b
    size = np.empty(n, np.int64)
    size[:] = 0
    for i in range(n):
        r = i
        while parent[r] != r:
            r = parent[r]
        size[r] += 1
    largest = np.empty(B, np.float64)
    largest[:] = 0.0
    count = np.empty(B, np.int64)
    count[:] = 0
    for i in range(n):
        if size[i] > 0:
            c = i // N
            count[c] += 1
            if size[i] > largest[c]:
                largest[c] = size[i]
    return largest, count


def neighbourhood_sums(values: np.ndarray, pairs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per row of ``values`` (n, F): (the sum of its own and its linked rows' values (n, F), 1 + its number
    of links (n,)), over sorted (P, 2) pairs i < j (:func:`swarm_envs.sensing.ideal.copy_pairs`). Each sum
    adds the row's own value, then the linked rows' in increasing index (the same floating-point order as
    ``np.add.at`` over links sorted by (row, neighbour)), in one compiled pass."""
    values = np.ascontiguousarray(values, dtype=np.float64)
    pairs = np.ascontiguousarray(pairs, dtype=np.int64).reshape(-1, 2)
    return _neighbourhood_sums_kernel(values, pairs)
