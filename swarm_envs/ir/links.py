"""The IR layer's result: the links of a scene (:class:`IRLinks`: receiver, transmitter, per-detector and
per-emitter gains, relative geometry) and the emitter-order sums of their gains."""

from __future__ import annotations
from dataclasses import dataclass, field
import numpy as np
from swarm_envs.sim.platforms import Platform, get_platform

__all__ = ["IRLinks", "emitter_sums", "clear_rays_numpy"]


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
        return clear & clear_rays_numpy(self.rel_position, self.rel_heading, platform, sub, xy[start + within])

    @property
    def bearing(self) -> np.ndarray:
        """(P,) true bearing (rad) of tx in rx's frame (ground truth, for validation / ideal sensing)."""
        return np.arctan2(self.rel_position[:, 1], self.rel_position[:, 0])


def emitter_sums(gains: np.ndarray) -> np.ndarray:
    """(P, n_d) sums of ``gains`` (P, n_d, n_e) over emitters, sequentially in emitter order from 0.0
    (:class:`IRLinks` ``emitter_sums`` of a model without a kernel; the kernel sums in the same order)."""
    acc = np.zeros(gains.shape[:2])
    for j in range(gains.shape[2]):
        acc += gains[:, :, j]
    return acc


def clear_rays_numpy(R: np.ndarray, psi: np.ndarray, platform: Platform, offsets: np.ndarray, xy: np.ndarray) -> np.ndarray:
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
