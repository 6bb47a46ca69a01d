"""Compiled (numba) gain kernels, the IR layer's hot path: every lit emitter-detector ray of every candidate
pair, with its line of sight.

The IR layer's per-step work is a loop over P visible pairs x n_detectors x n_emitters that numpy can
only do through many (P, n_d, n_e) temporaries (memory-bound). These kernels do the same arithmetic
pair by pair, skipping dark emitter-detector combinations early, and test each lit ray against the pair's
candidate occluders (per-ray line of sight, docs/design.md#infrared-physical-layer). They implement exactly the models of
:mod:`swarm_envs.ir.models` (the numpy methods there stay the reference, and the layer's path for a model
without a kernel; ``tests/ir/test_ir_kernels.py`` checks the two agree to 1e-12). The pair and occluder kernels
are in :mod:`swarm_envs.ir.pair_kernels` and :mod:`swarm_envs.ir.occluder_kernels`; their plain numpy references
in :mod:`swarm_envs._compile.reference`.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from swarm_envs._compile._numba import njit  # numba.njit whose cache recovers from corrupted files
from swarm_envs.sim._vecmath import power_into
from swarm_envs._compile._worker import run_chunks
from swarm_envs.ir.ray_kernels import DISC_TOL, hits_disc

__all__ = ["MODEL_IDS", "model_params", "GainInputs", "gains_kernel", "gains_kernel_threaded", "ChunkRows"]

#: model class name -> kernel model id
MODEL_IDS = {"DropletIR": 0, "EpuckIR": 1, "RoneIR": 2, "DropletLowPowerIR": 3}


def model_params(model: object) -> tuple[int, np.ndarray]:
    """(kernel id, float parameters) of an IR model instance; raises KeyError for unknown models."""
    kind = MODEL_IDS[type(model).__name__]
    if kind in (0, 3):
        p = [model.sensor_switch, model.emitter_switch, model.amp_coeff, model.amp_offset_cm, model.r_near_cm, model._a_near, 0.0, 0.0]
        if kind == 3:
            p[6], p[7] = model.low_coeff, model.low_offset
    elif kind == 1:
        p = [model.k_m, model.o_m, model.d_sat_cm]
    else:
        s_arc, e_arc = model.sensor_half_arc + model._eps, model.emitter_half_arc + model._eps
        p = [s_arc, e_arc, model.max_range, math.cos(s_arc), math.cos(e_arc)]
    return kind, np.asarray(p, dtype=np.float64)


@njit(cache=True, inline="always", error_model="numpy")
def _droplet_sensor(a: float, switch: float) -> float:  # [F14 Eq. (19)]
    a4 = a * a * a * a
    return 1.0 - a4 if a < switch else 1.0 / (8.0 * a4)


@njit(cache=True, inline="always", error_model="numpy")
def _droplet_emitter(b: float, switch: float) -> float:  # [F14 Eq. (20)]
    b2 = b * b
    return -b2 * b2 + 0.5 * b2 + 0.9375 if b < switch else 1.0 / (4.0 * b2 * b2)


@njit(cache=True, inline="always", error_model="numpy")
def _gain(kind: int, p0: float, p1: float, p2: float, p3: float, p4: float, p5: float, p6: float, p7: float, d_m: float, cd: float, ce: float) -> float:
    # the e-puck (kind 1) has its own ray arithmetic, in _gains_chunk
    if kind == 2:  # r-one binary arcs [L Sec. 3.2]; p3, p4 = cos of the half arcs
        if d_m <= p2 and cd >= p3 and ce >= p4:
            return 1.0
        return 0.0
    # Droplet [F14 Eqs. (19)-(21)], full power (0) or the firmware's low power (3)
    a = math.acos(min(1.0, max(-1.0, cd)))
    b = math.acos(min(1.0, max(-1.0, ce)))
    r = 100.0 * d_m
    if kind == 3:
        amp = p6 / max(r, 1e-9) ** 2 + p7
    elif r >= p4:
        amp = p2 / max(r - p3, 1e-9) ** 2 - 1.0
    else:
        amp = p5 * (p4 / max(r, 1e-9)) ** 2 - 1.0
    amp = max(amp, 0.0)
    return _droplet_sensor(a, p0) * _droplet_emitter(b, p1) * amp


_SIGN_TOL = 1e-12  # m: cosine numerators farther than this from 0 have the sign of the reference's cosines


@njit(cache=True, error_model="numpy", nogil=True)
def _finish_far_rays(
    out: np.ndarray, sums: np.ndarray, row0: int, row1: int, far_at: np.ndarray, far_L2: np.ndarray, n_far: int, expo: float, power: np.ndarray
) -> None:
    """The e-puck rows ``row0:row1`` of ``out`` (P, n_d, n_e), whose far rays (flat positions in ``out``
    ``far_at[:n_far]``, squared lengths ``far_L2``) hold their factor only (:func:`_gains_chunk`): multiplied
    by ``L2^expo`` (:func:`swarm_envs.sim._vecmath.power_into`, one vectorised pass), then each detector's
    sum over emitters into ``sums`` rows, sequentially in emitter order from 0.0 (dark rays add 0.0,
    which changes no sum: the sums of the lit rays in that order, as documented)."""
    power_into(far_L2[:n_far], expo, power[:n_far])
    flat = out.reshape(-1)
    for k in range(n_far):
        flat[far_at[k]] = flat[far_at[k]] * power[k]
    nd, ne = out.shape[1], out.shape[2]
    for row in range(row0, row1):
        for i in range(nd):
            acc = 0.0
            for j in range(ne):
                acc += out[row, i, j]
            sums[row, i] = acc


def _hardware_args(hardware: tuple | None, nd: int, ne: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The kernels' per-robot channel tables: ``hardware`` = (rx (P,), tx (P,), detector table (M, n_d, 3),
    emitter table (M, n_e, 3)) as :meth:`swarm_envs.ir.hardware.Hardware.tables` gives them, or None
    (nominal channels: empty index arrays)."""
    if hardware is None:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty, np.zeros((1, nd, 3)), np.zeros((1, ne, 3))
    rx, tx, det, em = hardware
    return (np.ascontiguousarray(rx, dtype=np.int64), np.ascontiguousarray(tx, dtype=np.int64),
            np.ascontiguousarray(det, dtype=np.float64), np.ascontiguousarray(em, dtype=np.float64))


class GainInputs(NamedTuple):
    """What the gain kernels read for P candidate pairs (the arguments of :func:`_gains_chunk` after its
    output buffers, in order): the transmitters in the receivers' frames, the platform's detectors and
    emitters, its IR model and the pairs' candidate occluders."""

    rel_position: np.ndarray  #: (P, 2) transmitter centre in the receiver's frame (m)
    rel_cos_sin: np.ndarray  #: (P, 2) cos and sin of the transmitter's heading in the receiver's frame
    det_pos: np.ndarray  #: (n_d, 2) detector positions in the body frame (m)
    det_dir: np.ndarray  #: (n_d, 2) detector axes (unit vectors)
    em_pos: np.ndarray  #: (n_e, 2) emitter positions (m)
    em_dir: np.ndarray  #: (n_e, 2) emitter axes
    kind: int  #: the IR model's id (:data:`MODEL_IDS`)
    params: np.ndarray  #: the model's parameters (:func:`model_params`)
    ir_range: float  #: largest distance with light (m)
    occ_offsets: np.ndarray  #: (P + 1,) CSR offsets of each pair's candidate occluders
    occ_xy: np.ndarray  #: (K, 2) occluder centres in the receiver's frame (m)
    occ_radius: float  #: occluding disc radius (m)


def gains_kernel(
    inputs: GainInputs,
    compact: bool = False,
    hardware: tuple | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Gains of P pairs; same geometry as ``pair_cosines`` (docs/design.md#infrared-physical-layer), same models. ``rel_position`` (P, 2):
    transmitter centre in the receiver frame (m); ``rel_cos_sin`` (P, 2): cos and sin of the transmitter's
    heading in the receiver frame.

    Returns ``(gains, lit, sums)``: ``lit`` the indices of the pairs with a nonzero gain, ``gains`` the
    (P, n_d, n_e) gains of every pair, or with ``compact`` only the rows of the ``lit`` pairs, and
    ``sums`` (rows of ``gains``, n_d) each detector's gains summed over the emitters sequentially in
    emitter order from 0.0 (bit for bit ``acc = 0.0; for j: acc += gains[p, i, j]``; adding a dark
    ray's 0.0 changes no sum, so only lit rays are added, in that order).

    Per-ray line of sight (docs/design.md#infrared-physical-layer): the gain of ray (i, j), from emitter j of the transmitter to detector
    i of the receiver, is zero when that segment crosses an occluding disc (radius ``occ_radius``) of pair
    p: centres ``occ_xy[occ_offsets[p]:occ_offsets[p + 1]]`` in the receiver's frame; a blocked ray skips
    the model, pairs without candidate occluders cost nothing extra.

    Dark rays are skipped without computing them where the model needs the emitter in front of the
    detector and the detector in front of the emitter (e-puck; r-one arcs narrower than pi): with
    ``dx`` the ray from detector i (position d_i, axis u_i) to emitter j (e_j, axis a_j, both in the
    receiver frame) and R the transmitter centre, ``dx . u_i <= R . u_i + max_j |e_j| - d_i . u_i``
    and ``dx . a_j >= R . a_j + e_j . a_j - max_i |d_i|``; a detector whose bound is below -1e-9 m
    (or an emitter whose bound is above 1e-9 m) has only rays with cos <= 0, which the model leaves
    dark. The margin is far above rounding (~1e-16 m), so exactly the same rays are lit as without
    the bound.

    Hardware variation (docs/design.md#hardware-variation): with ``hardware`` = (rx, tx, detector table,
    emitter table), pair p's receiver is robot ``rx[p]`` and its transmitter ``tx[p]`` of the tables
    ((M, n_d, 3) and (M, n_e, 3): gain multiplier, cos and sin of the channel's axis angle); the axes of
    pair p's detectors and emitters are those robots' (offset) axes and ray (i, j) is multiplied by
    ``detector gain[rx[p], i] * emitter gain[tx[p], j]``. None: the nominal axes, no multiplier.
    """
    rel_position, det_pos, em_pos = inputs.rel_position, inputs.det_pos, inputs.em_pos
    P, nd, ne = rel_position.shape[0], det_pos.shape[0], em_pos.shape[0]
    out = np.empty((P, nd, ne), np.float64)  # each row is zeroed just before it is filled (one pass over memory)
    sums = np.empty((P, nd), np.float64)
    lit = np.empty(P, np.int64)
    n_lit = _gains_chunk(
        0, P, out, sums, lit, *inputs, bool(compact), *_hardware_args(hardware, nd, ne),
    )
    if compact:
        return out[:n_lit], lit[:n_lit].copy(), sums[:n_lit]
    return out, lit[:n_lit].copy(), sums


def gains_kernel_threaded(
    inputs: GainInputs,
    n_chunks: int,
    deferred: bool = False,
    hardware: tuple | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray] | tuple[np.ndarray, np.ndarray, np.ndarray, ChunkRows]:
    """:func:`gains_kernel` with ``compact=True`` on ``n_chunks`` threads (this one and the helper threads
    of :func:`swarm_envs._compile._worker.run_chunks`): the pairs are cut into contiguous chunks, each filled (and
    compacted within its own rows) by one thread, then the chunks' lit rows are moved together in order
    (:func:`_gather_chunk_rows`, :func:`_gather_gain_rows`). Every row is computed by the same code as
    the serial kernel, so the result is the same bit for bit, whatever the number of chunks or threads.

    ``deferred=True``: ``lit`` and ``sums`` are gathered before returning, the gain rows are not; returns
    ``(gains, lit, sums, rows)`` with ``rows`` a :class:`ChunkRows`, and ``gains`` holds its values once
    ``rows.gather()`` has run (for a caller whose work reads only ``lit``, ``sums`` and some rows).
    ``hardware``: as in :func:`gains_kernel`."""
    P, nd, ne = inputs.rel_position.shape[0], inputs.det_pos.shape[0], inputs.em_pos.shape[0]
    hw = _hardware_args(hardware, nd, ne)
    out = np.empty((P, nd, ne))
    sums = np.empty((P, nd))
    lit = np.empty(P, dtype=np.int64)
    n_chunks = max(1, min(int(n_chunks), P))
    bounds = [(P * k) // n_chunks for k in range(n_chunks + 1)]

    def chunk(k: int) -> int:
        return _gains_chunk(
            bounds[k], bounds[k + 1], out, sums, lit, *inputs, True, *hw,
        )

    counts = np.asarray(run_chunks(chunk, n_chunks), dtype=np.int64)
    starts = np.asarray(bounds[:-1], dtype=np.int64)
    n_lit = _gather_chunk_rows(sums, lit, starts, counts)
    if deferred:
        return out[:n_lit], lit[:n_lit].copy(), sums[:n_lit], ChunkRows(out, starts, counts)
    _gather_gain_rows(out, starts, counts)
    return out[:n_lit], lit[:n_lit].copy(), sums[:n_lit]


class ChunkRows:
    """The lit gain rows of :func:`gains_kernel_threaded` as its chunks left them: chunk k's rows are
    ``out[starts[k]:starts[k] + counts[k]]``, lit rows ``sum(counts[:k])`` on. :meth:`take` reads rows by
    lit index without moving any; :meth:`gather` moves them together in place, once (after it, ``take``
    reads the gathered rows). Not thread-safe: no ``take`` may run while ``gather`` does."""

    def __init__(self, out: np.ndarray, starts: np.ndarray, counts: np.ndarray) -> None:
        self._out, self._starts, self._counts = out, starts, counts
        self._first = np.cumsum(counts) - counts  # lit index of each chunk's first row
        self.n_rows = int(counts.sum())
        self._gathered = False

    def take(self, idx: np.ndarray) -> np.ndarray:
        """Copies of the rows of lit indices ``idx`` (S,): (S, n_d, n_e), as ``gathered[idx]``."""
        idx = np.asarray(idx, dtype=np.int64)
        if self._gathered:
            return self._out[idx]
        chunk = np.searchsorted(self._first, idx, side="right") - 1
        return self._out[idx - self._first[chunk] + self._starts[chunk]]

    def gather(self) -> np.ndarray:
        """The rows moved together (``out[:n_rows]``, the kernel's ``gains``), moving them on the first call."""
        if not self._gathered:
            _gather_gain_rows(self._out, self._starts, self._counts)
            self._gathered = True
        return self._out[: self.n_rows]


@njit(cache=True, error_model="numpy", nogil=True)
def _gather_chunk_rows(sums: np.ndarray, lit: np.ndarray, starts: np.ndarray, counts: np.ndarray) -> int:
    """The ``counts[k]`` rows of ``sums`` and ``lit`` at each chunk's start ``starts[k]`` moved together to
    the front, in chunk order; returns their number."""
    n = counts[0]
    for k in range(1, counts.shape[0]):  # rows only move towards the front: a forward copy is safe
        for q in range(counts[k]):
            src = starts[k] + q
            for i in range(sums.shape[1]):
                sums[n, i] = sums[src, i]
            lit[n] = lit[src]
            n += 1
    return n


@njit(cache=True, error_model="numpy", nogil=True)
def _gather_gain_rows(out: np.ndarray, starts: np.ndarray, counts: np.ndarray) -> None:
    """:func:`_gather_chunk_rows` for the gain rows ``out`` (P, n_d, n_e), element by element (no row views:
    numba counts a reference per view)."""
    n = counts[0]
    for k in range(1, counts.shape[0]):
        for q in range(counts[k]):
            src = starts[k] + q
            for i in range(out.shape[1]):
                for j in range(out.shape[2]):
                    out[n, i, j] = out[src, i, j]
            n += 1


@njit(cache=True, error_model="numpy", nogil=True)
def _gains_chunk(
    start: int,
    stop: int,
    out: np.ndarray,
    sums: np.ndarray,
    lit: np.ndarray,
    rel_position: np.ndarray,
    rel_cos_sin: np.ndarray,
    det_pos: np.ndarray,
    det_dir: np.ndarray,
    em_pos: np.ndarray,
    em_dir: np.ndarray,
    kind: int,
    params: np.ndarray,
    ir_range: float,
    occ_offsets: np.ndarray,
    occ_xy: np.ndarray,
    occ_radius: float,
    compact: bool,
    hw_rx: np.ndarray,
    hw_tx: np.ndarray,
    hw_det: np.ndarray,
    hw_em: np.ndarray,
) -> int:
    """Gain rows of pairs ``start:stop`` (:func:`gains_kernel`) into ``out``/``sums`` rows from ``start``
    on: row ``p`` each, or with ``compact`` the lit pairs' rows one after the other, their pair indices
    into ``lit`` from ``start`` on. Returns the number of lit pairs.

    The per-pair and per-ray work is written out in this one loop, arrays indexed and never sliced or
    passed to a helper inside it: in numba each array view or array argument costs an atomic reference
    count, and the threads of :func:`gains_kernel_threaded` share ``out`` and the inputs (measured: ~40
    reference counts per pair took a tenth of the kernel's time). Helpers inside take scalars only.

    **e-puck rays** [T20 Eqs. (7),(24),(25),(27)]: the same values as :func:`_gain` without a square
    root or division per ray. With ``dx`` the ray (detector -> emitter), ``nd = dx . u_i = |dx|
    cos(detector angle)`` and ``ne = -dx . a_j = |dx| cos(emitter angle)``, ``ce^7 cd^3 h_m = ne^7 nd^3 /
    L2^5 h_m`` and, beyond d_sat, ``h_m = o_m (100 |dx|)^k_m = o_m 100^k_m L2^(k_m / 2)``. A ray is dark
    when nd or ne <= 0; when one of them is within 1e-12 m of 0 (where rounding could flip the sign)
    the reference's cosines decide and give the gain, so exactly the same rays are lit. A ray beyond
    d_sat gets only its factor ``ne^7 nd^3 o_m 100^k_m`` in the loop; its flat position in ``out`` and
    ``L2`` are queued in ``far_at``/``far_L2``, and :func:`_finish_far_rays` multiplies by
    ``L2^(k_m / 2 - 5)`` for many rays at once, every ~64 pairs while the rows are still in cache. That
    factor is > 1e-124 (nd, ne >= 1e-12 m) and the power >= 0.4 (L2 < 1.2 m^2), so the ray is lit
    exactly when the factor is > 0. Droplet and r-one rays: :func:`_gain`, summed as they come.

    **Occlusion** (docs/design.md#infrared-physical-layer): a ray is blocked when :func:`hits_disc` finds an occluder's disc on it.

    **Hardware variation** (``hw_rx`` non-empty; :func:`gains_kernel`): each pair loads its receiver's
    detector axes and its transmitter's emitter axes (and the front-only bounds' constants) from the
    tables, and multiplies each ray's gain by the two channels' multipliers."""
    nd, ne = det_pos.shape[0], em_pos.shape[0]
    r2 = occ_radius * occ_radius
    r2_hi, r2_lo = r2 * (1.0 + DISC_TOL), r2 * (1.0 - DISC_TOL)
    prm = np.empty(8, np.float64)
    prm[:] = 0.0
    for i in range(params.shape[0]):  # element copy (a slice assignment from an array compiles numba's shape-error text)
        prm[i] = params[i]
    k_m, o_m, d_sat_cm = prm[0], prm[1], prm[2]  # e-puck
    d_sat2 = (d_sat_cm / 100.0) ** 2
    scale = o_m * 100.0**k_m
    # axes and the per-element constants of the front-only bounds (gains_kernel docstring); with hardware
    # variation each pair overwrites them with its two robots' axes
    varied = hw_rx.shape[0] > 0
    dcos, dsin = np.cos(det_dir), np.sin(det_dir)
    ecos, esin = np.cos(em_dir), np.sin(em_dir)
    det_self = np.empty(nd, np.float64)  # d_i . u_i
    rho_d = 0.0
    for i in range(nd):
        det_self[i] = det_pos[i, 0] * dcos[i] + det_pos[i, 1] * dsin[i]
        rho_d = max(rho_d, math.sqrt(det_pos[i, 0] ** 2 + det_pos[i, 1] ** 2))
    em_self = np.empty(ne, np.float64)  # e_j . (emitter axis), body frame
    rho_e = 0.0
    for j in range(ne):
        em_self[j] = em_pos[j, 0] * ecos[j] + em_pos[j, 1] * esin[j]
        rho_e = max(rho_e, math.sqrt(em_pos[j, 0] ** 2 + em_pos[j, 1] ** 2))
    gd, ge = np.empty(nd, np.float64), np.empty(ne, np.float64)  # the pair's channel multipliers
    gd[:] = 1.0
    ge[:] = 1.0
    last_rx = -1  # the receiver whose detectors are loaded (pairs come sorted by receiver)
    margin = 1e-9
    prune_det = kind == 1 or (kind == 2 and prm[3] > 0.0)
    prune_em = kind == 1 or (kind == 2 and prm[4] > 0.0)
    ex, ey, eax, eay = np.empty(ne, np.float64), np.empty(ne, np.float64), np.empty(ne, np.float64), np.empty(ne, np.float64)  # a pair's emitters, RX frame
    dets = np.empty(nd, np.int64)
    ems = np.empty(ne, np.int64)
    far_cap = 64 * nd * ne  # e-puck far rays waiting for their power
    far_at = np.empty(far_cap, np.int64)
    far_L2 = np.empty(far_cap, np.float64)
    power = np.empty(far_cap, np.float64)
    expo = 0.5 * k_m - 5.0
    n_far = 0
    done = start  # rows before this one are finished
    n_lit = 0
    for p in range(start, stop):
        row = start + n_lit if compact else p
        for i in range(nd):
            for j in range(ne):
                out[row, i, j] = 0.0
            sums[row, i] = 0.0
        Rx, Ry = rel_position[p, 0], rel_position[p, 1]  # transmitter centre and heading, RX frame
        c, s = rel_cos_sin[p, 0], rel_cos_sin[p, 1]
        q0, q1 = occ_offsets[p], occ_offsets[p + 1]  # candidate occluders occ_xy[q0:q1]
        any_lit = False
        n_new = n_far  # far rays queued by this pair start here (dropped if it stays dark)
        if math.sqrt(Rx * Rx + Ry * Ry) <= ir_range:
            if varied:
                u_rx, u_tx = hw_rx[p], hw_tx[p]
                if u_rx != last_rx:
                    for i in range(nd):
                        gd[i], dcos[i], dsin[i] = hw_det[u_rx, i, 0], hw_det[u_rx, i, 1], hw_det[u_rx, i, 2]
                        det_self[i] = det_pos[i, 0] * dcos[i] + det_pos[i, 1] * dsin[i]
                    last_rx = u_rx
                for j in range(ne):
                    ge[j], ecos[j], esin[j] = hw_em[u_tx, j, 0], hw_em[u_tx, j, 1], hw_em[u_tx, j, 2]
                    em_self[j] = em_pos[j, 0] * ecos[j] + em_pos[j, 1] * esin[j]
            n_em = 0
            for j in range(ne):  # TX emitters and their axes in the RX frame
                ex[j] = Rx + c * em_pos[j, 0] - s * em_pos[j, 1]
                ey[j] = Ry + s * em_pos[j, 0] + c * em_pos[j, 1]
                eax[j] = c * ecos[j] - s * esin[j]
                eay[j] = s * ecos[j] + c * esin[j]
                ems[n_em] = j  # branch-free compaction (the bound's outcome is unpredictable): kept if it may light
                n_em += np.int64((not prune_em) | (Rx * eax[j] + Ry * eay[j] + em_self[j] - rho_d <= margin))
            n_det = 0
            for i in range(nd):
                dets[n_det] = i
                n_det += np.int64((not prune_det) | (Rx * dcos[i] + Ry * dsin[i] + rho_e - det_self[i] >= -margin))
            for a in range(n_det):
                i = dets[a]
                x0, y0, dc, ds = det_pos[i, 0], det_pos[i, 1], dcos[i], dsin[i]
                for b in range(n_em):
                    j = ems[b]
                    dx, dy = ex[j] - x0, ey[j] - y0
                    proj_d = proj_e = d = cd = ce = 0.0
                    near_zero = False
                    if kind == 1:  # e-puck (docstring)
                        proj_d = dx * dc + dy * ds
                        if proj_d <= -_SIGN_TOL:
                            continue
                        proj_e = -(dx * eax[j] + dy * eay[j])
                        if proj_e <= -_SIGN_TOL:
                            continue
                        L2 = dx * dx + dy * dy
                        near_zero = proj_d < _SIGN_TOL or proj_e < _SIGN_TOL or L2 < 1e-12
                        if near_zero:  # the reference's cosines decide, and give the gain
                            d = math.sqrt(L2)
                            inv = 1.0 / max(d, 1e-12)
                            ux, uy = dx * inv, dy * inv
                            cd, ce = ux * dc + uy * ds, -(ux * eax[j] + uy * eay[j])
                            if cd <= 0.0 or ce <= 0.0:
                                continue
                    else:
                        L2 = dx * dx + dy * dy
                        d = math.sqrt(L2)
                        inv = 1.0 / max(d, 1e-12)
                        ux, uy = dx * inv, dy * inv
                        cd = ux * dc + uy * ds
                        ce = -(ux * eax[j] + uy * eay[j])
                        # rays the model leaves dark (r-one: outside the arcs or range; the same zero branch
                        # as _gain) need no occlusion test
                        if kind == 2 and not (d <= prm[2] and cd >= prm[3] and ce >= prm[4]):
                            continue
                    blocked = False
                    for q in range(q0, q1):
                        if hits_disc(x0, y0, ex[j], ey[j], dx, dy, L2, occ_xy[q, 0], occ_xy[q, 1], r2, r2_hi, r2_lo):
                            blocked = True
                            break
                    if blocked:
                        continue
                    if kind != 1:
                        g = _gain(kind, prm[0], prm[1], prm[2], prm[3], prm[4], prm[5], prm[6], prm[7], d, cd, ce)
                        if varied:
                            g = g * (gd[i] * ge[j])
                        sums[row, i] += g  # rays in (detector, emitter) order: emitter order per detector
                    elif near_zero:
                        d_cm = 100.0 * d
                        hm = 1.0 if d_cm <= d_sat_cm else o_m * math.exp(k_m * math.log(max(d_cm, 1e-12)))
                        ce2 = ce * ce
                        g = ce2 * ce2 * ce2 * ce * cd * cd * cd * hm
                    else:
                        ne2 = proj_e * proj_e
                        num = ne2 * ne2 * ne2 * proj_e * proj_d * proj_d * proj_d
                        if L2 <= d_sat2:  # h_m = 1
                            L4 = L2 * L2
                            g = num / (L4 * L4 * L2)
                        else:  # the power later (docstring)
                            g = num * scale
                            far_at[n_new] = (row * nd + i) * ne + j
                            far_L2[n_new] = L2
                            n_new += 1
                    if kind == 1 and varied:
                        g = g * (gd[i] * ge[j])
                    out[row, i, j] = g
                    if g > 0.0:
                        any_lit = True
        if any_lit:  # (a far ray makes its pair lit: an unlit pair queued none)
            n_far = n_new
            lit[start + n_lit] = p
            n_lit += 1
        if kind == 1 and n_far > far_cap - nd * ne:
            end = start + n_lit if compact else p + 1
            _finish_far_rays(out, sums, done, end, far_at, far_L2, n_far, expo, power)
            done, n_far = end, 0
    if kind == 1:
        _finish_far_rays(out, sums, done, start + n_lit if compact else stop, far_at, far_L2, n_far, expo, power)
    return n_lit


