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
   lists of the pair's two ends (:func:`pair_occluders`); the rays are tested inside the compiled gain
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
5. optional, after the gains (:func:`block_links`, a numpy pass that leaves the compiled kernels alone):
   static obstacle segments block light per ray as robots do (a ray from emitter j to detector i that
   crosses a segment carries no light), and switched-off robots (``silent``) neither emit nor detect,
   though their bodies still occlude. A link left without light is dropped. Without obstacles or silent
   robots the links are returned untouched.

All public inputs/outputs are SI (metres, radians, angles wrapped to (-pi, pi]).
"""

from __future__ import annotations

import threading
from dataclasses import dataclass, field
import numpy as np
from scipy.spatial import cKDTree

from swarm_envs.sim.geometry import wrap_angle
from swarm_envs.ir import gain_kernels, occluder_kernels, pair_kernels
from swarm_envs.ir.hardware import Hardware
from swarm_envs.sim.platforms import Platform, get_platform

__all__ = [
    "IRLinks", "compute_links", "compute_links_with_rows", "neighbour_csr", "pair_geometry", "pair_cosines", "pair_gains", "pair_occluders", "line_of_sight",
    "occluder_width", "gain_threads", "THREADED_MIN_PAIRS", "block_links", "rays_blocked", "no_obstacles",
]

OCCLUSION_RULES = ("ray", "centre", "none")

#: candidate directed pairs of one scene from which its gain kernel uses threads (:func:`gain_threads`)
THREADED_MIN_PAIRS = 16384


@dataclass
class IRLinks:
    """Directed IR links of one step (P pairs). Row p: transmitter ``tx[p]`` as seen by receiver ``rx[p]``.

    Attributes:
        rx: (P,) int receiving robot index.
        tx: (P,) int transmitting robot index.
        distance: (P,) centre distance (m).
        rel_position: (P, 2) tx centre in rx's body frame (m).
        rel_heading: (P,) tx heading in rx's frame (rad, wrapped to (-pi, pi]).
        gains: (P, n_detectors, n_emitters) noiseless model gain; rows = rx detectors, cols = tx emitters
            (units of the platform's IR model: ADC counts for the Droplet, intensity y for the e-puck,
            0/1 for the r-one).
        n_robots: number of robots in the scene the links were computed from.
        occluders: per-ray occluders of the pairs, ``(offsets, centres in the receiver frame, rows)``:
            pair p's discs are ``centres[offsets[rows[p]]:offsets[rows[p] + 1]]`` (None: no per-ray
            occlusion); use :meth:`ray_clear`.
        emitter_sums: (P, n_detectors) the light each detector of rx receives from all of tx's emitters
            lit at once, ``sum_j gains[p, i, j]`` (SwarmCom's all-emitters-on light "G" per detector
            [T20 Eq. (10)] before its intensity scale). Summed sequentially in emitter order from 0.0, so
            it equals ``acc = 0.0; for j in range(n_e): acc += gains[p, i, j]`` bit for bit (numpy's
            ``gains.sum(axis=-1)`` adds pairwise and may differ in the last bit). Filled by
            :func:`compute_links`; None for links built by hand.
    """

    rx: np.ndarray
    tx: np.ndarray
    distance: np.ndarray
    rel_position: np.ndarray
    rel_heading: np.ndarray
    gains: np.ndarray
    n_robots: int = 0
    occluders: tuple[np.ndarray, np.ndarray, np.ndarray] | None = field(default=None, repr=False)
    emitter_sums: np.ndarray | None = field(default=None, repr=False)
    #: (P, n_detectors, n_emitters) bool, rays not blocked by a static obstacle (:func:`block_links`), or
    #: None (no obstacle near any link); part of :meth:`ray_clear`
    obstacle_clear: np.ndarray | None = field(default=None, repr=False)

    def __len__(self) -> int:
        return int(self.rx.shape[0])

    def ray_clear(self, platform: Platform | str) -> np.ndarray:
        """(P, n_detectors, n_emitters) bool: ray (detector i, emitter j) of each link misses every third
        robot (docs/design.md#infrared-physical-layer) and every static obstacle, whether lit or not. For code that recomputes gains with
        another model (e.g. other detector arcs or emitter power) and must keep this step's occlusion:
        multiply by this mask."""
        platform = get_platform(platform)
        clear = np.ones((len(self), platform.n_detectors, platform.n_emitters), dtype=bool)
        if self.obstacle_clear is not None:
            clear &= self.obstacle_clear
        if self.occluders is None or len(self) == 0:
            return clear
        offsets, xy, rows = self.occluders
        counts = np.diff(offsets)[rows]
        if counts.sum() == 0:
            return clear
        sub = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
        start = np.repeat(offsets[rows], counts)
        within = np.arange(int(counts.sum())) - np.repeat(sub[:-1], counts)
        return clear & _clear_rays_numpy(self.rel_position, self.rel_heading, platform, sub, xy[start + within])

    @property
    def bearing(self) -> np.ndarray:
        """(P,) true bearing (rad) of tx in rx's frame (ground truth, for validation / ideal sensing)."""
        return np.arctan2(self.rel_position[:, 1], self.rel_position[:, 0])


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
        args = (
            R, cos_sin, platform.detector_positions, platform.detector_directions,
            platform.emitter_positions, platform.emitter_directions, kind, params, float(platform.ir_range),
            offsets, xy, float(platform.radius),
        )
        if compact and threads > 1:
            if deferred:
                return gain_kernels.gains_kernel_threaded(*args, int(threads), True, hw)
            return (*gain_kernels.gains_kernel_threaded(*args, int(threads), False, hw), None)
        return (*gain_kernels.gains_kernel(*args, compact, hw), None)
    g = _pair_gains_numpy(R, psi, platform, model, None if hardware is None else hardware[2].pairs(hardware[0], hardware[1]))
    if xy.shape[0]:
        g = g * _clear_rays_numpy(R, psi, platform, offsets, xy)
    lit = np.flatnonzero(g.reshape(g.shape[0], -1).max(axis=1, initial=0.0) > 0)
    g = g[lit] if compact else g
    return g, lit, _emitter_sums(g), None


def _emitter_sums(gains: np.ndarray) -> np.ndarray:
    """(P, n_d) sums of ``gains`` (P, n_d, n_e) over emitters, sequentially in emitter order from 0.0
    (:class:`IRLinks` ``emitter_sums`` of a model without a kernel; the kernel sums in the same order)."""
    acc = np.zeros(gains.shape[:2])
    for j in range(gains.shape[2]):
        acc += gains[:, :, j]
    return acc


def _pair_gains_numpy(R: np.ndarray, psi: np.ndarray, platform: Platform, model: object, hardware: Hardware | None = None) -> np.ndarray:
    """The numpy reference of :func:`pair_gains` without occluders (the path of a model without a kernel, and
    what the kernel is tested against); ``hardware``: per-pair channel deviations (:meth:`Hardware.pairs`)."""
    distance, cos_det, cos_em = pair_cosines(R, psi, platform, hardware)
    g = np.asarray(model.gain_from_cos(distance, cos_det, cos_em), dtype=float)
    if hardware is not None:
        g = g * (hardware.detector_gain[:, :, None] * hardware.emitter_gain[:, None, :])
    return g * (np.hypot(R[:, 0], R[:, 1]) <= platform.ir_range)[:, None, None]


def _clear_rays_numpy(R: np.ndarray, psi: np.ndarray, platform: Platform, offsets: np.ndarray, xy: np.ndarray) -> np.ndarray:
    """(P, n_d, n_e) True where the ray detector i - emitter j misses every occluding disc of its pair: the
    kernel's per-ray test in numpy, for :meth:`IRLinks.ray_clear` and a model without a kernel (rows are
    (pair, occluder) combinations, no Python loop)."""
    P = R.shape[0]
    counts = np.diff(offsets)
    pair = np.repeat(np.arange(P), counts)
    c, s = np.cos(psi[pair])[:, None], np.sin(psi[pair])[:, None]
    ex, ey = platform.emitter_positions[:, 0][None, :], platform.emitter_positions[:, 1][None, :]
    emx = (R[pair, 0:1] + c * ex - s * ey)[:, None, :]  # (K, 1, n_e), receiver frame
    emy = (R[pair, 1:2] + s * ex + c * ey)[:, None, :]
    dtx = platform.detector_positions[None, :, 0, None]  # (1, n_d, 1)
    dty = platform.detector_positions[None, :, 1, None]
    sx, sy = emx - dtx, emy - dty
    px, py = xy[:, 0, None, None] - dtx, xy[:, 1, None, None] - dty
    L2 = sx * sx + sy * sy
    t = np.clip(np.where(L2 > 0, (px * sx + py * sy) / np.where(L2 > 0, L2, 1.0), 0.0), 0.0, 1.0)
    qx, qy = px - t * sx, py - t * sy
    hit = (qx * qx + qy * qy < platform.radius**2).astype(np.int64)  # (K, n_d, n_e)
    clear = np.ones((P, platform.n_detectors, platform.n_emitters), dtype=bool)
    has = counts > 0
    if hit.shape[0]:
        clear[has] = np.add.reduceat(hit, offsets[:-1][has], axis=0) == 0
    return clear


def occluder_width(platform: Platform | str) -> float:
    """Distance (m) from a pair's centre segment within which a third robot's centre can block a ray:
    ``radius + rho``, rho the largest emitter / detector distance from a robot's centre (every ray lies
    within rho of the centre segment, so a disc farther than ``radius + rho`` misses all of them)."""
    platform = get_platform(platform)
    rho = max(np.hypot(*platform.emitter_positions.T).max(), np.hypot(*platform.detector_positions.T).max())
    return float(platform.radius + rho)


def neighbour_csr(positions: np.ndarray, reach: float, tree: cKDTree) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Neighbour lists within ``reach`` (m) of every robot from one KD-tree ``query_pairs``, as CSR
    (starts, counts, neighbours)."""
    near = tree.query_pairs(reach, output_type="ndarray")
    N = positions.shape[0]
    src = np.concatenate([near[:, 0], near[:, 1]])
    dst = np.concatenate([near[:, 1], near[:, 0]])
    order = np.argsort(src, kind="stable")
    counts = np.bincount(src, minlength=N)
    starts = np.cumsum(counts) - counts
    return starts.astype(np.int64), counts.astype(np.int64), dst[order].astype(np.int64)


def pair_occluders(
    positions: np.ndarray,
    headings: np.ndarray,
    rx: np.ndarray,
    tx: np.ndarray,
    width: float,
    tree: cKDTree | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Candidate occluders of P (receiver, transmitter) pairs: third robots whose centre is closer than
    ``width`` (m) to the segment between the two centres.

    Vectorised over pairs: such a robot lies within ``sqrt(|rx tx|^2 / 4 + width^2)`` of one end, so the candidates
    are the neighbours of both ends within that distance (one KD-tree ``query_pairs`` in CSR form), tested
    by a compiled kernel (plain numpy reference: :func:`swarm_envs._compile.reference.occluder_lists` and
    :func:`swarm_envs._compile.reference.occluder_frames`).

    Returns:
        offsets (P + 1,) int, robots (K,) int, centres (K, 2) in the receiver's body frame (m): pair p's
        occluders are rows ``offsets[p]:offsets[p + 1]``, sorted by robot index.
    """
    positions = np.ascontiguousarray(positions, dtype=float).reshape(-1, 2)
    headings = np.ascontiguousarray(headings, dtype=float).reshape(-1)
    rx = np.ascontiguousarray(rx, dtype=np.int64).reshape(-1)
    tx = np.ascontiguousarray(tx, dtype=np.int64).reshape(-1)
    offsets, idx = _occluder_lists(positions, rx, tx, width, tree)
    _, xy = _occluder_frames(positions, headings, rx, np.arange(rx.shape[0]), offsets, idx)
    return offsets, idx, xy


def _occluder_lists(
    positions: np.ndarray,
    a: np.ndarray,
    b: np.ndarray,
    width: float,
    tree: cKDTree | None,
    max_length: float | None = None,
    near_pairs: np.ndarray | None = None,
    near_range: float = 0.0,
    threads: int = 1,
) -> tuple[np.ndarray, np.ndarray]:
    """CSR (offsets (P + 1,), robots (K,)) of the third robots closer than ``width`` to segment a[p]-b[p].
    ``max_length``: the longest segment (m) if known (to within 1e-12 m), else computed. ``near_pairs``
    (U, 2): unordered pairs known to include every pair of robots closer than ``near_range`` (m) (e.g.
    the KD-tree's candidate pairs): the neighbour lists are taken from them instead of a second KD-tree
    query when the lists' reach is shorter (compiled path). ``threads`` > 1: the compiled search runs on that
    many threads (:func:`gain_threads`; same result bit for bit)."""
    P, N = a.shape[0], positions.shape[0]
    if P == 0 or N < 3:
        return np.zeros(P + 1, dtype=np.int64), np.zeros(0, dtype=np.int64)
    if tree is None:
        tree = cKDTree(positions)
    if max_length is None:
        seg = positions[b] - positions[a]
        max_length = float(np.hypot(seg[:, 0], seg[:, 1]).max())
    # a centre within width of a segment is within sqrt(length^2 / 4 + width^2) of the segment's nearer end
    # (foot point on that half, Pythagoras); + 2e-9 m^2 covers the kernel's own margin and rounding
    reach2 = 0.25 * float(max_length) ** 2 + float(width) ** 2 + 2e-9
    reach = float(np.sqrt(reach2))
    if near_pairs is not None and reach < near_range * (1.0 - 1e-9):  # lists from the pairs, no second query
        starts, counts, nbrs = pair_kernels.neighbour_csr_kernel(positions, np.ascontiguousarray(near_pairs, dtype=np.int64), reach2)
    else:
        starts, counts, nbrs = neighbour_csr(positions, reach, tree)
    if threads > 1:
        return occluder_kernels.occluders_kernel_threaded(positions, float(width), a, b, starts, counts, nbrs, int(threads))
    return occluder_kernels.occluders_kernel(positions, float(width), a, b, starts, counts, nbrs)


def _occluder_frames(
    positions: np.ndarray, headings: np.ndarray, rx: np.ndarray, pair_of: np.ndarray, offsets: np.ndarray, idx: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The occluders of pair ``pair_of[p]`` as centres in receiver ``rx[p]``'s frame: (offsets (P + 1,), (K, 2))."""
    rx = np.ascontiguousarray(rx, dtype=np.int64)
    pair_of = np.ascontiguousarray(pair_of, dtype=np.int64)
    return occluder_kernels.occluder_frames_kernel(positions, np.cos(headings), np.sin(headings), rx, pair_of, offsets, idx)


def line_of_sight(
    positions: np.ndarray,
    radius: float,
    i: np.ndarray,
    j: np.ndarray,
    tree: cKDTree | None = None,
) -> np.ndarray:
    """Centre-line rule (a coarser line of sight, for comparison): True where the segment
    between centres ``positions[i]`` and ``positions[j]`` crosses no third robot's disc (open disc of
    ``radius`` m around every other centre). The simulator itself decides line of sight per ray
    (:func:`compute_links`).

    Returns: (P,) bool mask.
    """
    positions = np.ascontiguousarray(positions, dtype=float).reshape(-1, 2)
    i = np.ascontiguousarray(i, dtype=np.int64).reshape(-1)
    j = np.ascontiguousarray(j, dtype=np.int64).reshape(-1)
    offsets, _ = _occluder_lists(positions, i, j, radius, tree)
    return np.diff(offsets) == 0


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
    threads = gain_threads(rx.shape[0]) if copy is None else 1
    occluders = None
    if occlusion == "ray":
        # occluders once per unordered pair (every candidate pair: a pair's occluders are found among its
        # neighbours'), then in each receiver's frame
        a, b = (np.ascontiguousarray(pairs[:, k], dtype=np.int64) for k in (0, 1))
        offsets, idx = _occluder_lists(positions, a, b, occluder_width(platform), tree, longest, pairs, r, threads)
        occluders = _occluder_frames(positions, headings, rx, pair_of, offsets, idx)
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


def no_obstacles() -> np.ndarray:
    """An empty (0, 2, 2) array of obstacle segments."""
    return np.zeros((0, 2, 2))


def _cross(ax: np.ndarray, ay: np.ndarray, bx: np.ndarray, by: np.ndarray) -> np.ndarray:
    return ax * by - ay * bx


def rays_blocked(starts: np.ndarray, ends: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """(...,) bool: the ray from ``starts`` (..., 2) to ``ends`` (..., 2) (m) crosses or touches one of
    ``segments`` (S, 2, 2) (m); a ray lying on a segment's line counts as clear. Orientation tests,
    vectorised over rays and segments."""
    p, q = np.asarray(starts, float)[..., None, :], np.asarray(ends, float)[..., None, :]
    return _crosses(p, q, segments[:, 0], segments[:, 1]).any(axis=-1)


def _crosses(p: np.ndarray, q: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Elementwise (broadcast) whether segment p-q crosses or touches segment a-b (points (..., 2));
    collinear pairs count as not crossing."""
    ab, pq = b - a, q - p
    d1 = _cross(ab[..., 0], ab[..., 1], p[..., 0] - a[..., 0], p[..., 1] - a[..., 1])
    d2 = _cross(ab[..., 0], ab[..., 1], q[..., 0] - a[..., 0], q[..., 1] - a[..., 1])
    d3 = _cross(pq[..., 0], pq[..., 1], a[..., 0] - p[..., 0], a[..., 1] - p[..., 1])
    d4 = _cross(pq[..., 0], pq[..., 1], b[..., 0] - p[..., 0], b[..., 1] - p[..., 1])
    return (d1 * d2 <= 0) & (d3 * d4 <= 0) & ~((d1 == 0) & (d2 == 0))


def block_links(
    links: IRLinks,
    positions: np.ndarray,
    headings: np.ndarray,
    platform: Platform | str,
    obstacles: np.ndarray | None = None,
    silent: np.ndarray | None = None,
    drop_zero: bool = True,
    emit_off: np.ndarray | None = None,
    detect_off: np.ndarray | None = None,
) -> IRLinks:
    """``links`` with the light of static ``obstacles`` and switched-off robots taken out (a numpy pass
    after the gains).

    Args:
        links: the scene's links (gains gathered).
        positions: (N, 2) robot centres, world frame (m); headings (N,) (rad).
        platform: the robots' platform (emitter and detector positions).
        obstacles: (S, 2, 2) segments (m). A link's rays are tested against each segment its centre
            segment passes within the rays' reach (emitter / detector offsets) of (:func:`rays_blocked`);
            a blocked ray's gain becomes 0 and the link's ``emitter_sums`` are summed again (in emitter
            order, as the kernel sums them).
        silent: (N,) bool robots that neither emit nor detect: their links are dropped.
        drop_zero: drop links left without light.
        emit_off: (N,) bool robots that do not emit: the links from them are dropped.
        detect_off: (N,) bool robots that do not detect: the links to them are dropped.

    Returns: the new :class:`IRLinks` (``obstacle_clear`` set when a ray was tested), or ``links`` itself
    when nothing changes.
    """
    platform = get_platform(platform)
    n_links = len(links)
    keep = np.ones(n_links, dtype=bool)
    if silent is not None:
        silent = np.asarray(silent, dtype=bool)
        keep &= ~(silent[links.rx] | silent[links.tx])
    if emit_off is not None:
        keep &= ~np.asarray(emit_off, dtype=bool)[links.tx]
    if detect_off is not None:
        keep &= ~np.asarray(detect_off, dtype=bool)[links.rx]
    obstacle_clear = None
    gains, sums = links.gains, links.emitter_sums
    segments = no_obstacles() if obstacles is None else np.asarray(obstacles, dtype=float).reshape(-1, 2, 2)
    if len(segments) and n_links:
        # (link, segment) pairs whose rays can meet: every ray lies within the rays' reach (the emitter and
        # detector offsets) of the link's centre segment, so the centre segment must pass that close
        reach = max(np.hypot(*platform.emitter_positions.T).max(), np.hypot(*platform.detector_positions.T).max())
        a, b = positions[links.rx], positions[links.tx]
        lo, hi = np.minimum(a, b) - reach, np.maximum(a, b) + reach
        s_lo, s_hi = segments.min(axis=1), segments.max(axis=1)
        link, seg = np.nonzero(((lo[:, None, :] <= s_hi[None]) & (hi[:, None, :] >= s_lo[None])).all(axis=-1) & keep[:, None])
        close = _segment_distance(a[link], b[link], segments[seg, 0], segments[seg, 1]) <= reach * (1 + 1e-9)
        link, seg = link[close], seg[close]
        rows, pair_row = np.unique(link, return_inverse=True)
        if rows.size:
            detectors = _world_points(positions[links.rx[rows]], headings[links.rx[rows]], platform.detector_positions)
            emitters = _world_points(positions[links.tx[rows]], headings[links.tx[rows]], platform.emitter_positions)
            # each pair's rays against its one segment, then or-ed per link: (R, n_d, n_e)
            a_end, b_end = segments[seg, 0][:, None, None, :], segments[seg, 1][:, None, None, :]
            hit = _crosses(emitters[pair_row][:, None, :, :], detectors[pair_row][:, :, None, :], a_end, b_end)
            blocked = np.zeros((rows.size,) + hit.shape[1:], dtype=bool)
            np.logical_or.at(blocked, pair_row, hit)
            if blocked.any():
                obstacle_clear = np.ones(gains.shape, dtype=bool)
                obstacle_clear[rows] = ~blocked
                gains = gains.copy()
                gains[rows] = np.where(blocked, 0.0, gains[rows])
                if sums is not None:
                    sums = sums.copy()
                    sums[rows] = _emitter_sums(gains[rows])
                if drop_zero:
                    keep[rows] &= gains[rows].reshape(rows.size, -1).max(axis=1) > 0
    if keep.all() and obstacle_clear is None:
        return links
    occluders = None if links.occluders is None else (*links.occluders[:2], links.occluders[2][keep])
    return IRLinks(
        links.rx[keep], links.tx[keep], links.distance[keep], links.rel_position[keep], links.rel_heading[keep], gains[keep],
        links.n_robots, occluders, None if sums is None else sums[keep], None if obstacle_clear is None else obstacle_clear[keep],
    )


def _segment_distance(p: np.ndarray, q: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(K,) distance (m) between segments p-q and a-b, each (K, 2): 0 where they cross, else the smallest
    of the four end-point-to-segment distances."""

    def point_to_segment(x: np.ndarray, s0: np.ndarray, s1: np.ndarray) -> np.ndarray:
        d = s1 - s0
        t = np.clip(((x - s0) * d).sum(-1) / np.maximum((d * d).sum(-1), 1e-300), 0.0, 1.0)
        return np.linalg.norm(x - s0 - t[:, None] * d, axis=-1)

    ends = np.minimum(np.minimum(point_to_segment(p, a, b), point_to_segment(q, a, b)), np.minimum(point_to_segment(a, p, q), point_to_segment(b, p, q)))
    d1 = _cross(*(b - a).T, *(p - a).T)
    d2 = _cross(*(b - a).T, *(q - a).T)
    d3 = _cross(*(q - p).T, *(a - p).T)
    d4 = _cross(*(q - p).T, *(b - p).T)
    return np.where((d1 * d2 <= 0) & (d3 * d4 <= 0), 0.0, ends)


def _world_points(centres: np.ndarray, headings: np.ndarray, body_points: np.ndarray) -> np.ndarray:
    """(R, K, 2) world positions (m) of body-frame points ``body_points`` (K, 2) of R robots."""
    c, s = np.cos(headings)[:, None], np.sin(headings)[:, None]
    x, y = body_points[None, :, 0], body_points[None, :, 1]
    return np.stack([centres[:, 0:1] + c * x - s * y, centres[:, 1:2] + s * x + c * y], axis=-1)


def gain_threads(n_pairs: int) -> int:
    """Threads for the gain kernel and occluder search of one scene of ``n_pairs`` candidate directed pairs: numba's thread
    count (``NUMBA_NUM_THREADS``, default all cores; ``numba.set_num_threads``) from
    :data:`THREADED_MIN_PAIRS` pairs on (about 370 e-puck robots at the flocking default density), else 1.
    The chunks run on the calling thread and the helper threads of :func:`swarm_envs._compile._worker.run_chunks`
    (the library's own, which wait on a lock when idle, so they take no core from the physics or the
    worker thread; numba's own parallel threads spin for milliseconds after each parallel region).

    Only :func:`compute_links` of a single scene (``copy=None``: one env, as a large swarm is stepped)
    uses threads; a batch of copies stays on one thread (batched training scales with copies and worker
    processes instead), and only from the main Python thread (one large scene per process uses the
    helpers; envs stepped from other threads stay on their thread). The result is the same bit for bit
    either way."""
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
