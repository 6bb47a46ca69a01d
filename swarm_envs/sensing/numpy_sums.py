"""numpy's floating-point sums in compiled code, bit for bit: numpy's pairwise summation of a row
(:func:`pairwise_block`), ``np.add.reduceat`` over row segments (:func:`segment_sum`) and the sum over the last axis
(:func:`sum_last`). The sensing kernels use them wherever numpy's order of additions must be kept."""

from __future__ import annotations
import numpy as np
from swarm_envs._compile._numba import njit  # numba.njit whose cache recovers from corrupted files

__all__ = ["segment_sum", "PAIRWISE_INIT", "sum_last", "pairwise_block"]


def segment_sum(a: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """``np.add.reduceat(a, starts, axis=0)`` bit for bit, compiled for float64 rows and valid ``starts``
    (reduceat loops over segments slowly when most segments hold one or two rows); otherwise reduceat itself.

    numpy reduces each segment ``s:e`` column by column as ``a[s] + pairwise_sum(a[s+1:e])``, with its
    pairwise summation (sequential from -0.0 (numpy >= 2) below 8 terms, 8 interleaved partial sums up to 128, halving
    above); the kernel repeats exactly that order, so float results are identical, not just close.
    """
    a = np.asarray(a)
    starts = np.asarray(starts, dtype=np.int64)
    if a.dtype != np.float64 or starts.size == 0 or starts.min() < 0 or starts.max() >= a.shape[0]:
        return np.add.reduceat(a, starts, axis=0)
    flat = np.ascontiguousarray(a).reshape(a.shape[0], -1)
    return _segment_sum(flat, starts, PAIRWISE_INIT).reshape((starts.size, *a.shape[1:]))

#: the start value of numpy's short pairwise sums: -0.0 under numpy >= 2 (the additive identity: a sum of
#: -0.0 stays -0.0), 0.0 before; asked of the installed numpy. Kernels that repeat numpy's summation take it
#: as an argument, not a global (numba's cache would freeze it).
PAIRWISE_INIT = -0.0 if np.signbit(np.add.reduceat(np.full((3, 1), -0.0), [0], axis=0)[0, 0]) else 0.0


@njit(cache=True, nogil=True)
def _pairwise_sum(a, lo, n, c, init):  # pragma: no cover - compiled
    """numpy's ``DOUBLE_pairwise_sum`` of ``a[lo:lo+n, c]`` (numpy/_core/src/umath/loops_utils.h.src)."""
    if n < 8:
        res = init
        for i in range(n):
            res += a[lo + i, c]
        return res
    if n <= 128:
        r0, r1, r2, r3 = a[lo, c], a[lo + 1, c], a[lo + 2, c], a[lo + 3, c]
        r4, r5, r6, r7 = a[lo + 4, c], a[lo + 5, c], a[lo + 6, c], a[lo + 7, c]
        m = n - n % 8
        i = 8
        while i < m:
            r0 += a[lo + i, c]
            r1 += a[lo + i + 1, c]
            r2 += a[lo + i + 2, c]
            r3 += a[lo + i + 3, c]
            r4 += a[lo + i + 4, c]
            r5 += a[lo + i + 5, c]
            r6 += a[lo + i + 6, c]
            r7 += a[lo + i + 7, c]
            i += 8
        res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
        while i < n:
            res += a[lo + i, c]
            i += 1
        return res
    n2 = n // 2
    n2 -= n2 % 8
    return _pairwise_sum(a, lo, n2, c, init) + _pairwise_sum(a, lo + n2, n - n2, c, init)


@njit(cache=True, nogil=True)
def _segment_sum(a, starts, init):  # pragma: no cover - compiled
    G = starts.size
    L, m = a.shape
    out = np.empty((G, m), np.float64)
    for g in range(G):
        s = starts[g]
        e = starts[g + 1] if g + 1 < G else L
        if e <= s + 1:  # one row (reduceat also returns a[s] when the next start is not larger)
            for c in range(m):
                out[g, c] = a[s, c]
        elif e - s - 1 < 8:  # short segment: _pairwise_sum's sequential branch, inline (it is recursive,
            for c in range(m):  # so numba calls it as a function: slow for the typical 2-3 rows)
                res = init
                for i in range(s + 1, e):
                    res += a[i, c]
                out[g, c] = a[s, c] + res
        else:
            for c in range(m):
                out[g, c] = a[s, c] + _pairwise_sum(a, s + 1, e - s - 1, c, init)
    return out


def sum_last(a: np.ndarray) -> np.ndarray:
    """Sum over the last axis, added left to right (``((a0 + a1) + a2) + ...``), compiled (reference:
    :func:`swarm_envs._compile.reference.sum_last`, numpy column additions in the same order, the same bits).
    (``a.sum(-1)`` reduces a short last axis slowly: ~4x slower for the (L, 8, 8) gain matrices.)"""
    a = np.asarray(a, dtype=float)
    if a.shape[-1] == 0:
        return np.zeros(a.shape[:-1])
    flat = np.ascontiguousarray(a.reshape(-1, a.shape[-1]))  # one compiled layout (a single row can come as a column view)
    return _sum_last(flat).reshape(a.shape[:-1])


@njit(cache=True, nogil=True)
def _sum_last(a):  # pragma: no cover - compiled
    m, k = a.shape
    out = np.empty(m, np.float64)
    for i in range(m):
        r = a[i, 0]
        for j in range(1, k):
            r += a[i, j]
        out[i] = r
    return out


@njit(cache=True, nogil=True)
def pairwise_block(a, n):  # pragma: no cover - compiled
    """numpy's pairwise sum of ``a[:n]`` for 8 <= n <= 128 (the unrolled, non-recursive branch)."""
    r0, r1, r2, r3 = a[0], a[1], a[2], a[3]
    r4, r5, r6, r7 = a[4], a[5], a[6], a[7]
    m = n - n % 8
    i = 8
    while i < m:
        r0 += a[i]
        r1 += a[i + 1]
        r2 += a[i + 2]
        r3 += a[i + 3]
        r4 += a[i + 4]
        r5 += a[i + 5]
        r6 += a[i + 6]
        r7 += a[i + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += a[i]
        i += 1
    return res
