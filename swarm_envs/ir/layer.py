"""Shared infrared physical layer (SPEC 2): candidate pairs, line of sight, emitter-detector geometry, gains.

Computed once per env step, vectorised over all pairs (no Python loop over robot pairs):

1. candidate pairs: centres closer than the IR range, from ``scipy.spatial.cKDTree.query_pairs``;
2. line of sight: the segment between the two centres must not cross a *third* robot's disc
   (radius ``platform.radius``); occluded pairs exchange no light at all;
3. for each ordered pair (receiver u, transmitter w), every detector i of u and emitter j of w:
   ``r_ij = R + Rot(psi) e_j - d_i`` (vector from detector i to emitter j in u's body frame, R = w's
   centre in u's frame, psi = w's heading in u's frame, e_j / d_i the emitter / detector positions in
   their own body frames). This is [F14 Eq. (1)] ``r_ij = R - rho b_i + rho b_j`` generalised to
   arbitrary positions (the e-puck's offset emitters/detectors, [T20 Eqs. (3)-(5),(8)-(14)]).
   Detector incidence angle ``angle(r_ij) - delta_i`` and emission angle
   ``angle(-r_ij) - (psi + epsilon_j)`` [F14 Eqs. (2),(3),(11),(12)], delta / epsilon the axis angles;
4. gain = ``platform.ir_model.gain(|r_ij|, detector_angle, emitter_angle)`` (:mod:`swarm_envs.ir.models`).

All public inputs/outputs are SI (metres, radians, angles wrapped to (-pi, pi]).
"""

from __future__ import annotations

from dataclasses import dataclass
import numpy as np
from scipy.spatial import cKDTree

from swarm_envs.geometry import wrap_angle
from swarm_envs.ir import kernels
from swarm_envs.platforms import Platform, get_platform

__all__ = ["IRLinks", "compute_links", "pair_geometry", "pair_cosines", "pair_gains", "line_of_sight", "wrap_angle"]


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
    """

    rx: np.ndarray
    tx: np.ndarray
    distance: np.ndarray
    rel_position: np.ndarray
    rel_heading: np.ndarray
    gains: np.ndarray
    n_robots: int = 0

    def __len__(self) -> int:
        return int(self.rx.shape[0])

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
    rel_position: np.ndarray, rel_heading: np.ndarray, platform: Platform | str
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The same geometry as :func:`pair_geometry` as (distance, cos detector angle, cos emitter angle).

    Every IR model is symmetric in its angles (SPEC 3.1), so gains need only the cosines, which come from
    dot products with the unit detector-emitter vectors: no arctan2 and no angle wrapping on the
    (P, n_d, n_e) hot path.
    """
    platform = get_platform(platform)
    R = np.asarray(rel_position, dtype=float).reshape(-1, 2)
    psi = np.asarray(rel_heading, dtype=float).reshape(-1)
    c, s = np.cos(psi)[:, None], np.sin(psi)[:, None]
    ex, ey = platform.emitter_positions[:, 0][None, :], platform.emitter_positions[:, 1][None, :]
    emx = R[:, 0:1] + c * ex - s * ey  # emitter positions in the receiver frame (P, n_e)
    emy = R[:, 1:2] + s * ex + c * ey
    eca, esa = np.cos(platform.emitter_directions)[None, :], np.sin(platform.emitter_directions)[None, :]
    eax = (c * eca - s * esa)[:, None, :]  # emitter axes in the receiver frame (P, 1, n_e)
    eay = (s * eca + c * esa)[:, None, :]
    dx = emx[:, None, :] - platform.detector_positions[None, :, 0, None]
    dy = emy[:, None, :] - platform.detector_positions[None, :, 1, None]
    distance = np.hypot(dx, dy)
    inv = 1.0 / np.maximum(distance, 1e-12)
    ux, uy = dx * inv, dy * inv  # unit vector detector -> emitter
    dax = np.cos(platform.detector_directions)[None, :, None]
    day = np.sin(platform.detector_directions)[None, :, None]
    cos_detector = ux * dax + uy * day
    cos_emitter = -(ux * eax + uy * eay)
    return distance, cos_detector, cos_emitter


def pair_gains(
    rel_position: np.ndarray, rel_heading: np.ndarray, platform: Platform | str, model: object | None = None
) -> np.ndarray:
    """Noiseless gains (P, n_detectors, n_emitters) of the platform's IR model for P pairs.

    Equal to ``model.gain(*pair_geometry(...))``: a compiled kernel (:mod:`swarm_envs.ir.kernels`) when
    numba is installed, else numpy from cosines (:func:`pair_cosines`, ``model.gain_from_cos``). Line of sight is assumed (occlusion is :func:`line_of_sight`'s
    job). Pairs whose centre distance exceeds ``platform.ir_range`` get zero gain (the platform's
    "no infrared beyond" cut-off). ``model`` overrides the platform's IR model (e.g. the Droplet's
    low-power emitters, :class:`swarm_envs.ir.models.DropletLowPowerIR`).
    """
    platform = get_platform(platform)
    model = platform.ir_model if model is None else model
    R = np.ascontiguousarray(rel_position, dtype=float).reshape(-1, 2)
    psi = np.ascontiguousarray(rel_heading, dtype=float).reshape(-1)
    if kernels.HAVE_NUMBA and type(model).__name__ in kernels.MODEL_IDS:
        kind, params = kernels.model_params(model)
        return kernels.gains_kernel(
            R, psi, platform.detector_positions, platform.detector_directions,
            platform.emitter_positions, platform.emitter_directions, kind, params, float(platform.ir_range),
        )
    return _pair_gains_numpy(R, psi, platform, model)


def _pair_gains_numpy(R: np.ndarray, psi: np.ndarray, platform: Platform, model: object) -> np.ndarray:
    """The numpy reference of :func:`pair_gains` (used without numba, and to test the kernel)."""
    distance, cos_det, cos_em = pair_cosines(R, psi, platform)
    g = np.asarray(model.gain_from_cos(distance, cos_det, cos_em), dtype=float)
    return g * (np.hypot(R[:, 0], R[:, 1]) <= platform.ir_range)[:, None, None]


def line_of_sight(
    positions: np.ndarray,
    radius: float,
    i: np.ndarray,
    j: np.ndarray,
    tree: cKDTree | None = None,
) -> np.ndarray:
    """True where the segment between centres ``positions[i]`` and ``positions[j]`` crosses no third
    robot's disc (open disc of ``radius`` m around every other centre).

    Vectorised over pairs without Python lists: a robot k within ``radius`` of the segment lies within
    ``|ij| / 2 + radius`` of the nearer endpoint, so the candidates are the neighbours of i and of j
    within that distance, gathered from one KD-tree ``query_pairs`` in CSR form and tested by a compiled
    kernel (numba), or as flat (pair, candidate) numpy arrays without numba.

    Returns: (P,) bool mask.
    """
    positions = np.ascontiguousarray(positions, dtype=float)
    i = np.asarray(i, dtype=np.intp).reshape(-1)
    j = np.asarray(j, dtype=np.intp).reshape(-1)
    P = i.shape[0]
    if P == 0:
        return np.zeros(0, dtype=bool)
    if tree is None:
        tree = cKDTree(positions)
    a = positions[i]
    seg = positions[j] - a
    length = np.hypot(seg[:, 0], seg[:, 1])
    reach = 0.5 * float(length.max()) + radius
    near = tree.query_pairs(reach, output_type="ndarray")
    if near.shape[0] == 0:
        return np.ones(P, dtype=bool)
    src = np.concatenate([near[:, 0], near[:, 1]])
    dst = np.concatenate([near[:, 1], near[:, 0]])
    order = np.argsort(src, kind="stable")
    dst = dst[order]
    counts = np.bincount(src, minlength=positions.shape[0])
    starts = np.cumsum(counts) - counts
    if kernels.HAVE_NUMBA:
        return ~kernels.occluded_kernel(positions, float(radius), i, j, starts, counts, dst)
    blocked = np.zeros(P, dtype=bool)
    L2 = np.where(length > 0, length * length, 1.0)
    for end in (i, j):  # two vectorised passes: neighbours of i, then of j
        c = counts[end]
        pair = np.repeat(np.arange(P), c)
        offset = np.arange(int(c.sum())) - np.repeat(np.cumsum(c) - c, c)
        cand = dst[np.repeat(starts[end], c) + offset]
        keep = (cand != i[pair]) & (cand != j[pair])
        cand, pair = cand[keep], pair[keep]
        ap = positions[cand] - a[pair]
        sp = seg[pair]
        t = np.clip((ap[:, 0] * sp[:, 0] + ap[:, 1] * sp[:, 1]) / L2[pair], 0.0, 1.0)
        rx_ = ap[:, 0] - t * sp[:, 0]
        ry_ = ap[:, 1] - t * sp[:, 1]
        blocked[pair[rx_ * rx_ + ry_ * ry_ < radius * radius]] = True
    return ~blocked


def compute_links(
    positions: np.ndarray,
    headings: np.ndarray,
    platform: Platform | str,
    max_range: float | None = None,
    drop_zero: bool = True,
    copy: np.ndarray | None = None,
) -> IRLinks:
    """All directed IR links of a scene (SPEC 2), vectorised.

    Args:
        positions: (N, 2) robot centres, world frame (m).
        headings: (N,) robot headings, world frame (rad).
        platform: platform of all robots.
        max_range: candidate cut-off on centre distance (m); default ``platform.ir_range``.
        drop_zero: drop pairs whose gain matrix is all zero (e.g. beyond the range, or r-one pairs outside
            each other's cones). Default True.
        copy: (N,) env copy of each robot (batched engine): no pair and no occluder crosses copies (the
            KD-tree gets a third coordinate that puts copies out of each other's range; 0 within a copy, so
            every distance and link equals that of the copy alone).

    Returns:
        :class:`IRLinks` with both directions (u, w) and (w, u) of every candidate pair in line of sight,
        sorted by (rx, tx).
    """
    platform = get_platform(platform)
    positions = np.asarray(positions, dtype=float).reshape(-1, 2)
    headings = np.asarray(headings, dtype=float).reshape(-1)
    N = positions.shape[0]
    r = platform.ir_range if max_range is None else float(max_range)
    n_d, n_e = platform.n_detectors, platform.n_emitters
    if N < 2:
        return _empty_links(n_d, n_e, N)
    points = positions
    if copy is not None:
        lift = np.asarray(copy, dtype=float).reshape(-1, 1) * (4.0 * r + 4.0 * platform.radius + 1.0)
        points = np.concatenate([positions, lift], axis=1)
    tree = cKDTree(points)
    pairs = tree.query_pairs(r, output_type="ndarray")
    if pairs.shape[0] == 0:
        return _empty_links(n_d, n_e, N)
    los = line_of_sight(positions, platform.radius, pairs[:, 0], pairs[:, 1], tree)
    pairs = pairs[los]
    rx = np.concatenate([pairs[:, 0], pairs[:, 1]]).astype(np.intp)
    tx = np.concatenate([pairs[:, 1], pairs[:, 0]]).astype(np.intp)
    order = np.lexsort((tx, rx))
    rx, tx = rx[order], tx[order]
    d = positions[tx] - positions[rx]
    c, s = np.cos(headings[rx]), np.sin(headings[rx])
    rel = np.stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]], axis=-1)
    rel_heading = wrap_angle(headings[tx] - headings[rx])
    gains = pair_gains(rel, rel_heading, platform)
    distance = np.hypot(d[:, 0], d[:, 1])
    if drop_zero:
        keep = gains.reshape(gains.shape[0], -1).max(axis=1) > 0
        if not keep.all():
            rx, tx, rel, rel_heading, gains, distance = (
                rx[keep], tx[keep], rel[keep], rel_heading[keep], gains[keep], distance[keep]
            )
    return IRLinks(rx, tx, distance, rel, rel_heading, gains, N)


def _empty_links(n_d: int, n_e: int, n_robots: int) -> IRLinks:
    return IRLinks(
        np.zeros(0, np.intp),
        np.zeros(0, np.intp),
        np.zeros(0),
        np.zeros((0, 2)),
        np.zeros(0),
        np.zeros((0, n_d, n_e)),
        n_robots,
    )
