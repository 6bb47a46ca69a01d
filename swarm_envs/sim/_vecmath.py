"""``x ** y`` and ``e^x`` over an array in one loop that the compiler can vectorise (numba; SIMD on AVX2).

numba compiles ``math.exp`` / ``math.log`` to calls into the C library, one element at a time; a loop
with a call in it is not vectorised. The e-puck gain kernel needs ``L2 ** (k_m / 2 - 5)`` for every lit
ray (~350k per step at N = 1000), and SwarmCom's slot loop the detector response's ``exp(-(y + b) T / c)``
for every detector and bit slot (~250k per step at N = 1000), so here are ``log`` and ``exp`` written as
plain arithmetic: the algorithms and coefficients of FreeBSD's msun ``e_log.c`` and ``e_exp.c`` (Sun
Microsystems, 1993, as in musl), with the exponent and mantissa taken from the IEEE bits. Each is within
1 ulp of the exact value; ``power_into`` computes ``exp(y * log(x))`` as the library path does, so it
agrees with ``math.exp(y * math.log(x))`` to a few 1e-14 relative for the arguments it is used with (the
rounding of ``y * log(x)`` dominates both; ``tests/sim/test_vecmath.py``).

:func:`exp_array` is the same ``exp`` in numpy operations: the same IEEE operations in the same order, so
it equals :func:`exp_moderate` / :func:`exp_into` bit for bit; numpy code that must give a kernel's bits
uses it (:func:`swarm_envs.comm.channel.detector_response`).

Scope: ``x`` positive, normal and finite; ``y * log(x)`` within about +-700 (no overflow or underflow
handling). The results do not depend on an element's position in the array (the vector and scalar
remainder loops do the same IEEE operations, without contraction), so a value is the same whichever
batch it is computed in.
"""

from __future__ import annotations

import math

import numpy as np
from llvmlite import ir
from numba import types
from numba.core.extending import intrinsic

from swarm_envs._compile._numba import njit

__all__ = ["log_positive", "exp_moderate", "exp_into", "exp_array", "power_into"]

_LN2_HI = 6.93147180369123816490e-01
_LN2_LO = 1.90821492927058770002e-10
_LG1 = 6.666666666666735130e-01  # e_log.c: minimax polynomial of (log(1+f) - 2s) / s, s = f / (2 + f)
_LG2 = 3.999999999940941908e-01
_LG3 = 2.857142874366239149e-01
_LG4 = 2.222219843214978396e-01
_LG5 = 1.818357216161805012e-01
_LG6 = 1.531383769920937332e-01
_LG7 = 1.479819860511658591e-01
_INV_LN2 = 1.44269504088896338700e00
_P1 = 1.66666666666666019037e-01  # e_exp.c: Remez polynomial of r (exp(r) + 1) / (exp(r) - 1)
_P2 = -2.77777777770155933842e-03
_P3 = 6.61375632143793436117e-05
_P4 = -1.65339022054652515390e-06
_P5 = 4.13813679705723846039e-08
_ROUND = 6755399441055744.0  # 1.5 * 2**52: an integer-valued |k| < 2**51 added to it sits in the low bits
_ROUND_BITS = 0x4338000000000000  # the bits of _ROUND


def exp_array(x: np.ndarray) -> np.ndarray:
    """``e^x`` element-wise for |x| < ~700 in numpy: :func:`exp_moderate`'s operations, bit for bit."""
    x = np.asarray(x, dtype=np.float64)
    flat = np.ascontiguousarray(x).reshape(-1)
    kf = np.floor(_INV_LN2 * flat + 0.5)
    hi = flat - kf * _LN2_HI
    lo = kf * _LN2_LO
    r = hi - lo
    rr = r * r
    c = r - rr * (_P1 + rr * (_P2 + rr * (_P3 + rr * (_P4 + rr * _P5))))
    y = 1.0 + (r * c / (2.0 - c) - lo + hi)
    k = (kf + _ROUND).view(np.int64) - _ROUND_BITS  # int(kf), exactly
    return (y * ((k + 1023) << 52).view(np.float64)).reshape(x.shape)


@intrinsic
def _bits(typingctx, x):  # float64 -> its IEEE bits as int64
    if x != types.float64:
        return None

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.IntType(64))

    return types.int64(types.float64), codegen


@intrinsic
def _from_bits(typingctx, n):  # int64 IEEE bits -> float64
    if n != types.int64:
        return None

    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], ir.DoubleType())

    return types.float64(types.int64), codegen


@njit(cache=True, error_model="numpy")
def log_positive(x: float) -> float:
    """Natural log of a positive, normal, finite ``x`` (``e_log.c``: ``x = 2^k (1 + f)``, ``1 + f`` in
    [sqrt(2)/2, sqrt(2)), ``log(1 + f) = f - f^2/2 + s (f^2/2 + R(s^2))``)."""
    bits = _bits(x)
    hx = (bits >> 32) + (0x3FF00000 - 0x3FE6A09E)
    k = (hx >> 20) - 0x3FF
    hx = (hx & 0x000FFFFF) + 0x3FE6A09E
    f = _from_bits((hx << 32) | (bits & 0xFFFFFFFF)) - 1.0
    hfsq = 0.5 * f * f
    s = f / (2.0 + f)
    z = s * s
    w = z * z
    t1 = w * (_LG2 + w * (_LG4 + w * _LG6))
    t2 = z * (_LG1 + w * (_LG3 + w * (_LG5 + w * _LG7)))
    dk = _from_bits(_ROUND_BITS + k) - _ROUND  # float(k), exactly
    return s * (hfsq + (t2 + t1)) + dk * _LN2_LO - hfsq + f + dk * _LN2_HI


@njit(cache=True, error_model="numpy")
def exp_moderate(x: float) -> float:
    """``e^x`` for |x| < ~700 (``e_exp.c``: ``x = k ln2 + r``, |r| <= ln2 / 2, ``e^r = 1 + r + r c / (2 - c)``,
    times ``2^k`` set in the exponent bits)."""
    kf = math.floor(_INV_LN2 * x + 0.5)
    hi = x - kf * _LN2_HI
    lo = kf * _LN2_LO
    r = hi - lo
    rr = r * r
    c = r - rr * (_P1 + rr * (_P2 + rr * (_P3 + rr * (_P4 + rr * _P5))))
    y = 1.0 + (r * c / (2.0 - c) - lo + hi)
    k = _bits(kf + _ROUND) - _ROUND_BITS  # int(kf), exactly
    return y * _from_bits((k + 1023) << 52)


@njit(cache=True, error_model="numpy")
def power_into(x: np.ndarray, y: float, out: np.ndarray) -> None:
    """``out[k] = exp(y * log(x[k]))`` (module docstring for the domain) in one vectorisable loop."""
    for k in range(x.shape[0]):
        out[k] = exp_moderate(y * log_positive(x[k]))


@njit(cache=True, error_model="numpy")
def exp_into(x: np.ndarray, out: np.ndarray) -> None:
    """``out[k] = exp_moderate(x[k])`` (|x| < ~700) in one vectorisable loop."""
    for k in range(x.shape[0]):
        out[k] = exp_moderate(x[k])
