"""Compiled occluder search: for every candidate IR link, the robots whose bodies may block its rays (neighbour
lists sorted by distance, per-chunk search on helper threads, gathered in link order), and the occluders' frames."""

from __future__ import annotations
import numpy as np
from swarm_envs._compile._numba import njit  # numba.njit whose cache recovers from corrupted files
from swarm_envs._compile._worker import run_chunks
from swarm_envs.ir.ray_kernels import DISC_TOL, segment_hits_disc

__all__ = ["occluders_kernel", "occluders_kernel_threaded", "occluder_frames_kernel"]


@njit(cache=True, error_model="numpy", nogil=True)
def occluders_kernel(
    positions: np.ndarray,
    width: float,
    rx: np.ndarray,
    tx: np.ndarray,
    starts: np.ndarray,
    counts: np.ndarray,
    nbrs: np.ndarray,
) -> tuple[np.ndarray, np.ndarray]:
    """Third robots whose centre is closer than ``width`` to the centre segment rx[p]-tx[p], as CSR.

    Candidates are the neighbour lists (CSR ``starts``, ``counts``, ``nbrs``) of both ends, which must
    reach ``sqrt(|rx tx|^2 / 4 + width^2 + 1e-9)``: a centre closer than ``width`` to the segment is closer than
    ``sqrt(|rx tx|^2 / 4 + width^2)`` (Pythagoras, foot point on the nearer half) to its nearer end, so
    each end's list, sorted by distance here, is read only up to that pair's own reach, and each end
    tests only the candidates whose projection on the segment falls in its own half (none twice). Returns offsets (P + 1,) and robot indices (K,), each pair's sorted.

    The disc test is :func:`hits_disc`'s (the verdict of :func:`segment_hits_disc`: nearest end, or the
    cross product against the width with a 1e-6 relative margin) evaluated without branching on its
    outcome, candidates kept by an index increment; the few within the margin get the exact test after
    the pair's loop.
    """
    N = positions.shape[0]
    near, dist2 = nbrs.copy(), np.empty(nbrs.shape[0], np.float64)
    _sort_neighbours(0, N, positions, starts, counts, near, dist2)
    base, cnt, idx = _occluder_buffers(rx, tx, counts, 1)
    _occluders_chunk(0, rx.shape[0], base[0], positions, width, rx, tx, starts, counts, near, dist2, cnt, idx)
    return _occluders_gather(base, cnt, idx, 1)


def occluders_kernel_threaded(
    positions: np.ndarray,
    width: float,
    rx: np.ndarray,
    tx: np.ndarray,
    starts: np.ndarray,
    counts: np.ndarray,
    nbrs: np.ndarray,
    n_chunks: int,
) -> tuple[np.ndarray, np.ndarray]:
    """:func:`occluders_kernel` on ``n_chunks`` threads (this one and the helper threads of
    :func:`swarm_envs._compile._worker.run_chunks`): robots' lists sorted and pairs searched in contiguous chunks,
    one thread each, every pair by the same code into its own part of the buffer, then gathered in
    order; the same result bit for bit, whatever the number of chunks or threads."""
    N, P = positions.shape[0], rx.shape[0]
    n_chunks = max(1, int(n_chunks))
    near, dist2 = nbrs.copy(), np.empty(nbrs.shape[0])
    run_chunks(lambda k: _sort_neighbours_kernel((N * k) // n_chunks, (N * (k + 1)) // n_chunks, positions, starts, counts, near, dist2), n_chunks)
    base, cnt, idx = _occluder_buffers_kernel(rx, tx, counts, n_chunks)
    run_chunks(
        lambda k: _occluders_chunk_kernel(
            (P * k) // n_chunks, (P * (k + 1)) // n_chunks, base[k], positions, float(width), rx, tx, starts, counts, near, dist2, cnt, idx
        ),
        n_chunks,
    )
    return _occluders_gather_kernel(base, cnt, idx, n_chunks)

# entry points of the threaded search: the inlined helpers below, each compiled on its own
@njit(cache=True, error_model="numpy", nogil=True)
def _sort_neighbours_kernel(r0: int, r1: int, positions: np.ndarray, starts: np.ndarray, counts: np.ndarray, near: np.ndarray, dist2: np.ndarray) -> None:
    _sort_neighbours(r0, r1, positions, starts, counts, near, dist2)


@njit(cache=True, error_model="numpy", nogil=True)
def _occluder_buffers_kernel(rx: np.ndarray, tx: np.ndarray, counts: np.ndarray, n_chunks: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    return _occluder_buffers(rx, tx, counts, n_chunks)


@njit(cache=True, error_model="numpy", nogil=True)
def _occluders_chunk_kernel(
    p0: int, p1: int, K: int, positions: np.ndarray, width: float, rx: np.ndarray, tx: np.ndarray, starts: np.ndarray,
    counts: np.ndarray, near: np.ndarray, dist2: np.ndarray, cnt: np.ndarray, idx: np.ndarray,
) -> None:
    _occluders_chunk(p0, p1, K, positions, width, rx, tx, starts, counts, near, dist2, cnt, idx)


@njit(cache=True, error_model="numpy", nogil=True)
def _occluders_gather_kernel(base: np.ndarray, cnt: np.ndarray, idx: np.ndarray, n_chunks: int) -> tuple[np.ndarray, np.ndarray]:
    return _occluders_gather(base, cnt, idx, n_chunks)


@njit(cache=True, inline="always", error_model="numpy", nogil=True)
def _sort_neighbours(r0: int, r1: int, positions: np.ndarray, starts: np.ndarray, counts: np.ndarray, near: np.ndarray, dist2: np.ndarray) -> None:
    """Neighbour lists of robots ``r0:r1`` (``near``, in place) by increasing distance, squared distances
    into ``dist2`` (insertion sort: the lists are short)."""
    for r in range(r0, r1):
        s0 = starts[r]
        for q in range(s0, s0 + counts[r]):
            k = near[q]
            d2 = (positions[k, 0] - positions[r, 0]) ** 2 + (positions[k, 1] - positions[r, 1]) ** 2
            q2 = q
            while q2 > s0 and dist2[q2 - 1] > d2:
                dist2[q2] = dist2[q2 - 1]
                near[q2] = near[q2 - 1]
                q2 -= 1
            dist2[q2] = d2
            near[q2] = k


@njit(cache=True, inline="always", error_model="numpy", nogil=True)
def _occluder_buffers(rx: np.ndarray, tx: np.ndarray, counts: np.ndarray, n_chunks: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Buffers of an occluder search in ``n_chunks`` chunks of pairs: the start of each chunk's part of
    ``idx`` (n_chunks + 1,), per-pair counts (P,) and ``idx``, sized by the candidates of both ends of
    every pair (a pair's occluders are among them)."""
    P = rx.shape[0]
    base = np.empty(n_chunks + 1, np.int64)
    base[:] = 0
    for k in range(n_chunks):
        acc = 0
        for p in range((P * k) // n_chunks, (P * (k + 1)) // n_chunks):
            acc += counts[rx[p]] + counts[tx[p]]
        base[k + 1] = base[k] + acc
    cnt = np.empty(P, np.int64)
    cnt[:] = 0
    return base, cnt, np.empty(max(1, base[n_chunks]), np.int64)


@njit(cache=True, inline="always", error_model="numpy", nogil=True)
def _occluders_chunk(
    p0: int, p1: int, K: int, positions: np.ndarray, width: float, rx: np.ndarray, tx: np.ndarray, starts: np.ndarray,
    counts: np.ndarray, near: np.ndarray, dist2: np.ndarray, cnt: np.ndarray, idx: np.ndarray,
) -> None:
    """Occluders of pairs ``p0:p1`` (:func:`occluders_kernel`), each pair's sorted, one after the other into
    ``idx`` from ``K`` on; their numbers into ``cnt``."""
    w2 = width * width
    w2_hi, w2_lo = w2 * (1.0 + DISC_TOL), w2 * (1.0 - DISC_TOL)
    grey = np.empty(max(1, 2 * positions.shape[0]), np.int64)  # one pair's candidates near the disc edge
    for p in range(p0, p1):
        K0 = K
        a, b = rx[p], tx[p]
        ax, ay = positions[a, 0], positions[a, 1]
        sx, sy = positions[b, 0] - ax, positions[b, 1] - ay
        L2 = sx * sx + sy * sy
        # a centre within width of the segment is within sqrt(L2 / 4 + width^2) of the end its foot point
        # is nearer to (or within width of an end); margin far above rounding
        reach2 = 0.25 * L2 + w2 + 1e-9
        half = 0.5 * L2
        # the segment as segment_hits_disc(ax, ay, ax + sx, ay + sy, ...) computes it
        x1, y1 = ax + sx, ay + sy
        tx_, ty_ = x1 - ax, y1 - ay
        T2 = tx_ * tx_ + ty_ * ty_
        n_grey = 0
        for e in range(2):
            end = a if e == 0 else b
            for q in range(starts[end], starts[end] + counts[end]):
                if dist2[q] > reach2:
                    break
                k = near[q]
                px, py = positions[k, 0] - ax, positions[k, 1] - ay
                # each candidate from one end only: a's half (projection <= L2 / 2) from a, the rest from b
                mine = ((px * sx + py * sy <= half) == (e == 0)) & (k != a) & (k != b)
                # the verdict of hits_disc (== segment_hits_disc) without a branch on its outcome
                dot = px * tx_ + py * ty_
                qx, qy = px - tx_, py - ty_
                cr = px * ty_ - py * tx_
                cr2 = cr * cr
                at_start = dot <= 0.0
                at_end = (dot >= T2) & (not at_start)
                inner = (not at_start) & (not at_end)
                hit = (at_start & (px * px + py * py < w2)) | (at_end & (qx * qx + qy * qy < w2)) | (inner & (cr2 <= w2_lo * T2))
                idx[K] = k
                K += np.int64(mine & hit)
                # within 1e-6 of the radius the exact test decides, after the loop (rare)
                grey[n_grey] = k
                n_grey += np.int64(mine & inner & (cr2 < w2_hi * T2) & (cr2 > w2_lo * T2))
        for t in range(n_grey):
            k = grey[t]
            if segment_hits_disc(ax, ay, x1, y1, positions[k, 0], positions[k, 1], w2):
                idx[K] = k
                K += 1
        for q in range(K0 + 1, K):  # insertion sort: each pair's occluders in robot order
            q2 = q
            while q2 > K0 and idx[q2 - 1] > idx[q2]:
                idx[q2 - 1], idx[q2] = idx[q2], idx[q2 - 1]
                q2 -= 1
        cnt[p] = K - K0


@njit(cache=True, inline="always", error_model="numpy", nogil=True)
def _occluders_gather(base: np.ndarray, cnt: np.ndarray, idx: np.ndarray, n_chunks: int) -> tuple[np.ndarray, np.ndarray]:
    """CSR (offsets (P + 1,), robots (K,)) from the chunks' parts of ``idx`` (:func:`_occluder_buffers`)."""
    P = cnt.shape[0]
    offsets = np.empty(P + 1, np.int64)
    offsets[:] = 0
    for p in range(P):
        offsets[p + 1] = offsets[p] + cnt[p]
    out = np.empty(offsets[P], np.int64)
    for k in range(n_chunks):
        first = (P * k) // n_chunks
        n = offsets[(P * (k + 1)) // n_chunks] - offsets[first]
        for q in range(n):  # element copy (a slice assignment from an array compiles numba's shape-error text)
            out[offsets[first] + q] = idx[base[k] + q]
    return offsets, out


@njit(cache=True, error_model="numpy", nogil=True)
def occluder_frames_kernel(
    positions: np.ndarray, cos_h: np.ndarray, sin_h: np.ndarray, rx: np.ndarray, pair_of: np.ndarray, offsets: np.ndarray, idx: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Occluders of pair ``pair_of[p]`` (CSR ``offsets``, ``idx``) as centres in receiver rx[p]'s body
    frame (``cos_h``, ``sin_h``: the robots' heading cosines and sines): returns offsets (P + 1,) and
    centres (K, 2)."""
    P = rx.shape[0]
    out_off = np.empty(P + 1, np.int64)
    out_off[:] = 0
    for p in range(P):
        out_off[p + 1] = out_off[p] + offsets[pair_of[p] + 1] - offsets[pair_of[p]]
    xy = np.empty((out_off[P], 2), np.float64)
    for p in range(P):
        a, u = rx[p], pair_of[p]
        c, s = cos_h[a], sin_h[a]
        q2 = out_off[p]
        for q in range(offsets[u], offsets[u + 1]):
            dx, dy = positions[idx[q], 0] - positions[a, 0], positions[idx[q], 1] - positions[a, 1]
            xy[q2, 0] = c * dx + s * dy
            xy[q2, 1] = -s * dx + c * dy
            q2 += 1
    return out_off, xy
