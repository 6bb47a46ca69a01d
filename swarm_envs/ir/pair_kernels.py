"""Compiled pair finding: the directed candidate pairs of robots within IR reach, each robot's neighbours as
compressed rows, and the links kept after the gains are known."""

from __future__ import annotations
import math
import numpy as np
from swarm_envs._compile._numba import njit  # numba.njit whose cache recovers from corrupted files

__all__ = ["neighbour_csr_kernel", "select_links_kernel", "directed_pairs_kernel"]


@njit(cache=True, error_model="numpy", nogil=True)
def neighbour_csr_kernel(positions: np.ndarray, pairs: np.ndarray, reach2: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Neighbour lists as CSR (starts (N,), counts (N,), neighbours) from the unordered ``pairs`` (U, 2):
    both ends of every pair whose squared centre distance (computed as :func:`occluders_kernel` does)
    is at most ``reach2`` (m^2). Equal to the lists of a KD-tree query within ``sqrt(reach2)`` when
    ``pairs`` holds every pair closer than a larger range (up to the order within a list)."""
    N, U = positions.shape[0], pairs.shape[0]
    keep = np.empty(U, np.int64)
    counts = np.empty(N, np.int64)
    counts[:] = 0
    n = 0
    for u in range(U):
        a, b = pairs[u, 0], pairs[u, 1]
        d2 = (positions[b, 0] - positions[a, 0]) ** 2 + (positions[b, 1] - positions[a, 1]) ** 2
        keep[n] = u
        n += np.int64(d2 <= reach2)
    for t in range(n):
        counts[pairs[keep[t], 0]] += 1
        counts[pairs[keep[t], 1]] += 1
    starts = np.empty(N, np.int64)
    fill = np.empty(N, np.int64)
    acc = 0
    for r in range(N):
        starts[r] = acc
        fill[r] = acc
        acc += counts[r]
    nbrs = np.empty(acc, np.int64)
    for t in range(n):
        a, b = pairs[keep[t], 0], pairs[keep[t], 1]
        nbrs[fill[a]] = b
        fill[a] += 1
        nbrs[fill[b]] = a
        fill[b] += 1
    return starts, counts, nbrs


@njit(cache=True, error_model="numpy", nogil=True)
def select_links_kernel(
    lit: np.ndarray, rx: np.ndarray, tx: np.ndarray, rel: np.ndarray, rel_heading: np.ndarray, distance: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Rows ``lit`` of the links' arrays in one pass: ``(rx[lit], tx[lit], rel[lit], rel_heading[lit],
    distance[lit])`` (numpy's fancy indexing, one array at a time, is ~5x slower at 36k links)."""
    n = lit.shape[0]
    rx_, tx_ = np.empty(n, rx.dtype), np.empty(n, tx.dtype)
    rel_, rh_, d_ = np.empty((n, 2), np.float64), np.empty(n, np.float64), np.empty(n, np.float64)
    for k in range(n):
        p = lit[k]
        rx_[k], tx_[k] = rx[p], tx[p]
        rel_[k, 0], rel_[k, 1] = rel[p, 0], rel[p, 1]
        rh_[k], d_[k] = rel_heading[p], distance[p]
    return rx_, tx_, rel_, rh_, d_


@njit(cache=True, error_model="numpy", nogil=True)
def directed_pairs_kernel(
    pairs: np.ndarray, positions: np.ndarray, headings: np.ndarray, cos_h: np.ndarray, sin_h: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Both directions of U unordered pairs ``pairs`` (U, 2), sorted by (rx, tx), and their geometry.

    Two counting-sort passes (by tx, then stably by rx): the same order as sorting the unique keys
    ``rx * N + tx``. Per directed pair p, with ``d = x[tx] - x[rx]``
    (world frame) and ``cos_h, sin_h`` the robots' heading cosines / sines: ``rel = (c d_x + s d_y,
    -s d_x + c d_y)`` (tx centre in rx's frame, c, s of rx), ``rel_heading`` = heading of tx - heading
    of rx wrapped to (-pi, pi] and ``distance = sqrt(d_x^2 + d_y^2)``: the same values as the numpy
    reference (:func:`swarm_envs._compile.reference.ir_directed_pairs`), bit for bit.

    Returns rx (P,), tx (P,), pair_of (P,) the row of ``pairs`` of each, rel (P, 2), (cos, sin) of the
    relative heading (P, 2) (from the robots' cosines and sines), rel_heading (P,), distance (P,), P = 2 U.
    """
    U, N = pairs.shape[0], positions.shape[0]
    P = 2 * U
    start = np.empty(N + 1, np.int64)
    start[:] = 0
    for u in range(U):
        start[pairs[u, 0] + 1] += 1
        start[pairs[u, 1] + 1] += 1
    for r in range(N):
        start[r + 1] += start[r]
    # each robot is the receiver of as many directed pairs as it is the transmitter of: one bucket layout
    fill = start[:N].copy()
    by_tx_rx = np.empty(P, np.int64)  # pass 1: directed pairs bucketed by transmitter
    by_tx_u = np.empty(P, np.int64)
    for u in range(U):
        for k in range(2):
            a, b = pairs[u, k], pairs[u, 1 - k]
            q = fill[b]
            fill[b] += 1
            by_tx_rx[q] = a
            by_tx_u[q] = u
    for i in range(N):  # element copy: a slice assignment from an array compiles numba's shape-error text
        fill[i] = start[i]
    rx = np.empty(P, np.int64)
    tx = np.empty(P, np.int64)
    pair_of = np.empty(P, np.int64)
    for b in range(N):  # pass 2, stable: by receiver, each bucket in transmitter order
        for q0 in range(start[b], start[b + 1]):
            a = by_tx_rx[q0]
            q = fill[a]
            fill[a] += 1
            rx[q] = a
            tx[q] = b
            pair_of[q] = by_tx_u[q0]
    rel = np.empty((P, 2), np.float64)
    rel_cs = np.empty((P, 2), np.float64)
    rel_heading = np.empty(P, np.float64)
    distance = np.empty(P, np.float64)
    two_pi = 2.0 * np.pi
    for p in range(P):
        a, b = rx[p], tx[p]
        dx, dy = positions[b, 0] - positions[a, 0], positions[b, 1] - positions[a, 1]
        c, s = cos_h[a], sin_h[a]
        rel[p, 0] = c * dx + s * dy
        rel[p, 1] = -s * dx + c * dy
        rel_cs[p, 0] = cos_h[b] * c + sin_h[b] * s
        rel_cs[p, 1] = sin_h[b] * c - cos_h[b] * s
        y = np.pi - (headings[b] - headings[a])
        if y >= two_pi and y < 2.0 * two_pi:  # y % 2 pi without fmod; y - 2 pi is exact here (Sterbenz)
            y -= two_pi
        elif y < 0.0 and y > -two_pi:
            y += two_pi
        elif y < 0.0 or y >= two_pi:
            y %= two_pi
        rel_heading[p] = np.pi - y
        distance[p] = math.sqrt(dx * dx + dy * dy)
    return rx, tx, pair_of, rel, rel_cs, rel_heading, distance
