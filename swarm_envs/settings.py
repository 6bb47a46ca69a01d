"""Settings of the swarm envs: the defaults and the one validator every entry point uses.

:func:`validate_settings` checks a task's keyword arguments up front (types, finiteness, allowed values,
and combinations such as BCH codes and message sizes the SwarmCom frame can carry [T20]), whatever the
``sensing`` mode, so a bad value fails when the env is built, never at ``reset`` or mid-training. The env
constructor (:class:`swarm_envs.env.SwarmEnv`) and the training config check (:mod:`agents.config`)
both call it. Geometry that needs the built arena (do the robots fit?) is checked by the constructor
right after (:func:`swarm_envs.world.check_capacity` and the task's own layout check).

Errors: unknown keys raise ``TypeError`` (like any unknown keyword argument); bad values raise
:class:`SettingsError` (a ``ValueError``) whose ``key`` attribute names the setting.
"""

from __future__ import annotations

import math
import numbers
from typing import Any

from swarm_envs.comm.bch import SUPPORTED as BCH_CODES
from swarm_envs.comm.protocol import MAX_PAYLOAD
from swarm_envs.platforms import PLATFORMS, Platform, get_platform
from swarm_envs.registry import env_class

__all__ = ["COMMON_DEFAULTS", "SettingsError", "validate_settings", "task_class"]

#: Keyword arguments every task accepts, with their defaults (see README "Environments").
COMMON_DEFAULTS: dict[str, Any] = {
    "n_robots": 10,
    "platform": "epuck",
    "sensing": "full",
    "max_cycles": 500,
    "render_mode": None,
    "arena": "square",
    "arena_size": None,  # m; None = platform spacing * sqrt(number of robots)
    "reward_mode": "global",
    "flatten": False,
    "n_neighbours": 8,
    "n_messages": 8,
    "message_bits": 0,
    # SwarmCom messaging [T20]
    "bitrate": 310,
    "relative_threshold": None,  # m_tr (ADC counts); None = the platform's: 5 e-puck/r-one [T20], 8 droplet
    "code": (15, 15),
    "comm_mode": "broadcast",
    # range & bearing [F14]
    "rb_schedule": "contention",
    "rb_max_age": 10,
    "rb_noise": None,  # ADC counts; None = the platform model's documented default
    "rb_near_model": False,  # Droplet: firmware low-power fit instead of the power ladder when saturated
    # bearing-only sensing and scale-free coordinates [L]
    "bearing_source": None,  # None = "sectors" on rone, "range_bearing" elsewhere
    "bearing_noise": True,  # r-one sector readings with the measured receiver-arc spread [L Sec. 3.2.1]
    "exchange": "network",
    "scale_free_method": "two_hop",
    "scale_free_k": 1,
    "physics_substeps": 8,
}

_SHAPES = ("square", "circle")  # swarm_envs.world.Arena.SHAPES (not imported: world needs pymunk)

_CHOICES: dict[str, tuple] = {
    "sensing": ("full", "ideal"),
    "render_mode": (None, "rgb_array", "human"),
    "arena": _SHAPES,
    "reward_mode": ("global", "local"),
    "comm_mode": ("broadcast", "flooding"),
    "rb_schedule": ("contention", "every_step"),
    "bearing_source": (None, "sectors", "range_bearing"),
    "exchange": ("network", "ideal"),
    "scale_free_method": ("two_hop", "null_space"),
    "bitrate": (310, 650, 1080, 1160, 1670, 1800),
}
#: key -> (lowest allowed integer, highest or None)
_INTS: dict[str, tuple[int, int | None]] = {
    "n_robots": (1, None),
    "max_cycles": (1, None),
    "n_neighbours": (1, None),
    "n_messages": (1, None),
    "rb_max_age": (1, None),
    "scale_free_k": (1, None),
    "physics_substeps": (1, None),
    "message_bits": (0, MAX_PAYLOAD),  # the frame's length field [T20]
    "n_anchors": (3, None),  # CentroidSeeking: a polygon
}
#: key -> (description with unit, allow None, allow zero); every value must be a finite real, not a bool
_REALS: dict[str, tuple[str, bool, bool]] = {
    "arena_size": ("a positive number of metres", True, False),
    "relative_threshold": ("a positive number of ADC counts (m_tr)", True, False),
    "rb_noise": ("a non-negative number of ADC counts", True, True),
    "collision_penalty": ("a non-negative number", False, True),  # Flocking
}
_BOOLS = ("flatten", "rb_near_model", "bearing_noise")


class SettingsError(ValueError):
    """A bad env setting; ``key`` names it."""

    def __init__(self, key: str, message: str) -> None:
        super().__init__(message)
        self.key = key


def task_class(task: type | str) -> type:
    """The env class of ``task``: a class (returned as is) or a registered id such as
    ``"swarm_envs/Flocking-v0"``."""
    if isinstance(task, type):
        return task
    return env_class(task)


def _is_real(value: Any) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def _is_int(value: Any) -> bool:
    return isinstance(value, numbers.Integral) and not isinstance(value, bool)


def validate_settings(task: type | str, settings: dict[str, Any]) -> dict[str, Any]:
    """Check ``settings`` (keyword arguments) for ``task`` (env class or registered id) and return the
    resolved settings: every default filled in, ``code`` as a tuple. Raises ``TypeError`` for unknown keys
    and :class:`SettingsError` (``ValueError``) naming the key for a bad value."""
    cls = task_class(task)
    defaults = {**COMMON_DEFAULTS, **getattr(cls, "TASK_DEFAULTS", {})}
    if not isinstance(settings, dict):
        raise TypeError(f"settings must be a dict of keyword arguments, got {type(settings).__name__}")
    unknown = sorted(set(settings) - set(defaults), key=str)
    if unknown:
        raise TypeError(f"{cls.__name__} got unknown keyword argument(s) {unknown}; allowed: {sorted(defaults)}")
    cfg = {**defaults, **settings}

    for key, allowed in _CHOICES.items():
        value = cfg[key]
        try:
            ok = not isinstance(value, bool) and any(value is a if a is None else value == a for a in allowed)
        except (TypeError, ValueError):  # e.g. an array, whose comparison is not a bool
            ok = False
        if not ok:
            raise SettingsError(key, f"{key}={value!r} is not allowed; allowed values: {list(allowed)}")
    for key, (low, high) in _INTS.items():
        if key not in cfg:
            continue
        value = cfg[key]
        if not _is_int(value) or value < low or (high is not None and value > high):
            span = f">= {low}" if high is None else f"in [{low}, {high}]"
            why = " (the SwarmCom frame's length field)" if key == "message_bits" else ""
            raise SettingsError(key, f"{key} must be an integer {span}{why}, got {value!r}")
    for key, (what, allow_none, allow_zero) in _REALS.items():
        if key not in cfg:
            continue
        value = cfg[key]
        if value is None and allow_none:
            continue
        ok = _is_real(value) and math.isfinite(value) and (value >= 0 if allow_zero else value > 0)
        if not ok:
            raise SettingsError(key, f"{key} must be {what}{' or None' if allow_none else ''} (finite), got {value!r}")
    for key in _BOOLS:
        if not isinstance(cfg[key], bool):
            raise SettingsError(key, f"{key} must be True or False, got {cfg[key]!r}")

    platform = cfg["platform"]
    if not isinstance(platform, Platform) and (not isinstance(platform, str) or platform not in PLATFORMS):
        raise SettingsError("platform", f"unknown platform {platform!r}; allowed values: {sorted(PLATFORMS)}")
    platform = get_platform(platform)
    if cfg["rb_near_model"] and platform.name != "droplet":
        raise SettingsError("rb_near_model", "rb_near_model=True is the Droplet firmware's low-power fit; use platform='droplet'")
    if cfg["bearing_source"] == "range_bearing" and not hasattr(platform.ir_model, "amplitude_inverse"):
        raise SettingsError(
            "bearing_source", f"bearing_source='range_bearing' needs a range & bearing platform; {platform.name!r} has none (use 'sectors')"
        )

    code = cfg["code"]
    if not (isinstance(code, (tuple, list)) and len(code) == 2 and all(_is_int(c) for c in code)):
        raise SettingsError("code", f"code must be a BCH (n, k) pair of integers, one of {sorted(BCH_CODES)}; got {code!r}")
    code = (int(code[0]), int(code[1]))
    if code not in BCH_CODES:
        raise SettingsError("code", f"code={code!r} is not a supported BCH code; allowed values: {sorted(BCH_CODES)}")
    cfg["code"] = code
    return cfg
