"""Robot platform presets: body geometry, drive limits and infrared channel layout.

All quantities are SI (metres, seconds, radians) in the robot's body frame: origin at the centre,
x-axis forward, angles counter-clockwise. The infrared *hardware model* (gain functions) of each
platform lives in :mod:`swarm_envs.ir.models`; :attr:`Platform.ir_model` (or :func:`model_for`) returns it.

Sources:
- ``droplet``: Farrow et al., ICRA 2014 [F14 Sec. III]: 4.4 cm diameter, 6 emitters and 6 sensors
  co-located at radius 2.0 cm, channel k at 30 + 60 k degrees. Max speed 2 cm/s is assumed.
  Motion error: an 8 % wheel-gain spread from the calibrated Droplets' square walks of Klingner et al.
  [K14 Sec. V-B] (``docs/design.md#motion-error``); the 10 % per-step noise is assumed.
- ``epuck``: Trenkwalder et al. 2020 [T20 Sec. 2, Eqs. (1),(2)]: 7.0 cm diameter, 8 proximity
  sensors; each has an emitter and a detector 0.127 cm either side of the sensor point, both facing
  the sensor's direction. Layout from the public Webots e-puck model. Motion error (stepper motors: open
  loop at the commanded step rate): 1 % wheel-gain spread and 2 % per-step noise, assumed.
- ``rone``: Lynch thesis [L Sec. 3.2]: 11 cm diameter, 8 IR receivers at 22.5 + 45 k degrees with
  68-degree arcs, 8 transmitters at 45 k degrees, each lighting its outward half-plane ("a radially
  uniform energy pattern" [L Sec. 3.2.1]; the half-plane is our reading, swarm_envs.ir.models.RoneIR). Motion error: no wheel turns below the minimum
  controllable speed of 15 mm/s [L Sec. 3.1]; 2 % wheel-gain spread and 2 % per-step noise, assumed.

Messaging bit rate (``ir_bitrate``, the default of the ``bitrate`` setting): e-puck 310 bps, the rate of
[T20]'s experiments; r-one 1250 bps, its receivers' rate [L Sec. 3.2.1]; Droplet 310 bps (assumed).

Message frames (``frame_crc_bits``, docs/design.md#swarmcom-messaging): the r-one's IR messages carry a
16-bit CRC [L Sec. 3.2.1, Table 3.3], the Droplet firmware's a CRC-16 of the same polynomial (cu-droplet
``ir_comm.c``), the e-puck's SwarmCom frames none [T20 Sec. 4.3].

A custom robot is a :class:`Platform` of its own (``dataclasses.replace(get_platform("epuck"), mass=0.2)``);
every field is checked when it is made (:meth:`Platform.__post_init__`), so a bad value fails there with a
``ValueError`` naming the field, never inside the physics engine or the IR layer.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from swarm_envs._text import shown

__all__ = [
    "Platform", "PLATFORMS", "get_platform", "model_for", "MAX_RADIUS", "MAX_SPEED", "MAX_MASS", "MAX_IR_RANGE", "MAX_CHANNELS",
    "MAX_WHEEL_ERROR", "MAX_BITRATE", "CRC_WIDTHS", "IR_MODELS", "register_ir_model",
]

#: CRC widths (bits) a message frame can carry: 0 (no CRC), 8, 16 (SwarmCom's frames, :mod:`swarm_envs.comm.protocol`)
CRC_WIDTHS = (0, 8, 16)

#: IR model class of each kind of IR hardware (:func:`model_for`): :mod:`swarm_envs.ir.models` registers
#: ``"droplet"``, ``"epuck"`` and ``"rone"`` when it is imported, as ``import swarm_envs`` does
#: (:func:`register_ir_model`); the models know no platform presets, the presets no model code.
IR_MODELS: dict[str, type] = {}


def register_ir_model(kind: str, cls: type) -> None:
    """Make ``cls`` (called with a :class:`Platform`, returning its IR model) the model of the IR hardware
    ``kind``: of the platform named ``kind``, and of a custom platform with ``extras["ir_model"] = kind``."""
    IR_MODELS[kind] = cls

#: bps: the fastest messaging rate a platform may declare (ten times the e-puck's fastest measured rate)
MAX_BITRATE = 20_000

#: m: the largest body radius; the arena, spawn and IR geometry are sized for robots of centimetres to decimetres
MAX_RADIUS = 1.0
#: m/s: the largest wheel speed; with the sub-step counts the physics allows (``physics_substeps`` <= 1000)
#: faster robots would close more than their contacts can stop within one sub-step
#: (:func:`swarm_envs.sim.control.default_substeps` also bounds it for small robots)
MAX_SPEED = 10.0
#: kg: the heaviest robot; pymunk needs a finite positive mass, and the motor forces scale with it
MAX_MASS = 1000.0
#: m: the longest infrared reach; the IR layer considers every pair of robots closer than this, so its
#: work grows with the square of the range (the presets reach 0.5-1 m)
MAX_IR_RANGE = 10.0
#: emitters or detectors per robot at most (the presets have 6-8; the IR layer's work grows with their product)
MAX_CHANNELS = 64
#: the largest relative spread of a wheel's speed (``wheel_gain_std``, ``wheel_noise_std``): a spread of the
#: whole commanded speed; a wheel's factor is clipped at zero, so noise never turns a wheel backwards
MAX_WHEEL_ERROR = 1.0


def _positive(name: str, value: Any, high: float, unit: str, why: str = "") -> float:
    """``value`` as a float in (0, high]; ``ValueError`` naming the field otherwise."""
    ok = isinstance(value, numbers.Real) and not isinstance(value, bool)
    try:
        number = float(value) if ok else math.nan
    except (OverflowError, ValueError):  # an int or fraction too large for a float
        number = math.nan
    if not (math.isfinite(number) and 0.0 < number <= high):
        why = f" ({why})" if why else ""
        raise ValueError(f"Platform.{name} must be a finite number of {unit} in (0, {high:g}]{why}, got {shown(value)}")
    return number


def _at_least_zero(name: str, value: Any, high: float, unit: str, why: str) -> float:
    """``value`` as a float in [0, high]; ``ValueError`` naming the field otherwise."""
    ok = isinstance(value, numbers.Real) and not isinstance(value, bool)
    try:
        number = float(value) if ok else math.nan
    except (OverflowError, ValueError):
        number = math.nan
    if not (math.isfinite(number) and 0.0 <= number <= high):
        raise ValueError(f"Platform.{name} must be a finite number of {unit} in [0, {high:g}] ({why}), got {value!r:.80}")
    return number


def _layout(name: str, value: Any, shape: tuple[int | None, ...]) -> np.ndarray:
    """``value`` as a read-only float array of ``shape`` (None: any length in [1, MAX_CHANNELS]), finite."""
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise ValueError(f"Platform.{name} must be a real-valued array, got {shown(value)}") from None
    want = "(" + ", ".join("n" if d is None else str(d) for d in shape) + ("," if len(shape) == 1 else "") + ")"
    if arr.ndim != len(shape) or any(d is not None and a != d for a, d in zip(arr.shape, shape)):
        raise ValueError(f"Platform.{name} must have shape {want}, got {arr.shape}")
    if not 1 <= arr.shape[0] <= MAX_CHANNELS:
        raise ValueError(f"Platform.{name} must list 1 to {MAX_CHANNELS} channels, got {arr.shape[0]}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"Platform.{name} must be finite")
    arr.setflags(write=False)
    return arr


@dataclass(frozen=True, eq=False)
class Platform:
    """A robot model: disc body, differential drive and IR emitter/detector layout.

    Attributes:
        name: preset name.
        radius: body radius (m).
        max_speed: maximum wheel (and so linear) speed (m/s).
        wheel_base: distance between the wheels (m); max angular speed = 2 max_speed / wheel_base.
        mass: body mass (kg), used by the physics engine for pushing.
        ir_range: centre distance (m) beyond which no infrared is exchanged (candidate-pair cut-off).
        emitter_positions: (n_emitters, 2) emitter positions in the body frame (m).
        emitter_directions: (n_emitters,) emitter axis angles in the body frame (rad).
        detector_positions: (n_detectors, 2) detector positions in the body frame (m).
        detector_directions: (n_detectors,) detector axis angles in the body frame (rad).
        sensor_arc: full angular width (rad) of a receiver's field of view (r-one), or None.
        extras: further data (e.g. ``"ir_model"``, the IR model class of a custom platform).
        wheel_gain_std: relative std of each wheel's speed gain, drawn per robot and episode (calibration
            error: wheel diameters, motor constants); the motion error of ``motion_noise``.
        wheel_noise_std: relative std of each wheel's speed, drawn per wheel and control step (slip,
            speed-control jitter); the motion error of ``motion_noise``.
        min_wheel_speed: wheel speed (m/s) below which a commanded wheel does not turn (gear-train
            friction; a dead zone); the motion error of ``motion_noise``.
        ir_bitrate: bits per second of the robot's infrared messaging (the default of the ``bitrate``
            setting); a whole number of bit slots per 0.1 s control step.
        frame_crc_bits: width of the CRC the robot's messaging firmware appends to every SwarmCom frame
            (0, 8 or 16; :func:`swarm_envs.comm.protocol.crc`): 16 on the r-one and the Droplet, 0 on the
            e-puck (module docstring).
    """

    name: str
    radius: float
    max_speed: float
    wheel_base: float
    mass: float
    ir_range: float
    emitter_positions: np.ndarray
    emitter_directions: np.ndarray
    detector_positions: np.ndarray
    detector_directions: np.ndarray
    sensor_arc: float | None = None
    extras: dict[str, Any] = field(default_factory=dict)
    wheel_gain_std: float = 0.0
    wheel_noise_std: float = 0.0
    min_wheel_speed: float = 0.0
    frame_crc_bits: int = 0
    ir_bitrate: int = 310

    def __post_init__(self) -> None:
        """Check every field; ``ValueError`` naming the field. Numbers become floats and the layouts
        read-only float arrays (the emitters and detectors on the body: at most ``radius`` from the centre)."""
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"Platform.name must be a non-empty string, got {self.name!r:.80}")
        radius = _positive("radius", self.radius, MAX_RADIUS, "metres")
        values = {
            "radius": radius,
            "max_speed": _positive("max_speed", self.max_speed, MAX_SPEED, "metres per second"),
            "wheel_base": _positive("wheel_base", self.wheel_base, 2.0 * radius, "metres", "at most the diameter: wheels on the body"),
            "mass": _positive("mass", self.mass, MAX_MASS, "kilograms"),
            "ir_range": _positive("ir_range", self.ir_range, MAX_IR_RANGE, "metres"),
            "emitter_positions": _layout("emitter_positions", self.emitter_positions, (None, 2)),
            "detector_positions": _layout("detector_positions", self.detector_positions, (None, 2)),
        }
        for kind in ("emitter", "detector"):
            positions = values[f"{kind}_positions"]
            values[f"{kind}_directions"] = _layout(f"{kind}_directions", getattr(self, f"{kind}_directions"), (positions.shape[0],))
            if np.any(np.hypot(positions[:, 0], positions[:, 1]) > radius * (1 + 1e-9)):
                raise ValueError(f"Platform.{kind}_positions must lie on the body (at most radius = {radius:g} m from the centre)")
        if self.sensor_arc is not None:
            values["sensor_arc"] = _positive("sensor_arc", self.sensor_arc, 2 * math.pi, "radians", "or None")
        spread = "a spread of the whole commanded speed; a wheel's factor is clipped at zero"
        values["wheel_gain_std"] = _at_least_zero("wheel_gain_std", self.wheel_gain_std, MAX_WHEEL_ERROR, "relative std", spread)
        values["wheel_noise_std"] = _at_least_zero("wheel_noise_std", self.wheel_noise_std, MAX_WHEEL_ERROR, "relative std", spread)
        values["min_wheel_speed"] = _at_least_zero(
            "min_wheel_speed", self.min_wheel_speed, values["max_speed"], "metres per second", "at most max_speed: some speed must turn the wheels"
        )
        if not isinstance(self.extras, dict):
            raise ValueError(f"Platform.extras must be a dict, got {type(self.extras).__name__}")
        crc_ok = isinstance(self.frame_crc_bits, numbers.Integral) and not isinstance(self.frame_crc_bits, bool)
        if not (crc_ok and int(self.frame_crc_bits) in CRC_WIDTHS):
            raise ValueError(f"Platform.frame_crc_bits must be one of {CRC_WIDTHS} (CRC widths SwarmCom frames can carry), got {shown(self.frame_crc_bits)}")
        values["frame_crc_bits"] = int(self.frame_crc_bits)
        rate_ok = isinstance(self.ir_bitrate, numbers.Integral) and not isinstance(self.ir_bitrate, bool)
        if not (rate_ok and 0 < int(self.ir_bitrate) <= MAX_BITRATE and int(self.ir_bitrate) % 10 == 0):
            raise ValueError(
                f"Platform.ir_bitrate must be a multiple of 10 bps in (0, {MAX_BITRATE}] (whole bit slots per 0.1 s step), "
                f"got {shown(self.ir_bitrate)}"
            )
        values["ir_bitrate"] = int(self.ir_bitrate)
        for key, value in values.items():
            object.__setattr__(self, key, value)

    @property
    def diameter(self) -> float:
        """Body diameter (m)."""
        return 2.0 * self.radius

    @property
    def max_angular_speed(self) -> float:
        """Angular speed (rad/s) when the wheels turn at +-max_speed in opposite directions."""
        return 2.0 * self.max_speed / self.wheel_base

    @property
    def n_emitters(self) -> int:
        return int(self.emitter_positions.shape[0])

    @property
    def n_detectors(self) -> int:
        return int(self.detector_positions.shape[0])

    @property
    def ir_model(self) -> Any:
        """The platform's infrared hardware model (see :mod:`swarm_envs.ir.models`)."""
        return model_for(self)

    def __repr__(self) -> str:
        return f"Platform({self.name!r}, diameter={self.diameter:.3f} m)"


def _ring(radius: float, angles_deg: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    angles = np.deg2rad(np.asarray(angles_deg, dtype=float))
    return radius * np.stack([np.cos(angles), np.sin(angles)], axis=-1), angles


def _droplet() -> Platform:
    pos, ang = _ring(0.020, 30.0 + 60.0 * np.arange(6))
    return Platform(
        name="droplet",
        radius=0.022,
        max_speed=0.02,
        wheel_base=0.044,
        mass=0.03,
        ir_range=0.50,  # A(r) falls below the 7-count no-reading floor near 45 cm [F14 Eq. (21)]
        emitter_positions=pos,
        emitter_directions=ang,
        detector_positions=pos.copy(),
        detector_directions=ang.copy(),
        wheel_gain_std=0.08,  # calibrated Droplets' square walks [K14 Sec. V-B] (docs/design.md#motion-error)
        wheel_noise_std=0.10,  # assumed: stick-slip steps of vibration motors
        frame_crc_bits=16,  # cu-droplet ir_comm.c: CRC-16 (avr-libc _crc16_update) over header and data
    )


# e-puck proximity sensors ps0..ps7 (x forward, y left): position radius (cm), angle (deg), facing (deg).
EPUCK_SENSOR_RADIUS_CM = np.array([3.16, 3.33, 3.10, 3.35, 3.35, 3.10, 3.33, 3.16])
EPUCK_SENSOR_ANGLE_DEG = np.array([-18.4, -48.7, -90.0, -153.4, 153.4, 90.0, 48.7, 18.4])
EPUCK_SENSOR_FACING_DEG = np.array([-17.2, -45.9, -90.0, -151.5, 151.2, 90.0, 45.8, 17.1])
EPUCK_EMITTER_OFFSET_CM = 0.127  # [T20 Eqs. (1),(2)]


def _epuck() -> Platform:
    ang = np.deg2rad(EPUCK_SENSOR_ANGLE_DEG)
    facing = np.deg2rad(EPUCK_SENSOR_FACING_DEG)
    point = (EPUCK_SENSOR_RADIUS_CM[:, None] / 100.0) * np.stack([np.cos(ang), np.sin(ang)], -1)
    perp_left = np.stack([-np.sin(facing), np.cos(facing)], -1)
    offset = EPUCK_EMITTER_OFFSET_CM / 100.0
    return Platform(
        name="epuck",
        radius=0.035,
        max_speed=0.128,
        wheel_base=0.053,
        mass=0.15,
        ir_range=1.0,  # beyond 1 m the strongest gain is a few ADC counts [T20 Eq. (25)]
        emitter_positions=point + offset * perp_left,
        emitter_directions=facing.copy(),
        detector_positions=point - offset * perp_left,
        detector_directions=facing.copy(),
        wheel_gain_std=0.01,  # assumed: stepper motors run open loop at the commanded step rate
        wheel_noise_std=0.02,  # assumed: slip
    )


def _rone() -> Platform:
    rx_pos, rx_ang = _ring(0.050, 22.5 + 45.0 * np.arange(8))
    tx_pos, tx_ang = _ring(0.050, 45.0 * np.arange(8))
    return Platform(
        name="rone",
        radius=0.055,
        max_speed=0.30,
        wheel_base=0.078,
        mass=0.3,
        ir_range=1.0,  # IR range ~1 m in the thesis simulation [L Sec. 5.4]
        emitter_positions=tx_pos,
        emitter_directions=tx_ang,
        detector_positions=rx_pos,
        detector_directions=rx_ang,
        sensor_arc=np.deg2rad(68.0),
        wheel_gain_std=0.02,  # assumed
        wheel_noise_std=0.02,  # assumed
        min_wheel_speed=0.015,  # "internal friction in the gear-train limits the minimum controllable speed" [L Sec. 3.1]
        frame_crc_bits=16,  # "A 16-bit cyclic redundancy check (CRC)" on every message [L Sec. 3.2.1, Table 3.3]
        ir_bitrate=1250,  # the receivers' rate: 32.8 ms for a 3-byte message [L Sec. 3.2.1]
    )


PLATFORMS: dict[str, Platform] = {p.name: p for p in (_droplet(), _epuck(), _rone())}


def get_platform(platform: str | Platform) -> Platform:
    """Return a preset by name (``"droplet"``, ``"epuck"``, ``"rone"``) or pass a Platform through."""
    if isinstance(platform, Platform):
        return platform
    try:
        return PLATFORMS[platform]
    except (KeyError, TypeError):
        raise ValueError(
            f"unknown platform {platform!r}; allowed values: {sorted(PLATFORMS)}"
        ) from None


def model_for(platform: Any) -> Any:
    """The IR model of a platform (a :class:`Platform` or a preset name), made once per platform object
    (a model reads its platform's fields, so a custom platform never shares a preset's model).

    The model class is the one named by the platform's name, or by ``platform.extras["ir_model"]``
    (``"droplet"``, ``"epuck"`` or ``"rone"``, see :data:`IR_MODELS`) for a custom platform.
    """
    if isinstance(platform, str):
        platform = get_platform(platform)
    model = platform.__dict__.get("_ir_model")
    if model is None:
        name = platform.name
        kind = (getattr(platform, "extras", None) or {}).get("ir_model", name)
        try:
            cls = IR_MODELS[kind]
        except (KeyError, TypeError):
            raise ValueError(
                f"no IR model for platform {name!r}; allowed: {sorted(IR_MODELS)} "
                "(or set platform.extras['ir_model'])"
            ) from None
        model = cls(platform)
        object.__setattr__(platform, "_ir_model", model)  # a Platform is frozen; the model is derived data
    return model
