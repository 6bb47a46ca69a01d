"""Per-robot hardware variation of the infrared channels (docs/design.md#hardware-variation).

[F14 Sec. VI]: the range & bearing model takes "the sensor and emitter models [to be] consistent across
different sensors and emitters, which tends not to be the case". Here every robot gets, when its env copy
is reset, its own deviation of each channel from the nominal platform:

- emitter power: a multiplier ``exp(s_e z)`` per emitter (lognormal, median 1);
- detector gain: a multiplier ``exp(s_d z)`` per detector;
- mounting angles: an offset ``s_a z`` (rad) of every detector's and emitter's axis;

z ~ N(0, 1) independent. The true gain of the ray from emitter j of transmitter w to detector i of
receiver u is then ``m_d[u, i] m_e[w, j] S(alpha') E(beta') A(r)`` [F14 Eq. (4)] with alpha', beta' measured
from the offset axes (positions unchanged); the range & bearing estimator keeps the nominal calibration.
No paper gives the spreads: they are assumptions (docs/design.md#hardware-variation), each a setting.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from swarm_envs.sim.platforms import Platform, get_platform

__all__ = ["Hardware", "draw_hardware"]


@dataclass
class Hardware:
    """Channel deviations of M robots (or of M pairs' receiver and transmitter, :meth:`pairs`).

    Attributes:
        detector_gain: (M, n_d) multiplier of each detector's gain.
        detector_offset: (M, n_d) offset (rad) of each detector's axis from the platform's.
        emitter_gain: (M, n_e) multiplier of each emitter's power.
        emitter_offset: (M, n_e) offset (rad) of each emitter's axis from the platform's.
    """

    detector_gain: np.ndarray
    detector_offset: np.ndarray
    emitter_gain: np.ndarray
    emitter_offset: np.ndarray
    _tables: tuple | None = field(default=None, init=False, repr=False, compare=False)

    def __len__(self) -> int:
        return int(self.detector_gain.shape[0])

    @classmethod
    def nominal(cls, n: int, platform: Platform | str) -> "Hardware":
        """``n`` robots exactly as the platform (multipliers 1, offsets 0)."""
        platform = get_platform(platform)
        nd, ne = platform.n_detectors, platform.n_emitters
        return cls(np.ones((n, nd)), np.zeros((n, nd)), np.ones((n, ne)), np.zeros((n, ne)))

    def pairs(self, rx: np.ndarray, tx: np.ndarray) -> "Hardware":
        """Per pair p: the detectors of robot ``rx[p]`` and the emitters of robot ``tx[p]`` (P rows)."""
        rx, tx = np.asarray(rx, dtype=np.int64), np.asarray(tx, dtype=np.int64)
        return Hardware(self.detector_gain[rx], self.detector_offset[rx], self.emitter_gain[tx], self.emitter_offset[tx])

    def tables(self, platform: Platform | str) -> tuple[np.ndarray, np.ndarray]:
        """The gain kernels' tables: (M, n_d, 3) and (M, n_e, 3) of (multiplier, cos, sin of the axis angle),
        computed once until :meth:`set_rows` changes a robot (read only)."""
        platform = get_platform(platform)
        if self._tables is None or self._tables[0] is not platform:
            d = platform.detector_directions[None, :] + self.detector_offset
            e = platform.emitter_directions[None, :] + self.emitter_offset
            det = np.stack([self.detector_gain, np.cos(d), np.sin(d)], axis=-1)
            em = np.stack([self.emitter_gain, np.cos(e), np.sin(e)], axis=-1)
            det.flags.writeable = em.flags.writeable = False
            self._tables = (platform, det, em)
        return self._tables[1], self._tables[2]

    def set_rows(self, rows: np.ndarray, other: "Hardware") -> None:
        """Overwrite robots ``rows`` with ``other``'s robots (in order)."""
        for name in ("detector_gain", "detector_offset", "emitter_gain", "emitter_offset"):
            getattr(self, name)[rows] = getattr(other, name)
        self._tables = None


def draw_hardware(
    rng: np.random.Generator, n: int, platform: Platform | str, emitter_spread: float, detector_spread: float, angle_spread_deg: float
) -> Hardware:
    """Channel deviations of ``n`` robots drawn from ``rng`` (module docstring): one standard-normal array
    (n, 2 (n_d + n_e)) per call, whatever the spreads, so a reset draws a fixed count. Spreads: standard
    deviations of ln(emitter power), ln(detector gain) and of the axis angles (degrees)."""
    platform = get_platform(platform)
    nd, ne = platform.n_detectors, platform.n_emitters
    z = rng.standard_normal((int(n), 2 * (nd + ne)))
    zd_gain, zd_ang, ze_gain, ze_ang = np.split(z, np.cumsum([nd, nd, ne]), axis=1)
    angle = np.radians(float(angle_spread_deg))
    return Hardware(
        np.exp(float(detector_spread) * zd_gain), angle * zd_ang, np.exp(float(emitter_spread) * ze_gain), angle * ze_ang
    )
