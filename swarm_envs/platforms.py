"""Robot platform presets: body geometry, drive limits and infrared channel layout.

All quantities are SI (metres, seconds, radians) in the robot's body frame: origin at the centre,
x-axis forward, angles counter-clockwise. The infrared *hardware model* (gain functions) of each
platform lives in :mod:`swarm_envs.ir.models`; :attr:`Platform.ir_model` (or :func:`model_for`) returns it.

Sources (docs/design.md#platforms):
- ``droplet``: Farrow et al., ICRA 2014 [F14 Sec. III]: 4.4 cm diameter, 6 emitters and 6 sensors
  co-located at radius 2.0 cm, channel k at 30 + 60 k degrees. Max speed 2 cm/s is assumed.
- ``epuck``: Trenkwalder et al. 2020 [T20 Sec. 2, Eqs. (1),(2)]: 7.0 cm diameter, 8 proximity
  sensors; each has an emitter and a detector 0.127 cm either side of the sensor point, both facing
  the sensor's direction. Layout from the public Webots e-puck model (docs/design.md#platforms).
- ``rone``: Lynch thesis [L Sec. 3.2]: 11 cm diameter, 8 IR receivers at 22.5 + 45 k degrees with
  68-degree arcs, 8 transmitters at 45 k degrees.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from swarm_envs.ir.models import MODEL_CLASSES

__all__ = ["Platform", "PLATFORMS", "get_platform", "model_for"]


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
        extras={"min_speed": 0.015},
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


_MODEL_CACHE: dict[str, Any] = {}


def model_for(platform: Any) -> Any:
    """The IR model of a platform (a :class:`Platform` or a preset name), cached by platform name.

    A custom platform may name a model class via ``platform.extras["ir_model"]`` (``"droplet"``,
    ``"epuck"`` or ``"rone"``, see :data:`swarm_envs.ir.models.MODEL_CLASSES`); it is then cached under
    its own name.
    """
    if isinstance(platform, str):
        platform = get_platform(platform)
    name = platform.name
    model = _MODEL_CACHE.get(name)
    if model is None:
        kind = (getattr(platform, "extras", None) or {}).get("ir_model", name)
        try:
            cls = MODEL_CLASSES[kind]
        except KeyError:
            raise ValueError(
                f"no IR model for platform {name!r}; allowed: {sorted(MODEL_CLASSES)} "
                "(or set platform.extras['ir_model'])"
            ) from None
        model = cls(platform)
        _MODEL_CACHE[name] = model
    return model
