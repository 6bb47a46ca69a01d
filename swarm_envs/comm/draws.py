"""Every random number of a SwarmCom step, drawn before its slot loop: ADC and intensity noise, CSMA access
delays and backoffs (:class:`StepDraws`), for all env copies in one compiled call, copy b from its own
generator (:func:`draw_copies`). The compiled drawer gives bit for bit what NumPy's ``Generator`` methods give
(:func:`_draw_copies_py` makes the same draws with NumPy calls), so copy b of a batch draws exactly what a single
env draws, whatever the robots do."""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
from numba.typed import List as _typed_list

from swarm_envs._compile._numba import njit

__all__ = ["StepDraws", "GeneratorList", "draw_step", "draw_copies"]


class StepDraws(NamedTuple):
    """All random numbers of one control step of S slots for N robots (module docstring).

    Attributes:
        noise: (S, N, n_det) float32, ADC noise n_m of every detector sample (counts), or shape (0, 0, 0)
            when the ADC has no noise (n_m = 0).
        intensity_noise: (S, N, n_det) float64 intensity noise n_j, or shape (0, 0, 0) when sigma = 0.
        backoff: (N, S) int64 in [0, W): the draw a robot uses if it defers (``1 + draw``) or arms a fresh
            access delay after a frame (``draw``) in slot s (at most one of the two per robot and slot).
        access: (N,) int64 in [0, W): access delay of a robot whose queue was filled since the last step.
    """

    noise: np.ndarray
    intensity_noise: np.ndarray
    backoff: np.ndarray
    access: np.ndarray


def draw_step(rng: np.random.Generator, S: int, n: int, n_det: int, noise_sigma: float, intensity_sigma: float, window: int) -> StepDraws:
    """Draw the random numbers of one step in a fixed order and with shapes fixed by (S, n), independent of
    the robots' activity (one env copy; :func:`draw_copies` does all copies of a batch in one call)."""
    return draw_copies(GeneratorList([rng]).sync([rng]), S, n, n_det, noise_sigma, intensity_sigma, window)


class GeneratorList:
    """The env copies' generators in the form :func:`draw_copies` takes (a ``numba.typed.List``), updated in
    place when a copy's generator is replaced (boxing a generator for numba costs ~20 us, so the list is
    kept between steps instead of being rebuilt)."""

    def __init__(self, generators: list[np.random.Generator]) -> None:
        self._py: list[np.random.Generator] = list(generators)
        if self._py:  # built by cached kernels (numba.typed.List's own methods compile in every process)
            self._list = _generator_list(self._py[0])
            for g in self._py[1:]:
                _append_generator(self._list, g)
        else:
            self._list = _typed_list(self._py)

    def sync(self, generators: list[np.random.Generator]) -> "Any":
        """The list for ``generators`` (same length as at construction; replaced entries are swapped in)."""
        if len(generators) != len(self._py):
            self.__init__(generators)
            return self._list
        for b, g in enumerate(generators):
            if self._py[b] is not g:
                self._py[b] = g
                _set_generator(self._list, b, g)
        return self._list


_jit = njit(cache=True, nogil=True)
#: for loops the compiler should vectorise: numpy's error model (no ZeroDivisionError branch in the loop)
_jit_vector = njit(cache=True, nogil=True, error_model="numpy")
#: small helpers of one kernel, inlined where numba types the caller (one compile unit less each on the first run)
_jit_inline = njit(cache=True, nogil=True, inline="always")


@_jit_inline
def _draw_buffers(B, n, S, n_det, noise_sigma, intensity_sigma):
    """The arrays :func:`draw_copies` fills for B copies of n robots: ADC noise (S, B n, n_det) float32, or
    empty when ``noise_sigma`` is 0, intensity noise (S, B n, n_det) or empty, backoff (B n, S) and access
    (B n,) int64."""
    N = B * n
    ni = S if intensity_sigma > 0 else 0
    noisy = noise_sigma > 0
    noise = np.empty((S if noisy else 0, N if noisy else 0, n_det if noisy else 0), np.float32)
    inoise = np.empty((ni, N if ni else 0, n_det if ni else 0), np.float64)
    inoise[:] = 0.0
    return noise, inoise, np.empty((N, S), np.int64), np.empty(N, np.int64)


@_jit
def _store_integers(k, backoff, access, o, n, S):
    """Copy rows ``o .. o + n``: the first n S integers of ``k`` are the backoff draws (robot-major), the last
    n the access delays."""
    for r in range(n):  # element loops: a slice assignment from an array compiles numba's shape-error text
        for s in range(S):
            backoff[o + r, s] = k[r * S + s]
        access[o + r] = k[n * S + r]


def _draw_copies_py(gens, S, n, n_det, noise_sigma, intensity_sigma, window):
    """:func:`draw_copies` with NumPy's ``Generator`` calls, run in plain Python (the reference of the
    compiled drawer) or compiled with numba's own ``Generator`` methods (the drawer on a numba without the
    internals the inlined sampler uses)."""
    noise, inoise, backoff, access = _draw_buffers(len(gens), n, S, n_det, noise_sigma, intensity_sigma)
    sg = np.float32(noise_sigma)
    for b in range(len(gens)):
        g = gens[b]
        o = b * n
        if noise_sigma > 0:
            noise[:, o : o + n, :] = g.standard_normal(size=(S, n, n_det), dtype=np.float32) * sg
        if intensity_sigma > 0:
            inoise[:, o : o + n, :] = g.normal(0.0, intensity_sigma, size=(S, n, n_det))
        _store_integers(g.integers(0, window, size=n * S + n), backoff, access, o, n, S)
    return noise, inoise, backoff, access


@njit(cache=True)
def _generator_list(g):
    """A typed list holding the generator ``g``."""
    out = _typed_list()
    out.append(g)
    return out


@njit(cache=True)
def _append_generator(gens, g):
    gens.append(g)


@njit(cache=True)
def _set_generator(gens, b, g):
    gens[b] = g


try:  # NumPy's float32 ziggurat, compiled inline (numba's bindings of the bit generator and NumPy's tables),
    # and numba's copy of NumPy's bounded-integer sampler
    from numba.np.random._constants import (
        fi_float,
        ki_float,
        wi_float,
        ziggurat_nor_inv_r_f,
        ziggurat_nor_r_f,
    )
    from numba.np.random.generator_core import next_float, next_uint32
    from numba.np.random.random_methods import buffered_bounded_lemire_uint32

    _FAST_NORMAL = True
except ImportError:  # pragma: no cover - other numba versions: numba's Generator.standard_normal (same stream)
    _FAST_NORMAL = False

if _FAST_NORMAL:
    _ZIG = (ki_float.copy(), wi_float.copy(), fi_float.copy(), np.float32(ziggurat_nor_r_f), np.float32(ziggurat_nor_inv_r_f))

    @njit(cache=True, nogil=True)
    def _normal_f(bg, ki, wi, fi, zr, zir):
        """One float32 standard normal: NumPy's ``random_standard_normal_f`` (ziggurat, 256 layers) step for
        step, drawing the same 32-bit words from the same bit generator, so the stream is NumPy's
        ``Generator.standard_normal(dtype=float32)`` bit for bit (``tests/comm/test_network_kernel.py``); inlined
        here it costs less than the library call per sample."""
        while True:
            r = next_uint32(bg)
            idx = r & 0xFF
            rabs = (r >> 9) & 0x7FFFFF
            x = np.float32(np.float32(rabs) * wi[idx])
            if (r >> 8) & 1:
                x = -x
            if rabs < ki[idx]:
                return x  # ~99 % of the samples
            if idx == 0:  # tail beyond the base layer
                while True:
                    xx = np.float32(-zir * np.log1p(-next_float(bg)))
                    yy = np.float32(-np.log1p(-next_float(bg)))
                    if np.float32(yy + yy) > np.float32(xx * xx):
                        return -np.float32(zr + xx) if (rabs >> 8) & 1 else np.float32(zr + xx)
            # wedge test as in NumPy's C code: float32 left side, double exp(-0.5 x^2) (not rounded to float32)
            elif np.float64((fi[idx - 1] - fi[idx]) * next_float(bg) + fi[idx]) < np.exp(-0.5 * np.float64(x) * np.float64(x)):
                return x

    @_jit_inline
    def _copy_noise(bg, noise, o, n, S, n_det, noise_sigma, ki, wi, fi, zr, zir):
        """Rows ``o .. o + n`` of the ADC noise (S, N, n_det): :func:`_normal_f` times ``noise_sigma``, in C
        order, as ``standard_normal(size=(S, n, n_det), dtype=float32) * noise_sigma``; nothing when 0."""
        if noise_sigma > 0:
            sg = np.float32(noise_sigma)
            for s in range(S):
                for r in range(o, o + n):
                    for d in range(n_det):
                        noise[s, r, d] = _normal_f(bg, ki, wi, fi, zr, zir) * sg

    @_jit_inline
    def _copy_integers(bg, window, backoff, access, o, n, S):
        """Rows ``o .. o + n`` of the backoff and access draws: ``integers(0, window, size=n * S + n)`` bit for
        bit (the first n S robot-major into ``backoff``, the last n into ``access``). NumPy draws an int64 range
        below 2**32 - 1 with Lemire's method on 32-bit words (``random_bounded_uint64_fill``), here numba's copy
        of it (``buffered_bounded_lemire_uint32``); a window of 1 draws nothing (all 0), as NumPy. The window is
        below 2**31 (:class:`swarm_envs.comm.protocol.CSMA`)."""
        rng = window - 1
        for r in range(n):
            for s in range(S):
                backoff[o + r, s] = np.int64(buffered_bounded_lemire_uint32(bg, rng)) if rng > 0 else 0
        for r in range(n):
            access[o + r] = np.int64(buffered_bounded_lemire_uint32(bg, rng)) if rng > 0 else 0

    @njit(cache=True, nogil=True)
    def _draw_copies_nb(gens, S, n, n_det, noise_sigma, window, ki, wi, fi, zr, zir):
        """:func:`_draw_copies_py` compiled, without intensity noise (the default): each copy's ADC noise
        (:func:`_copy_noise`) then its integers (:func:`_copy_integers`), the same numbers as NumPy's calls."""
        noise, inoise, backoff, access = _draw_buffers(len(gens), n, S, n_det, noise_sigma, 0.0)
        for b in range(len(gens)):
            bg = gens[b].bit_generator
            _copy_noise(bg, noise, b * n, n, S, n_det, noise_sigma, ki, wi, fi, zr, zir)
            _copy_integers(bg, window, backoff, access, b * n, n, S)
        return noise, inoise, backoff, access

    @njit(cache=True, nogil=True)
    def _draw_copies_intensity_nb(gens, S, n, n_det, noise_sigma, intensity_sigma, window, ki, wi, fi, zr, zir):
        """:func:`_draw_copies_nb` with intensity noise (``intensity_sigma > 0``): numba's ``Generator.normal``
        between each copy's ADC noise and integers (a kernel of its own: only this scenario compiles it)."""
        noise, inoise, backoff, access = _draw_buffers(len(gens), n, S, n_det, noise_sigma, intensity_sigma)
        for b in range(len(gens)):
            g = gens[b]
            o = b * n
            _copy_noise(g.bit_generator, noise, o, n, S, n_det, noise_sigma, ki, wi, fi, zr, zir)
            draws = g.normal(0.0, intensity_sigma, size=(S, n, n_det))
            for s in range(S):
                for r in range(n):
                    for d in range(n_det):
                        inoise[s, o + r, d] = draws[s, r, d]
            _copy_integers(g.bit_generator, window, backoff, access, o, n, S)
        return noise, inoise, backoff, access

    def _draw_copies(gens, S, n, n_det, noise_sigma, intensity_sigma, window):
        if intensity_sigma > 0:
            return _draw_copies_intensity_nb(gens, S, n, n_det, noise_sigma, intensity_sigma, window, *_ZIG)
        return _draw_copies_nb(gens, S, n, n_det, noise_sigma, window, *_ZIG)
else:
    _draw_copies = _jit(_draw_copies_py)


def draw_copies(gens: Any, S: int, n: int, n_det: int, noise_sigma: float, intensity_sigma: float, window: int) -> StepDraws:
    """Every random number of one step of S slots for ``len(gens)`` env copies of n robots, in one call.

    Copy b draws from ``gens[b]`` only (a :meth:`GeneratorList.sync` list), in a fixed order with shapes
    fixed by (S, n), independent of the robots' activity: the ADC noise n_m of every detector sample
    (float32 standard normals times ``noise_sigma``; an empty array when 0), the intensity noise n_j (only when
    ``intensity_sigma > 0``), then one ``integers(0, window, n * S + n)`` call whose first ``n * S`` values
    are the CSMA backoff draws (robot-major) and the last ``n`` the access delays. Robot rows of copy b are
    ``b * n .. b * n + n - 1``; so copy b of a batch draws exactly what a single env with ``gens[b]`` draws.
    """
    return StepDraws(*_draw_copies(gens, int(S), int(n), int(n_det), float(noise_sigma), float(intensity_sigma), int(window)))
