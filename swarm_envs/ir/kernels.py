"""Compiled (numba) kernels for the IR layer's hot path.

The IR layer's per-step work is a loop over P visible pairs x n_detectors x n_emitters that numpy can
only do through many (P, n_d, n_e) temporaries (memory-bound). These kernels do the same arithmetic
pair by pair, skipping dark emitter-detector combinations early, and test each lit ray against the pair's
candidate occluders (per-ray line of sight, docs/design.md#infrared-physical-layer). They implement exactly the models of
:mod:`swarm_envs.ir.models` (the numpy methods there stay the reference, and the layer's path for a model
without a kernel; ``tests/test_ir_kernels.py`` checks the two agree to 1e-12). The plain numpy references
of the pair, occluder and frame kernels are in :mod:`swarm_envs._compile.reference`.
"""

from __future__ import annotations

import math

import numpy as np

from swarm_envs._compile._numba import njit  # numba.njit whose cache recovers from corrupted files
from swarm_envs.sim._vecmath import power_into
from swarm_envs._compile._worker import run_chunks

__all__ = ["MODEL_IDS", "model_params", "gains_kernel", "gains_kernel_threaded", "ChunkRows", "occluders_kernel", "occluders_kernel_threaded", "neighbour_csr_kernel", "occluder_frames_kernel", "directed_pairs_kernel", "select_links_kernel"]

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


@njit(cache=True, inline="always", error_model="numpy")
def _segment_hits_disc(x0: float, y0: float, x1: float, y1: float, cx: float, cy: float, r2: float) -> bool:
    """Whether the segment (x0, y0)-(x1, y1) passes closer than sqrt(r2) to (cx, cy) (open disc)."""
    sx, sy = x1 - x0, y1 - y0
    px, py = cx - x0, cy - y0
    L2 = sx * sx + sy * sy
    t = (px * sx + py * sy) / L2 if L2 > 0.0 else 0.0
    t = min(1.0, max(0.0, t))
    qx, qy = px - t * sx, py - t * sy
    return qx * qx + qy * qy < r2


_SIGN_TOL = 1e-12  # m: cosine numerators farther than this from 0 have the sign of the reference's cosines
_DISC_TOL = 1e-6  # relative: a ray's line this far outside / inside the disc radius gets the reference's verdict


@njit(cache=True, inline="always", error_model="numpy")
def _hits_disc(
    x0: float, y0: float, x1: float, y1: float, dx: float, dy: float, L2: float, cx: float, cy: float, r2: float, r2_hi: float, r2_lo: float
) -> bool:
    """:func:`_segment_hits_disc` for a segment with ``dx = x1 - x0``, ``dy = y1 - y0``, ``L2 = dx * dx + dy * dy``
    computed so by the caller, and ``r2_hi, r2_lo = r2 (1 +- _DISC_TOL)``: the same verdict, without the
    division except within a relative 1e-6 of the radius (there it decides). When the nearest point is an
    end (t clamped to 0 or 1) the arithmetic is the same; otherwise the squared distance of the centre
    from the segment's line is ``cr^2 / L2`` (cr the cross product), compared with r2 with a margin far
    above rounding (~1e-14 relative)."""
    px, py = cx - x0, cy - y0
    dot = px * dx + py * dy
    if dot <= 0.0:  # t clamps to 0: nearest point is the start
        return px * px + py * py < r2
    if dot >= L2:  # t clamps to 1: nearest point is the end
        qx, qy = px - dx, py - dy
        return qx * qx + qy * qy < r2
    cr = px * dy - py * dx
    cr2 = cr * cr
    if cr2 >= r2_hi * L2:
        return False
    return cr2 <= r2_lo * L2 or _segment_hits_disc(x0, y0, x1, y1, cx, cy, r2)


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


def gains_kernel(
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
    return _gains_serial(
        rel_position, rel_cos_sin, det_pos, det_dir, em_pos, em_dir, kind, params, ir_range, occ_offsets, occ_xy,
        occ_radius, compact, *_hardware_args(hardware, det_pos.shape[0], em_pos.shape[0]),
    )


@njit(cache=True, error_model="numpy", nogil=True)
def _gains_serial(
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
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`gains_kernel` with its channel tables (:func:`_hardware_args`), compiled."""
    P, nd, ne = rel_position.shape[0], det_pos.shape[0], em_pos.shape[0]
    out = np.empty((P, nd, ne), np.float64)  # each row is zeroed just before it is filled (one pass over memory)
    sums = np.empty((P, nd), np.float64)
    lit = np.empty(P, np.int64)
    n_lit = _gains_chunk(
        0, P, out, sums, lit, rel_position, rel_cos_sin, det_pos, det_dir, em_pos, em_dir, kind, params,
        ir_range, occ_offsets, occ_xy, occ_radius, compact, hw_rx, hw_tx, hw_det, hw_em,
    )
    if compact:
        return out[:n_lit], lit[:n_lit].copy(), sums[:n_lit]
    return out, lit[:n_lit].copy(), sums


def gains_kernel_threaded(
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
    P, nd, ne = rel_position.shape[0], det_pos.shape[0], em_pos.shape[0]
    hw = _hardware_args(hardware, nd, ne)
    out = np.empty((P, nd, ne))
    sums = np.empty((P, nd))
    lit = np.empty(P, dtype=np.int64)
    n_chunks = max(1, min(int(n_chunks), P))
    bounds = [(P * k) // n_chunks for k in range(n_chunks + 1)]

    def chunk(k: int) -> int:
        return _gains_chunk(
            bounds[k], bounds[k + 1], out, sums, lit, rel_position, rel_cos_sin, det_pos, det_dir, em_pos,
            em_dir, kind, params, ir_range, occ_offsets, occ_xy, occ_radius, True, *hw,
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

    **Occlusion** (docs/design.md#infrared-physical-layer): a ray is blocked when :func:`_hits_disc` finds an occluder's disc on it.

    **Hardware variation** (``hw_rx`` non-empty; :func:`gains_kernel`): each pair loads its receiver's
    detector axes and its transmitter's emitter axes (and the front-only bounds' constants) from the
    tables, and multiplies each ray's gain by the two channels' multipliers."""
    nd, ne = det_pos.shape[0], em_pos.shape[0]
    r2 = occ_radius * occ_radius
    r2_hi, r2_lo = r2 * (1.0 + _DISC_TOL), r2 * (1.0 - _DISC_TOL)
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
                        if _hits_disc(x0, y0, ex[j], ey[j], dx, dy, L2, occ_xy[q, 0], occ_xy[q, 1], r2, r2_hi, r2_lo):
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

    The disc test is :func:`_hits_disc`'s (the verdict of :func:`_segment_hits_disc`: nearest end, or the
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
    w2_hi, w2_lo = w2 * (1.0 + _DISC_TOL), w2 * (1.0 - _DISC_TOL)
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
        # the segment as _segment_hits_disc(ax, ay, ax + sx, ay + sy, ...) computes it
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
                # the verdict of _hits_disc (== _segment_hits_disc) without a branch on its outcome
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
            if _segment_hits_disc(ax, ay, x1, y1, positions[k, 0], positions[k, 1], w2):
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
