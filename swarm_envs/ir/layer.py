"""Shared infrared physical layer (docs/design.md#infrared-physical-layer): candidate pairs, line of sight, emitter-detector geometry, gains.

Computed once per env step, vectorised over all pairs (no Python loop over robot pairs):

1. candidate pairs: centres closer than the IR range, from ``scipy.spatial.cKDTree.query_pairs``;
2. line of sight, per ray: light from emitter j of w reaches detector i of u only if the
   segment from the emitter point to the detector point crosses no *third* robot's disc (radius
   ``platform.radius``) [T20 Fig. 3: "due to occlusion, not all emitter-detector pairs are relevant"].
   Blocked rays get zero gain, so a partially occluded pair gets partial light and a pair whose every
   ray is blocked is no link. Candidate occluders of a pair are the robots whose centre lies within
   ``platform.radius + rho`` of the centre segment (rho = the largest emitter / detector offset from a
   robot's centre: every ray lies within rho of the centre segment), taken from the KD-tree neighbour
   lists of the pair's two ends (:func:`swarm_envs.ir.occlusion.pair_occluders`); the rays are tested inside the compiled gain
   kernel. ``occlusion="centre"`` gives the centre-line rule (one centre-to-centre segment per pair)
   for comparison;
3. for each ordered pair (receiver u, transmitter w), every detector i of u and emitter j of w:
   ``r_ij = R + Rot(psi) e_j - d_i`` (vector from detector i to emitter j in u's body frame, R = w's
   centre in u's frame, psi = w's heading in u's frame, e_j / d_i the emitter / detector positions in
   their own body frames). This is [F14 Eq. (1)] ``r_ij = R - rho b_i + rho b_j`` generalised to
   arbitrary positions (the e-puck's offset emitters/detectors, [T20 Eqs. (3)-(5),(8)-(14)]).
   Detector incidence angle ``angle(r_ij) - delta_i`` and emission angle
   ``angle(-r_ij) - (psi + epsilon_j)`` [F14 Eqs. (2),(3),(11),(12)], delta / epsilon the axis angles;
4. gain = ``platform.ir_model.gain(|r_ij|, detector_angle, emitter_angle)`` (:mod:`swarm_envs.ir.models`);
5. optional, after the gains (:func:`swarm_envs.ir.blocking.block_links`, a numpy pass that leaves the compiled kernels alone):
   static obstacle segments block light per ray as robots do (a ray from emitter j to detector i that
   crosses a segment carries no light), and switched-off robots (``silent``) neither emit nor detect,
   though their bodies still occlude. A link left without light is dropped. Without obstacles or silent
   robots the links are returned untouched.

All public inputs/outputs are SI (metres, radians, angles wrapped to (-pi, pi]).
"""

from __future__ import annotations

import threading
import numpy as np
from scipy.spatial import cKDTree

from swarm_envs.sim.geometry import wrap_angle
from swarm_envs.ir import gain_kernels, pair_kernels
from swarm_envs.ir.hardware import Hardware
from swarm_envs.sim.platforms import Platform, get_platform
from swarm_envs.ir.links import IRLinks, emitter_sums, clear_rays_numpy
from swarm_envs.ir.blocking import block_links
from swarm_envs.ir.occlusion import occluder_frames, occluder_lists, line_of_sight, occluder_width

__all__ = ["compute_links", "compute_links_with_rows", "pair_geometry", "pair_cosines", "pair_gains", "gain_threads", "THREADED_MIN_PAIRS"]

OCCLUSION_RULES = ("ray", "centre", "none")

#: candidate directed pairs of one scene from which its gain kernel uses threads (:func:`gain_threads`)
THREADED_MIN_PAIRS = 16384


def pair_geometry(
    rel_position: np.ndarray, rel_heading: np.ndarray, platform: Platform | str
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Emitter-detector geometry for P (receiver, transmitter) pairs [F14 Eqs. (1)-(3),(11),(12)].

    Args:
        rel_position: (P, 2) transmitter centre in the receiver's body frame (m).
        rel_heading: (P,) transmitter heading in the receiver's frame (rad).
        platform: both robots' platform.

    Returns:
        distance (P, n_d, n_e) detector-emitter distance (m); detector_angle (P, n_d, n_e) incidence
        angle at detector i of the direction to emitter j; emitter_angle (P, n_d, n_e) angle between
        emitter j's axis and the direction to detector i (rad, wrapped).
    """
    platform = get_platform(platform)
    R = np.asarray(rel_position, dtype=float).reshape(-1, 2)
    psi = np.asarray(rel_heading, dtype=float).reshape(-1)
    c, s = np.cos(psi)[:, None], np.sin(psi)[:, None]
    ex, ey = platform.emitter_positions[:, 0][None, :], platform.emitter_positions[:, 1][None, :]
    # emitter positions in the receiver frame: (P, n_e)
    emx = R[:, 0:1] + c * ex - s * ey
    emy = R[:, 1:2] + s * ex + c * ey
    dx = emx[:, None, :] - platform.detector_positions[None, :, 0, None]
    dy = emy[:, None, :] - platform.detector_positions[None, :, 1, None]
    distance = np.hypot(dx, dy)
    ang = np.arctan2(dy, dx)  # direction detector -> emitter, receiver frame
    detector_angle = wrap_angle(ang - platform.detector_directions[None, :, None])
    emitter_axis = psi[:, None, None] + platform.emitter_directions[None, None, :]
    emitter_angle = wrap_angle(ang + np.pi - emitter_axis)
    return distance, detector_angle, emitter_angle


def pair_cosines(
    rel_position: np.ndarray, rel_heading: np.ndarray, platform: Platform | str, hardware: Hardware | None = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The same geometry as :func:`pair_geometry` as (distance, cos detector angle, cos emitter angle).

    Every IR model is symmetric in its angles ([F14 Eqs. (19),(20)], [T20 Eqs. (24),(27)]), so gains need only the cosines, which come from
    dot products with the unit detector-emitter vectors: no arctan2 and no angle wrapping on the
    (P, n_d, n_e) hot path. ``hardware`` (P rows, :meth:`Hardware.pairs`): the axes of pair p's detectors
    and emitters are offset by its rows' angles (docs/design.md#hardware-variation).
    """
    platform = get_platform(platform)
    R = np.asarray(rel_position, dtype=float).reshape(-1, 2)
    psi = np.asarray(rel_heading, dtype=float).reshape(-1)
    c, s = np.cos(psi)[:, None], np.sin(psi)[:, None]
    ex, ey = platform.emitter_positions[:, 0][None, :], platform.emitter_positions[:, 1][None, :]
    emx = R[:, 0:1] + c * ex - s * ey  # emitter positions in the receiver frame (P, n_e)
    emy = R[:, 1:2] + s * ex + c * ey
    e_dir = platform.emitter_directions[None, :] + (0.0 if hardware is None else hardware.emitter_offset)
    d_dir = platform.detector_directions[None, :] + (0.0 if hardware is None else hardware.detector_offset)
    eca, esa = np.cos(e_dir), np.sin(e_dir)
    eax = (c * eca - s * esa)[:, None, :]  # emitter axes in the receiver frame (P, 1, n_e)
    eay = (s * eca + c * esa)[:, None, :]
    dx = emx[:, None, :] - platform.detector_positions[None, :, 0, None]
    dy = emy[:, None, :] - platform.detector_positions[None, :, 1, None]
    distance = np.hypot(dx, dy)
    inv = 1.0 / np.maximum(distance, 1e-12)
    ux, uy = dx * inv, dy * inv  # unit vector detector -> emitter
    dax = np.cos(d_dir)[:, :, None]
    day = np.sin(d_dir)[:, :, None]
    cos_detector = ux * dax + uy * day
    cos_emitter = -(ux * eax + uy * eay)
    return distance, cos_detector, cos_emitter


def pair_gains(
    rel_position: np.ndarray,
    rel_heading: np.ndarray,
    platform: Platform | str,
    model: object | None = None,
    occluders: tuple[np.ndarray, np.ndarray] | None = None,
    hardware: Hardware | None = None,
) -> np.ndarray:
    """Noiseless gains (P, n_detectors, n_emitters) of the platform's IR model for P pairs.

    Equal to ``model.gain(*pair_geometry(...))``: a compiled kernel (:mod:`swarm_envs.ir.gain_kernels`) for the
    package's IR models (:data:`swarm_envs.ir.gain_kernels.MODEL_IDS`), numpy from cosines for any other model
    (:func:`pair_cosines`, ``model.gain_from_cos``). Pairs whose
    centre distance exceeds ``platform.ir_range`` get zero gain (the platform's "no infrared beyond"
    cut-off). ``model`` overrides the platform's IR model (e.g. the Droplet's low-power emitters,
    :class:`swarm_envs.ir.models.DropletLowPowerIR`).

    Args:
        occluders: optional ``(offsets (P + 1,), centres (K, 2))``: the discs (radius ``platform.radius``)
            that may block pair p's rays, centres in the receiver's body frame (m), rows
            ``offsets[p]:offsets[p + 1]`` (from :func:`pair_occluders`). A ray, the segment from emitter j
            of the transmitter to detector i of the receiver, that crosses one of them gets zero gain
            (per-ray line of sight, docs/design.md#infrared-physical-layer). Default: no occluders (line of sight assumed).
        hardware: optional per-pair channel deviations (P rows: pair p's receiver detectors and transmitter
            emitters, :meth:`Hardware.pairs`; docs/design.md#hardware-variation). Default: the nominal platform.
    """
    platform = get_platform(platform)
    model = platform.ir_model if model is None else model
    R = np.ascontiguousarray(rel_position, dtype=float).reshape(-1, 2)
    psi = np.ascontiguousarray(rel_heading, dtype=float).reshape(-1)
    if occluders is None:
        offsets, xy = np.zeros(R.shape[0] + 1, dtype=np.int64), np.zeros((0, 2))
    else:
        offsets = np.ascontiguousarray(occluders[0], dtype=np.int64).reshape(-1)
        xy = np.ascontiguousarray(occluders[1], dtype=float).reshape(-1, 2)
        if offsets.shape[0] != R.shape[0] + 1 or offsets[0] != 0 or offsets[-1] != xy.shape[0] or np.any(np.diff(offsets) < 0):
            raise ValueError(f"occluders: offsets must be non-decreasing, length P + 1 = {R.shape[0] + 1}, from 0 to len(centres)")
    hw = None
    if hardware is not None:
        if len(hardware) != R.shape[0]:
            raise ValueError(f"hardware must have one row per pair ({R.shape[0]}), got {len(hardware)}")
        rows = np.arange(R.shape[0])
        hw = (rows, rows, hardware)
    return _gains(R, psi, platform, model, offsets, xy, compact=False, hardware=hw)[0]


def _gains(
    R: np.ndarray,
    psi: np.ndarray,
    platform: Platform,
    model: object,
    offsets: np.ndarray,
    xy: np.ndarray,
    compact: bool,
    cos_sin: np.ndarray | None = None,
    threads: int = 1,
    deferred: bool = False,
    hardware: tuple[np.ndarray, np.ndarray, Hardware] | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, gain_kernels.ChunkRows | None]:
    """(gains, lit, sums) of :func:`pair_gains` with checked inputs: ``lit`` the pairs with a nonzero gain,
    ``gains`` every pair's rows, or with ``compact`` only the ``lit`` rows (compiled kernel; numpy for a model
    without one), and
    ``sums`` (rows, n_d) the gains summed over emitters sequentially in emitter order (:class:`IRLinks`
    ``emitter_sums``). ``cos_sin`` (P, 2): cos and sin of ``psi`` if known (the kernel uses them; default
    from ``psi``). ``threads`` > 1 (with ``compact``): the compiled kernel splits the pairs over that many
    threads (:func:`gain_threads`; same result bit for bit). ``deferred`` (with threads): the gain rows are
    not gathered; the fourth result is then their :class:`gain_kernels.ChunkRows` (else None), and ``gains``
    holds its values once its ``gather()`` has run (:func:`gain_kernels.gains_kernel_threaded`). ``hardware``:
    optional (rx (P,), tx (P,), :class:`Hardware` of the robots they index): per-robot channel deviations
    (docs/design.md#hardware-variation)."""
    if type(model).__name__ in gain_kernels.MODEL_IDS:
        hw = None if hardware is None else (hardware[0], hardware[1], *hardware[2].tables(platform))
        kind, params = gain_kernels.model_params(model)
        if cos_sin is None:
            cos_sin = np.stack([np.cos(psi), np.sin(psi)], axis=-1)
        args = gain_kernels.GainInputs(
            R, cos_sin, platform.detector_positions, platform.detector_directions,
            platform.emitter_positions, platform.emitter_directions, kind, params, float(platform.ir_range),
            offsets, xy, float(platform.radius),
        )
        if compact and threads > 1:
            if deferred:
                return gain_kernels.gains_kernel_threaded(args, int(threads), True, hw)
            return (*gain_kernels.gains_kernel_threaded(args, int(threads), False, hw), None)
        return (*gain_kernels.gains_kernel(args, compact, hw), None)
    g = _pair_gains_numpy(R, psi, platform, model, None if hardware is None else hardware[2].pairs(hardware[0], hardware[1]))
    if xy.shape[0]:
        g = g * clear_rays_numpy(R, psi, platform, offsets, xy)
    lit = np.flatnonzero(g.reshape(g.shape[0], -1).max(axis=1, initial=0.0) > 0)
    g = g[lit] if compact else g
    return g, lit, emitter_sums(g), None


def _pair_gains_numpy(R: np.ndarray, psi: np.ndarray, platform: Platform, model: object, hardware: Hardware | None = None) -> np.ndarray:
    """The numpy reference of :func:`pair_gains` without occluders (the path of a model without a kernel, and
    what the kernel is tested against); ``hardware``: per-pair channel deviations (:meth:`Hardware.pairs`)."""
    distance, cos_det, cos_em = pair_cosines(R, psi, platform, hardware)
    g = np.asarray(model.gain_from_cos(distance, cos_det, cos_em), dtype=float)
    if hardware is not None:
        g = g * (hardware.detector_gain[:, :, None] * hardware.emitter_gain[:, None, :])
    return g * (np.hypot(R[:, 0], R[:, 1]) <= platform.ir_range)[:, None, None]


def compute_links(
    positions: np.ndarray,
    headings: np.ndarray,
    platform: Platform | str,
    max_range: float | None = None,
    drop_zero: bool = True,
    occlusion: str = "ray",
    copy: np.ndarray | None = None,
    obstacles: np.ndarray | None = None,
    silent: np.ndarray | None = None,
    hardware: Hardware | None = None,
    emit_off: np.ndarray | None = None,
    detect_off: np.ndarray | None = None,
) -> IRLinks:
    """All directed IR links of a scene (docs/design.md#infrared-physical-layer), vectorised.

    Args:
        positions: (N, 2) robot centres, world frame (m).
        headings: (N,) robot headings, world frame (rad).
        platform: platform of all robots.
        max_range: candidate cut-off on centre distance (m); default ``platform.ir_range``.
        drop_zero: drop pairs whose gain matrix is all zero (e.g. beyond the range, every ray occluded, or
            r-one pairs outside the receivers' arcs or behind the transmitters). Default True.
        occlusion: ``"ray"`` (docs/design.md#infrared-physical-layer, default): each emitter-detector ray is blocked by a third robot's disc
            it crosses; ``"centre"``: the centre-line rule, a pair is blocked entirely when its centre
            segment crosses a third robot's disc, else all its rays are clear; ``"none"``: no occlusion
            (comparison / ablation only).
        copy: (N,) env copy of each robot (batched engine): no pair and no occluder crosses copies (the
            KD-tree gets a third coordinate that puts copies out of each other's range; 0 within a copy, so
            every distance and link equals that of the copy alone).
        obstacles: (S, 2, 2) static obstacle segments, world frame (m), the same in every copy: they block
            light per ray (:func:`block_links`). None or empty: no obstacles.
        silent: (N,) bool switched-off robots: no light from or to them (their bodies still occlude).
        hardware: (N rows) each robot's channel deviations (docs/design.md#hardware-variation): the links'
            gains (and emitter sums) are those of the robots' own channels. None: the nominal platform.
        emit_off: (N,) bool robots whose emitters are off (receive-only): no link from them.
        detect_off: (N,) bool robots whose detectors are off (transmit-only): no link to them.

    Returns:
        :class:`IRLinks` with both directions (u, w) and (w, u) of every candidate pair, sorted by (rx, tx).
    """
    return compute_links_with_rows(
        positions, headings, platform, max_range, drop_zero, occlusion, copy, obstacles=obstacles, silent=silent, hardware=hardware,
        emit_off=emit_off, detect_off=detect_off,
    )[0]


def compute_links_with_rows(
    positions: np.ndarray,
    headings: np.ndarray,
    platform: Platform | str,
    max_range: float | None = None,
    drop_zero: bool = True,
    occlusion: str = "ray",
    copy: np.ndarray | None = None,
    deferred: bool = False,
    obstacles: np.ndarray | None = None,
    silent: np.ndarray | None = None,
    hardware: Hardware | None = None,
    emit_off: np.ndarray | None = None,
    detect_off: np.ndarray | None = None,
) -> tuple[IRLinks, gain_kernels.ChunkRows | None]:
    """:func:`compute_links`, and with ``deferred`` (for :class:`swarm_envs.sensing.full.FullSensing`), when
    the scene uses threads (:func:`gain_threads`; else None), the gain rows as the kernel's chunks left them
    (:class:`gain_kernels.ChunkRows`): everything else in the links is final, and ``links.gains`` holds its
    values only after ``rows.gather()``; until then read rows with ``rows.take(link indices)``."""
    if occlusion not in OCCLUSION_RULES:
        raise ValueError(f"occlusion must be one of {OCCLUSION_RULES}, got {occlusion!r}")
    platform = get_platform(platform)
    positions = np.asarray(positions, dtype=float).reshape(-1, 2)
    headings = np.asarray(headings, dtype=float).reshape(-1)
    N = positions.shape[0]
    r = platform.ir_range if max_range is None else float(max_range)
    n_d, n_e = platform.n_detectors, platform.n_emitters
    if N < 2:
        return _empty_links(n_d, n_e, N), None
    points = positions
    if copy is not None:
        lift = np.asarray(copy, dtype=float).reshape(-1, 1) * (4.0 * r + 4.0 * platform.radius + 1.0)
        points = np.concatenate([positions, lift], axis=1)
    tree = cKDTree(points)
    pairs = tree.query_pairs(r, output_type="ndarray")
    if pairs.shape[0] == 0:
        return _empty_links(n_d, n_e, N), None
    if occlusion == "centre":
        pairs = pairs[line_of_sight(positions, platform.radius, pairs[:, 0], pairs[:, 1], tree)]
    rx, tx, pair_of, rel, rel_cs, rel_heading, distance = _directed_pairs(pairs, positions, headings)
    longest = float(distance.max())
    if emit_off is not None or detect_off is not None:  # no gains for the links from / to switched-off sides
        dead = np.zeros(rx.shape[0], dtype=bool)
        if emit_off is not None:
            dead |= np.asarray(emit_off, dtype=bool)[tx]
        if detect_off is not None:
            dead |= np.asarray(detect_off, dtype=bool)[rx]
        if dead.all():
            return _empty_links(n_d, n_e, N), None
        if dead.any():
            live = ~dead
            rx, tx, pair_of, rel, rel_cs, rel_heading, distance = (v[live] for v in (rx, tx, pair_of, rel, rel_cs, rel_heading, distance))
    threads = gain_threads(rx.shape[0])
    occluders = None
    if occlusion == "ray":
        # occluders once per unordered pair (every candidate pair: a pair's occluders are found among its
        # neighbours'), then in each receiver's frame
        a, b = (np.ascontiguousarray(pairs[:, k], dtype=np.int64) for k in (0, 1))
        offsets, idx = occluder_lists(positions, a, b, occluder_width(platform), tree, longest, pairs, r, threads)
        occluders = occluder_frames(positions, headings, rx, pair_of, offsets, idx)
    if occluders is None:
        offsets, xy = np.zeros(rx.shape[0] + 1, dtype=np.int64), np.zeros((0, 2))
    else:
        offsets, xy = occluders
    if hardware is not None and len(hardware) != N:
        raise ValueError(f"hardware must have one row per robot ({N}), got {len(hardware)}")
    hw = None if hardware is None else (rx, tx, hardware)
    gains, lit, sums, rows_pending = _gains(rel, rel_heading, platform, platform.ir_model, offsets, xy, drop_zero, rel_cs, threads, deferred, hw)
    rows = np.arange(rx.shape[0])
    if drop_zero and lit.shape[0] < rx.shape[0]:
        rows = lit
        rx, tx, rel, rel_heading, distance = pair_kernels.select_links_kernel(lit, rx, tx, rel, rel_heading, distance)
    links = IRLinks(rx, tx, distance, rel, rel_heading, gains, N, None if occluders is None else (*occluders, rows), sums)
    switched = any(m is not None and np.any(m) for m in (silent, emit_off, detect_off))
    if (obstacles is not None and len(obstacles)) or switched:
        if rows_pending is not None:  # the post-pass reads and writes the gain rows
            rows_pending.gather()
            rows_pending = None
        links = block_links(links, positions, headings, platform, obstacles, silent, drop_zero, emit_off=emit_off, detect_off=detect_off)
    return links, rows_pending


def gain_threads(n_pairs: int) -> int:
    """Threads for the gain kernel and occluder search of one scene of ``n_pairs`` candidate directed pairs: numba's thread
    count (``NUMBA_NUM_THREADS``, default all cores; ``numba.set_num_threads``) from
    :data:`THREADED_MIN_PAIRS` pairs on (about 370 e-puck robots at the flocking default density), else 1.
    The chunks run on the calling thread and the helper threads of :func:`swarm_envs._compile._worker.run_chunks`
    (the library's own, which wait on a lock when idle, so they take no core from the physics or the
    worker thread; numba's own parallel threads spin for milliseconds after each parallel region).

    A scene is one env or a batch of copies (their pairs counted together). Threads are used only from the
    main Python thread (one large scene per process uses the helpers; envs stepped from other threads
    stay on their thread). The result is the same bit for bit either way."""
    if n_pairs < THREADED_MIN_PAIRS or threading.current_thread() is not threading.main_thread():
        return 1
    import numba

    return int(numba.get_num_threads())


def _directed_pairs(
    pairs: np.ndarray, positions: np.ndarray, headings: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Both directions of the unordered ``pairs`` (U, 2) sorted by (rx, tx): (rx, tx, row of ``pairs``, tx
    centre in rx's frame (P, 2) (m), (cos, sin) of tx's heading in rx's frame (P, 2) from the robots' own
    cosines and sines, that heading (P,) (rad, wrapped), centre distance (P,) (m)); compiled (plain numpy
    reference: :func:`swarm_envs._compile.reference.ir_directed_pairs`)."""
    c, s = np.cos(headings), np.sin(headings)  # per robot, then per pair
    pairs = np.ascontiguousarray(pairs, dtype=np.int64)
    return pair_kernels.directed_pairs_kernel(pairs, np.ascontiguousarray(positions), np.ascontiguousarray(headings), c, s)


def _empty_links(n_d: int, n_e: int, n_robots: int) -> IRLinks:
    return IRLinks(
        np.zeros(0, np.intp),
        np.zeros(0, np.intp),
        np.zeros(0),
        np.zeros((0, 2)),
        np.zeros(0),
        np.zeros((0, n_d, n_e)),
        n_robots,
        emitter_sums=np.zeros((0, n_d)),
    )
