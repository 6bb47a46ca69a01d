"""``np.argsort`` of a float array as numba compiles it, written out as one compiled function.

numba implements ``np.argsort(a)`` (``kind="quicksort"``) with seven generic helper functions
(``numba/misc/quicksort.py``), which take about 1.5 s to compile in every cold cache. :func:`argsort_quick`
is the same algorithm step for step (median-of-three partition, insertion sort below 15 elements, an
explicit stack that holds the larger part; NaN sorts last), in one function: the same permutation for
every input, ties and NaNs included (``tests/compile/test_first_run.py`` compares it with ``np.argsort`` compiled
by numba). Algorithm from numba (BSD-2-Clause, Copyright (c) 2012, Anaconda, Inc.).
"""

from __future__ import annotations

import numpy as np

from swarm_envs._compile._numba import njit

__all__ = ["argsort_quick"]

_SMALL = 15  # below this many elements: insertion sort (numba's SMALL_QUICKSORT)
_MAX_STACK = 100  # numba's MAX_STACK


@njit(cache=True)
def _lt(a: float, b: float) -> bool:
    """numba's ``lt_floats``: ``a < b`` with NaN after everything."""
    return a < b or (np.isnan(b) and not np.isnan(a))


@njit(cache=True)
def argsort_quick(A: np.ndarray) -> np.ndarray:
    """The indices that sort the 1-D float array ``A`` ascending (NaN last): ``np.argsort(A)`` as numba
    compiles it, the same permutation (module docstring)."""
    n = A.shape[0]
    R = np.arange(n)
    if n < 2:
        return R
    stack_lo = np.empty(_MAX_STACK, np.int64)
    stack_lo[:] = 0
    stack_hi = np.empty(_MAX_STACK, np.int64)
    stack_hi[:] = 0
    stack_hi[0] = n - 1
    top = 1
    while top > 0:
        top -= 1
        low, high = stack_lo[top], stack_hi[top]
        while high - low >= _SMALL:
            assert top < _MAX_STACK
            # partition A[R[low:high + 1]] around the median of {low, mid, high}
            mid = (low + high) >> 1
            if _lt(A[R[mid]], A[R[low]]):
                R[low], R[mid] = R[mid], R[low]
            if _lt(A[R[high]], A[R[mid]]):
                R[high], R[mid] = R[mid], R[high]
            if _lt(A[R[mid]], A[R[low]]):
                R[low], R[mid] = R[mid], R[low]
            pivot = A[R[mid]]
            R[high], R[mid] = R[mid], R[high]
            i = low
            j = high - 1
            while True:
                while i < high and _lt(A[R[i]], pivot):
                    i += 1
                while j >= low and _lt(pivot, A[R[j]]):
                    j -= 1
                if i >= j:
                    break
                R[i], R[j] = R[j], R[i]
                i += 1
                j -= 1
            R[i], R[high] = R[high], R[i]
            # push the larger part, continue with the smaller
            if high - i > i - low:
                if high > i:
                    stack_lo[top], stack_hi[top] = i + 1, high
                    top += 1
                high = i - 1
            else:
                if i > low:
                    stack_lo[top], stack_hi[top] = low, i - 1
                    top += 1
                low = i + 1
        # insertion sort of R[low:high + 1]
        for i in range(low + 1, high + 1):
            k = R[i]
            v = A[k]
            j = i
            while j > low and _lt(v, A[R[j - 1]]):
                R[j] = R[j - 1]
                j -= 1
            R[j] = k
    return R
