"""Infrared hardware models: emitter directivity x detector directivity x medium attenuation.

One small object per platform, obtained with ``platform.ir_model`` or
:func:`swarm_envs.sim.platforms.model_for` (made once per platform object; this module knows no platform presets:
it registers its classes by hardware kind with :func:`swarm_envs.sim.platforms.register_ir_model`). Every model
has ``gain(distance_m, detector_angle, emitter_angle) -> ndarray`` (numpy broadcasting), the noiseless
light one emitter delivers to one detector:

- ``distance_m``: emitter-to-detector distance (m; converted to cm inside where the fit is in cm),
- ``detector_angle``: incidence angle (rad) between the detector's axis and the direction to the emitter,
- ``emitter_angle``: angle (rad) between the emitter's axis and the direction to the detector.

Beware the papers swap letters (docs/design.md#infrared-physical-layer): [F14] calls the detector angle alpha and the emitter angle beta,
[T20] calls the emitter angle alpha and the detector angle beta. Here the arguments are named by role.

Units of the gain differ per platform and are stated on each class, together with the measurement
constants the range & bearing sensor needs (``adc_scale`` counts per gain unit, ``adc_max`` saturation
in counts, ``no_reading_floor`` in gain units, ``default_noise_sigma`` in counts).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from swarm_envs.sim.platforms import register_ir_model

__all__ = ["DropletIR", "DropletLowPowerIR", "EpuckIR", "RoneIR", "MODEL_CLASSES"]


class DropletIR:
    """Droplet IR channel [F14 Sec. IV, Eqs. (19)-(22)]; gain in 8-bit ADC counts (baseline-subtracted).

    ``gain = S(detector_angle) * E(emitter_angle) * A(r)`` [F14 Eq. (4)], r = emitter-sensor distance
    in cm (the reading of [F14 Eqs. (15),(16)] in docs/design.md#range-and-bearing). The gain is *not* clipped to the 8-bit range:
    saturation, rounding and noise belong to the measurement
    (:func:`swarm_envs.sensing.range_bearing_model.measure`).

    Near-range extension (ours): the fit ``A(r) = 14000/(r-3)^2 - 1`` has a pole at r = 3 cm and is only
    valid for roughly r >= 4 cm [F14 Eq. (21)], yet two Droplets at one radius of gap (centre distance
    6.6 cm, channel radius 2 cm) have facing emitter-sensor distances of 2.6 cm. Below
    ``r_near = 4 cm`` we continue the fit with an inverse-square law matched in value at 4 cm,
    ``A(r) = (A(4) + 1) (4 / r)^2 - 1``, which is continuous, finite and strictly decreasing, so the
    model stays invertible. Far away the fit crosses zero (r ~ 121 cm); A is floored at 0 there.
    """

    name = "droplet"
    #: switch points of the piecewise sensor / emitter fits (rad) [F14 Eqs. (19),(20)], chosen so the
    #: two branches meet continuously [F14 Eqs. (19),(20)]
    sensor_switch = 0.618614
    emitter_switch = 0.720527
    amp_coeff = 14000.0  # [F14 Eq. (21)]
    amp_offset_cm = 3.0
    inv_coeff = 118.0  # [F14 Eq. (22)] (118^2 = 13924 ~ 14000, the paper's rounding)
    r_near_cm = 4.0  # below this the inverse-square continuation is used (ours, see class doc)

    # measurement constants (docs/design.md#range-and-bearing)
    adc_scale = 1.0  # ADC counts per gain unit (the gain already is in counts)
    adc_max = 255.0  # 8-bit ADC
    no_reading_floor = 7.0  # firmware rejects a matrix whose entries are all below 7 counts (docs/design.md#range-and-bearing, estimator step 6)
    default_noise_sigma = 2.0  # counts; see swarm_envs.sensing.range_bearing for the choice

    def __init__(self, platform: Any = None) -> None:
        self.platform = platform
        self._a_near = self.amp_coeff / (self.r_near_cm - self.amp_offset_cm) ** 2  # A(r_near) + 1

    @staticmethod
    def _abs(a: Any) -> np.ndarray:
        return np.abs(np.asarray(a, dtype=float))

    def sensor(self, a: Any) -> np.ndarray:
        """Sensor directivity S(a) [F14 Eq. (19)]: ``1 - a^4`` if |a| < 0.618614 else ``1/(8 a^4)``.

        a: incidence angle (rad) at the detector; symmetric in a; dimensionless, S(0) = 1.
        """
        a = self._abs(a)
        with np.errstate(divide="ignore"):
            return np.where(a < self.sensor_switch, 1.0 - a**4, 1.0 / (8.0 * a**4))

    def emitter(self, b: Any) -> np.ndarray:
        """Emitter directivity E(b) [F14 Eq. (20)]: ``-b^4 + b^2/2 + 0.9375`` if |b| < 0.720527 else
        ``1/(4 b^4)``.

        b: emission angle (rad) off the emitter axis; symmetric in b; dimensionless, E(0) = 0.9375.
        """
        b = self._abs(b)
        with np.errstate(divide="ignore"):
            return np.where(b < self.emitter_switch, -(b**4) + 0.5 * b**2 + 0.9375, 1.0 / (4.0 * b**4))

    def amplitude(self, r_cm: Any) -> np.ndarray:
        """Amplitude A(r) in ADC counts [F14 Eq. (21)]: ``14000/(r-3)^2 - 1`` for r >= 4 cm (r in cm),
        inverse-square continuation below 4 cm (class doc), floored at 0."""
        r = np.asarray(r_cm, dtype=float)
        far = self.amp_coeff / np.maximum(r - self.amp_offset_cm, 1e-9) ** 2 - 1.0
        near = self._a_near * (self.r_near_cm / np.maximum(r, 1e-9)) ** 2 - 1.0
        return np.maximum(np.where(r >= self.r_near_cm, far, near), 0.0)

    def amplitude_inverse(self, x: Any) -> np.ndarray:
        """Inverse amplitude model (cm) [F14 Eq. (22)]: ``118/sqrt(x+1) + 3`` for x < A(4 cm), the
        inverse of the near-range continuation above. x in ADC counts (negative x treated as 0)."""
        x = np.maximum(np.asarray(x, dtype=float), 0.0)
        far = self.inv_coeff / np.sqrt(x + 1.0) + self.amp_offset_cm
        near = self.r_near_cm * np.sqrt(self._a_near / (x + 1.0))
        return np.where(x + 1.0 >= self._a_near, near, far)

    def gain(self, distance_m: Any, detector_angle: Any, emitter_angle: Any) -> np.ndarray:
        """Noiseless brightness ``S(detector_angle) E(emitter_angle) A(100 distance_m)`` in ADC counts
        [F14 Eq. (4)]. distance_m: emitter-sensor distance (m)."""
        return (
            self.sensor(detector_angle)
            * self.emitter(emitter_angle)
            * self.amplitude(100.0 * np.asarray(distance_m, dtype=float))
        )

    def gain_from_cos(self, distance_m: Any, cos_detector: Any, cos_emitter: Any) -> np.ndarray:
        """:meth:`gain` from the cosines of the (symmetric) angles, as the IR layer computes them."""
        a = np.arccos(np.clip(cos_detector, -1.0, 1.0))
        b = np.arccos(np.clip(cos_emitter, -1.0, 1.0))
        return self.gain(distance_m, a, b)

    def __repr__(self) -> str:
        return "DropletIR()"


class DropletLowPowerIR(DropletIR):
    """The Droplet emitters fired at the firmware's low power setting 250, for near range [F14 Sec. IV].

    The firmware's near fit is ``A(R) = 1100 / (R - 4)^2 + 12.5`` counts with R the centre distance in cm
    [F14 Sec. IV]. With both channels at rho = 2 cm, R - 4 = R - 2 rho is the facing emitter-sensor
    distance r, so in this module's convention (r = emitter-sensor distance) ``A_low(r) = 1100 / r^2 +
    12.5``; inverse ``r = sqrt(1100 / (x - 12.5))`` for x > 12.5 counts (x <= 12.5 reads as far away).
    Directivities S and E are the full-power ones. Used by the range & bearing sensor's
    ``near_model=True`` option instead of the power ladder when the full-power matrix saturates.
    """

    name = "droplet_low_power"
    low_coeff = 1100.0
    low_offset = 12.5

    def amplitude(self, r_cm: Any) -> np.ndarray:
        """Low-power amplitude (counts): ``1100 / r^2 + 12.5``, r = emitter-sensor distance (cm)."""
        r = np.maximum(np.asarray(r_cm, dtype=float), 1e-9)
        return self.low_coeff / r**2 + self.low_offset

    def amplitude_inverse(self, x: Any) -> np.ndarray:
        """Inverse of :meth:`amplitude` (cm); x <= 12.5 counts gives infinity."""
        x = np.asarray(x, dtype=float)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(x > self.low_offset, np.sqrt(self.low_coeff / np.maximum(x - self.low_offset, 1e-300)), np.inf)

    def __repr__(self) -> str:
        return "DropletLowPowerIR()"


class EpuckIR:
    """e-puck proximity-sensor IR channel [T20 Sec. 3]; gain = dimensionless detector intensity y.

    ``gain = h_e(emitter_angle) * h_m(d) * h_d(detector_angle)`` [T20 Eq. (7)] with
    ``h_e(a) = |cos a|^7`` (|a| <= pi/2, else 0) [Eq. (27)], ``h_d(b) = |cos b|^3`` (|b| <= pi/2, else 0)
    [Eq. (24)], ``h_m(d) = 1`` for d <= o_m^(-1/k_m) else ``o_m d^k_m`` with d in cm, k_m = -1.54557,
    o_m = 1.12202 [Eq. (25)]. y is the intensity before the detector's ``min(1, .)`` saturation.

    Measurement constants for range & bearing: the 12-bit ADC maps y to ``(m_max - m_min)(1 - y)``,
    m_max - m_min = 4080 - 150 = 3930 counts [T20 Eqs. (15)-(22)], so ``adc_scale = 3930`` counts per
    unit y, saturation at y = 1 (``adc_max = 3930`` counts); ADC noise variance 2.5 counts^2
    (sigma = 1.58 counts). The no-reading floor (ours) is 8 counts = 5 noise sigmas.
    """

    name = "epuck"
    k_m = -1.54557  # [T20 Eq. (25)]
    o_m = 1.12202
    adc_scale = 3930.0
    adc_max = 3930.0
    no_reading_floor = 8.0 / 3930.0
    default_noise_sigma = float(np.sqrt(2.5))

    def __init__(self, platform: Any = None) -> None:
        self.platform = platform
        self.d_sat_cm = self.o_m ** (-1.0 / self.k_m)  # ~1.077 cm: h_m = 1 below this

    def emitter(self, a: Any) -> np.ndarray:
        """Emitter directivity h_e(a) = |cos a|^7 for |a| <= pi/2, else 0 [T20 Eq. (27)]."""
        a = np.asarray(a, dtype=float)
        return np.where(np.abs(a) <= np.pi / 2, np.abs(np.cos(a)) ** 7, 0.0)

    def sensor(self, b: Any) -> np.ndarray:
        """Detector directivity h_d(b) = |cos b|^3 for |b| <= pi/2, else 0 [T20 Eq. (24)]."""
        b = np.asarray(b, dtype=float)
        return np.where(np.abs(b) <= np.pi / 2, np.abs(np.cos(b)) ** 3, 0.0)

    detector = sensor

    def amplitude(self, d_cm: Any) -> np.ndarray:
        """Medium attenuation h_m(d) [T20 Eq. (25)], d = emitter-detector distance in cm."""
        d = np.asarray(d_cm, dtype=float)
        return np.where(d <= self.d_sat_cm, 1.0, self.o_m * np.maximum(d, 1e-12) ** self.k_m)

    medium = amplitude

    def amplitude_inverse(self, y: Any) -> np.ndarray:
        """Inverse of h_m (cm): ``(y / o_m)^(1/k_m)``; y >= 1 maps to the saturation distance ~1.08 cm,
        y <= 0 to infinity."""
        y = np.asarray(y, dtype=float)
        with np.errstate(divide="ignore"):
            d = (np.maximum(y, 0.0) / self.o_m) ** (1.0 / self.k_m)
        return np.where(y >= 1.0, self.d_sat_cm, d)

    def gain(self, distance_m: Any, detector_angle: Any, emitter_angle: Any) -> np.ndarray:
        """Noiseless intensity ``h_e(emitter_angle) h_m(100 distance_m) h_d(detector_angle)`` (dimensionless)
        [T20 Eq. (7)]. distance_m: emitter-detector distance (m)."""
        return (
            self.emitter(emitter_angle)
            * self.amplitude(100.0 * np.asarray(distance_m, dtype=float))
            * self.sensor(detector_angle)
        )

    def gain_from_cos(self, distance_m: Any, cos_detector: Any, cos_emitter: Any) -> np.ndarray:
        """:meth:`gain` from the angles' cosines: ``max(cos, 0)^7`` and ``max(cos, 0)^3`` are h_e and h_d
        [T20 Eqs. (27),(24)] (|a| <= pi/2 exactly where cos a >= 0), without trigonometry."""
        ce = np.asarray(cos_emitter, dtype=float)
        cd = np.asarray(cos_detector, dtype=float)
        d = np.asarray(distance_m, dtype=float)
        ce, cd, d = np.broadcast_arrays(ce, cd, d)
        lit = (ce > 0.0) & (cd > 0.0)  # the power law is evaluated only where light arrives
        out = np.zeros(ce.shape)
        e, c = ce[lit], cd[lit]
        e2 = e * e
        out[lit] = (e2 * e2 * e2 * e) * (c * c * c) * self.amplitude(100.0 * d[lit])
        return out

    def __repr__(self) -> str:
        return "EpuckIR()"


class RoneIR:
    """r-one binary IR reception [L Sec. 3.2.1, 3.2.3]; gain 1 (heard) or 0.

    A receiver hears a transmitter iff the direction to it lies within the receiver's 68-degree arc
    (|detector_angle| <= 34 deg, ``platform.sensor_arc``; the shield limits "the detection of a single IR
    receiver to a 68 deg arc" [L Sec. 3.2.1, Fig. 3.9]) and the receiver lies in front of the transmitter
    (|emitter_angle| <= 90 deg) and the distance is at most ``max_range``.

    Transmitters: [L Sec. 3.2.1] says only that they "emit a radially uniform energy pattern". Our reading
    (an assumption): each transmitter emits uniformly over its outward half-plane (the 180 degrees in front
    of it) and the robot's own body blocks the inner side, so the 8 transmitters together light every
    direction; the thesis gives no transmitter shield, cone width or fall-off, and the binary model has no
    intensity. Because emitters and detectors sit on the body perimeter, a narrower transmitter cone would
    leave close neighbours (centre distance below ~19 cm with a 68-degree cone) unheard, which the thesis's
    contact-range behaviours contradict. A direction is lit by 4 adjacent transmitters (5 on a boundary), so
    the transmitter-index orientation estimate has a 45-degree resolution in the far field
    (docs/design.md#bearing-only-sensing).

    ``distance`` here is the emitter-detector distance; ``max_range`` defaults to ``platform.ir_range``
    (1 m). The IR layer additionally cuts at centre distance ``platform.ir_range``
    (:func:`swarm_envs.ir.layer.pair_gains`), so the effective cut is the smaller of the two.
    ``emitter_arc`` (rad) overrides the transmitter's full emission angle (default pi, the half-plane).
    """

    name = "rone"
    adc_scale = 1.0
    adc_max = 1.0
    no_reading_floor = 0.5
    default_noise_sigma = 0.0

    def __init__(self, platform: Any = None, emitter_arc: float | None = None) -> None:
        self.platform = platform
        arc = getattr(platform, "sensor_arc", None) or np.deg2rad(68.0)
        self.sensor_half_arc = 0.5 * float(arc)
        self.emitter_half_arc = 0.5 * float(emitter_arc if emitter_arc is not None else np.pi)
        self.max_range = float(getattr(platform, "ir_range", 1.0))
        self._eps = 1e-9  # so a direction exactly on the 34-degree boundary counts as inside

    def sensor(self, a: Any) -> np.ndarray:
        """1.0 where |a| <= half the receiver arc (34 deg), else 0.0."""
        return (np.abs(np.asarray(a, dtype=float)) <= self.sensor_half_arc + self._eps).astype(float)

    def emitter(self, b: Any) -> np.ndarray:
        """1.0 where |b| <= half the transmitter's emission angle (90 deg: its outward half-plane), else 0.0."""
        return (np.abs(np.asarray(b, dtype=float)) <= self.emitter_half_arc + self._eps).astype(float)

    def gain(self, distance_m: Any, detector_angle: Any, emitter_angle: Any) -> np.ndarray:
        """Binary reception (1.0 / 0.0); distance_m in metres."""
        inside = np.asarray(distance_m, dtype=float) <= self.max_range
        return self.sensor(detector_angle) * self.emitter(emitter_angle) * inside

    def gain_from_cos(self, distance_m: Any, cos_detector: Any, cos_emitter: Any) -> np.ndarray:
        """:meth:`gain` from the angles' cosines (inside the arc iff cos >= cos(half arc))."""
        inside = np.asarray(distance_m, dtype=float) <= self.max_range
        heard = np.asarray(cos_detector) >= np.cos(self.sensor_half_arc + self._eps)
        seen = np.asarray(cos_emitter) >= np.cos(self.emitter_half_arc + self._eps)
        return (heard & seen & inside).astype(float)

    def __repr__(self) -> str:
        return "RoneIR()"


#: Model class for each kind of IR hardware, registered with :func:`swarm_envs.sim.platforms.register_ir_model`
#: (:func:`swarm_envs.sim.platforms.model_for` picks one per platform).
MODEL_CLASSES: dict[str, type] = {"droplet": DropletIR, "epuck": EpuckIR, "rone": RoneIR}
for _kind, _cls in MODEL_CLASSES.items():
    register_ir_model(_kind, _cls)
