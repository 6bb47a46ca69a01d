"""Settings of the swarm envs: one rule per setting, in one place, used by every entry point.

Every keyword argument of an env is a :class:`Setting`: a default and a rule (type, finiteness, range, and
an upper bound where a larger value would exhaust memory or time). :data:`COMMON_SETTINGS` holds the
settings every task takes; a task declares its own in ``Task.SETTINGS`` with the same classes
(:class:`Int`, :class:`Real`, :class:`Choice`, :class:`Flag`), or gives a common setting another default.
:func:`validate_settings` checks a task's keyword arguments up front -- whatever the ``sensing`` mode --
and returns them resolved: defaults filled in and every value in its canonical Python type (``int``,
``float``, ``bool``, a tuple for ``code``), so numpy scalars are accepted where a number is meant and
bools are refused. The envs, ``make_vec``, ``train.py``'s config check and the command-line tools all call
it, so a bad value fails when the env is built, never at ``reset`` or mid-training. Geometry that needs
the built arena (do the robots fit?) is checked by the task right after (:class:`swarm_envs.tasks.task.Task`).

Errors: unknown keys raise ``TypeError`` (like any unknown keyword argument); bad values raise
:class:`SettingsError` (a ``ValueError``) whose ``key`` attribute names the setting.

Every bound has a reason (the rule's ``why``); :func:`settings_table` lists the rules with their reasons
(the table of ``docs/settings.md``, checked against this module by the tests).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Any, Literal

import numpy as np

from swarm_envs._text import shown
from swarm_envs.comm.bch import SUPPORTED as BCH_CODES
from swarm_envs.comm.protocol import MAX_PAYLOAD
from swarm_envs.sensing.stacks import SENSING_STACKS
from swarm_envs.sim.platforms import PLATFORMS, Platform, get_platform
from swarm_envs.sim.control import MAX_CLOSING, MAX_SUBSTEPS, default_substeps, min_substeps

__all__ = ["Setting", "Int", "Real", "reward_weight", "Choice", "Flag", "Default", "COMMON_SETTINGS", "COMMON_DEFAULTS", "MAX_ROBOTS", "SettingsError", "validate_settings", "task_settings", "ordered_settings"]

#: Robots (agents and static robots) of one env copy at most: the IR layer's work and memory grow with
#: robots x neighbours, and 10,000 robots already take minutes per episode.
MAX_ROBOTS = 10_000


class SettingsError(ValueError):
    """A bad env setting; ``key`` names it."""

    def __init__(self, key: str, message: str) -> None:
        super().__init__(message)
        self.key = key


def _is_int(value: Any) -> bool:
    return isinstance(value, numbers.Integral) and not isinstance(value, bool)


def _is_real(value: Any) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


@dataclass(frozen=True)
class Setting:
    """A keyword argument: its default and its rule. Subclasses implement :meth:`check`.

    Attributes:
        default: the value when the keyword is not given.
        doc: what the value means (shown in error messages).
        why: the reason for the rule's bounds (shown in the settings table of the docs).
        help: what the argument means (the ``meaning`` column of an env factory's arguments table,
            :func:`arguments_table`); keyword-only.
    """

    default: Any
    doc: str = ""
    why: str = ""
    help: str = field(default="", kw_only=True)

    def check(self, key: str, value: Any) -> Any:
        """``value`` in its canonical type, or :class:`SettingsError` naming ``key``."""
        return value

    def rule(self) -> str:
        """The rule in words (for error messages and docs)."""
        return "any value"

    def annotation(self) -> Any:
        """The type hint of the keyword argument (an env factory's signature)."""
        return Any


@dataclass(frozen=True)
class Int(Setting):
    """An integer in ``[low, high]`` (numpy integers accepted; bools and floats refused), or None when allowed."""

    low: int = 0
    high: int | None = None
    allow_none: bool = False

    def rule(self) -> str:
        span = f"an integer >= {self.low}" if self.high is None else f"an integer in [{self.low}, {self.high}]"
        return span + (" or None" if self.allow_none else "")

    def annotation(self) -> Any:
        return int | None if self.allow_none else int

    def check(self, key: str, value: Any) -> int | None:
        if value is None and self.allow_none:
            return None
        if not _is_int(value) or value < self.low or (self.high is not None and value > self.high):
            raise SettingsError(key, f"{key} must be {self.rule()}{self.doc and ' (' + self.doc + ')'}, got {shown(value)}")
        return int(value)


@dataclass(frozen=True)
class Real(Setting):
    """A finite real number in ``[low, high]`` (``(low, high]`` when ``low_open``), or None when allowed.

    Integers, numpy scalars and fractions are accepted and returned as ``float``; bools, NaN and inf are
    refused."""

    low: float = 0.0
    high: float = math.inf
    low_open: bool = False
    allow_none: bool = False
    unit: str = ""

    def rule(self) -> str:
        low = f"> {self.low:g}" if self.low_open else f">= {self.low:g}"
        span = low if math.isinf(self.high) else f"{low} and <= {self.high:g}"
        unit = f" {self.unit}" if self.unit else ""
        return f"a finite number{unit} {span}" + (" or None" if self.allow_none else "")

    def annotation(self) -> Any:
        return float | None if self.allow_none else float

    def check(self, key: str, value: Any) -> float | None:
        if value is None and self.allow_none:
            return None
        ok = _is_real(value)
        if ok:
            try:
                number = float(value)
            except (OverflowError, ValueError):  # e.g. a Fraction or int too large for a float
                ok = False
        if ok:
            above = number > self.low if self.low_open else number >= self.low
            ok = math.isfinite(number) and above and number <= self.high
        if not ok:
            raise SettingsError(key, f"{key} must be {self.rule()}{self.doc and ' (' + self.doc + ')'}, got {shown(value)}")
        return number


def reward_weight(default: float, doc: str, help: str = "") -> Real:
    """A reward weight setting of a task: a finite number in [0, 1000], so rewards stay within +-1000 per step."""
    return Real(default, doc, low=0.0, high=1000.0, why="a reward weight; rewards stay within +-1000 per step", help=help)


@dataclass(frozen=True)
class Choice(Setting):
    """One of ``choices`` (compared by value; a bool never matches a number)."""

    choices: tuple = ()

    def rule(self) -> str:
        return f"one of {list(self.choices)}"

    def annotation(self) -> Any:
        values = tuple(c for c in self.choices if c is not None)
        hint = Literal[values] if values else type(None)
        return hint | None if None in self.choices and values else hint

    def check(self, key: str, value: Any) -> Any:
        for allowed in self.choices:
            if allowed is None:
                if value is None:
                    return None
                continue
            if isinstance(value, bool) != isinstance(allowed, bool) or not isinstance(value, (str, numbers.Number)):
                continue
            try:
                if type(allowed)(value) == allowed and value == allowed:
                    return allowed
            except (TypeError, ValueError, OverflowError):  # e.g. an array or a string for a number
                continue
        raise SettingsError(key, f"{key}={shown(value)} is not allowed; allowed values: {list(self.choices)}")


@dataclass(frozen=True)
class Flag(Setting):
    """True or False (numpy bools accepted; numbers refused)."""

    def rule(self) -> str:
        return "True or False"

    def annotation(self) -> Any:
        return bool

    def check(self, key: str, value: Any) -> bool:
        if isinstance(value, (bool, np.bool_)):  # np.bool_ is named "bool" under numpy 2, "bool_" before
            return bool(value)
        raise SettingsError(key, f"{key} must be True or False, got {shown(value)}")


@dataclass(frozen=True)
class _PlatformSetting(Setting):
    def rule(self) -> str:
        return f"one of {sorted(PLATFORMS)} or a swarm_envs.Platform"

    def annotation(self) -> Any:
        return Literal[tuple(sorted(PLATFORMS))] | Platform

    def check(self, key: str, value: Any) -> str | Platform:
        if isinstance(value, str) and value in PLATFORMS:
            return value
        if not isinstance(value, Platform):
            raise SettingsError(key, f"unknown platform {shown(value)}; allowed values: {sorted(PLATFORMS)} or a swarm_envs.Platform")
        # its fields were checked when it was made (Platform.__post_init__); here what the physics can take
        if default_substeps(value) > MAX_SUBSTEPS:
            raise SettingsError(
                key,
                f"platform {value.name!r} is too fast for its size: max_speed={value.max_speed:g} m/s with radius "
                f"{value.radius:g} m needs {default_substeps(value)} physics sub-steps per control step, at most {MAX_SUBSTEPS}",
            )
        return value


@dataclass(frozen=True)
class _CodeSetting(Setting):
    def rule(self) -> str:
        return f"a BCH (n, k) pair, one of {sorted(BCH_CODES)}"

    def annotation(self) -> Any:
        return tuple[int, int]

    def check(self, key: str, value: Any) -> tuple[int, int]:
        if not (isinstance(value, (tuple, list)) and len(value) == 2 and all(_is_int(c) for c in value)):
            raise SettingsError(key, f"code must be a BCH (n, k) pair of integers, one of {sorted(BCH_CODES)}; got {shown(value)}")
        code = (int(value[0]), int(value[1]))
        if code not in BCH_CODES:
            raise SettingsError(key, f"code={shown(code)} is not a supported BCH code; allowed values: {sorted(BCH_CODES)}")
        return code


#: The settings every task takes (defaults and rules). The bounds are hard limits, not advice; each
#: rule's ``why`` states the reason for its bounds.
COMMON_SETTINGS: dict[str, Setting] = {
    "n_robots": Int(
        10, "agents per env copy", low=1, high=MAX_ROBOTS,
        why=f"agents and static robots of one copy together at most {MAX_ROBOTS:,}: the IR layer's work and memory grow with "
        "robots x neighbours, and 10,000 robots already take 1.0 s per step with ideal sensing (one make_vec copy of "
        "aggregation, median of 5 steps, 2 cores at load 6)",
        help="number of agents",
    ),
    "platform": _PlatformSetting(
        "epuck", why="a custom Platform's fields are checked when it is made (swarm_envs.sim.platforms); here also "
        f"that its speed and size need at most {MAX_SUBSTEPS} physics sub-steps",
        help='``"droplet"`` (4.4 cm, 6 IR channels), ``"epuck"`` (7 cm, 8 sensors), ``"rone"`` (11 cm, 8 RX + 8 TX), or a ``Platform``',
    ),
    "sensing": Choice("full", choices=tuple(SENSING_STACKS), help='``"full"``: the modelled IR stack; ``"ideal"``: exact, noiseless, lossless values (true ids with ``observe_ids``) in the same layout'),
    "max_cycles": Int(
        500, "control steps of 0.1 s per episode", low=1, high=10**9,
        why="10^9 steps are 3.2 years of simulated time; episode memory grows with the steps taken, never with this bound",
        help="control steps of 0.1 s per episode",
    ),
    "render_mode": Choice(None, choices=(None, "rgb_array", "human"), help='``"rgb_array"`` (headless) or ``"human"`` (window)'),
    "arena": Choice("square", choices=("square", "circle"), help='``"square"`` or ``"circle"``'),
    "arena_size": Real(
        None, low=0.0, low_open=True, high=10_000.0, allow_none=True, unit="of metres",
        why="None: the platform's spacing x sqrt(robots), at most 45 m; above 10 km an arena only adds empty space "
        "(float64 positions still resolve 2e-12 m there). Whether the robots fit is checked when the env is built",
        help="side or diameter (m); ``None``: the platform's spacing x sqrt(robots)",
    ),
    "reward_mode": Choice("global", choices=("global", "local"), help='``"global"`` (one team reward) or ``"local"`` (each robot its own term)'),
    "flatten": Flag(False, help="one flat ``Box`` observation instead of the ``Dict``"),
    "n_neighbours": Int(
        8, "observation rows", low=1, high=256,
        why="rows of range & bearing and scale-free coordinates per agent; memory grows with robots x rows",
        help="rows K of ``range_bearing`` and ``scale_free``",
    ),
    "n_messages": Int(8, "observation rows", low=1, high=256, why="rows of decoded messages per agent; memory grows with robots x rows", help="rows M of ``messages``"),
    "message_bits": Int(
        0, "the SwarmCom frame's length field", low=0, high=MAX_PAYLOAD,
        why=f"the SwarmCom frame's 8-bit length field counts at most {MAX_PAYLOAD} payload bits (swarm_envs.comm.protocol)",
        help="payload bits b an agent sends through its action (0: no message action)",
    ),
    # the robot's own id and the neighbour / sender ids its sensing decoded (swarm_envs.sensing.observation)
    "observe_ids": Flag(False, help="the robot's own id and the neighbour and sender ids its sensing decoded (``own_id``, ``*_ids`` parts)"),
    # SwarmCom messaging [T20]
    "bitrate": Choice(
        None, choices=(None, 310, 650, 1080, 1160, 1250, 1670, 1800),
        why="None: the platform's rate (e-puck 310, r-one 1250, Droplet 310; Platform.ir_bitrate); the rates measured "
        "in [T20] and the r-one's 1250 bps [L Sec. 3.2.1]",
        help="SwarmCom bit rate (bps): ``None`` the platform's (e-puck 310 [T20], r-one 1250 [L Sec. 3.2.1], Droplet 310), or 310, 650, 1080, 1160, 1250, 1670, 1800",
    ),
    # m_tr (ADC counts); None = the platform's: 5 e-puck/r-one [T20], 8 droplet.
    "relative_threshold": Real(
        None, low=0.0, low_open=True, high=3930.0, allow_none=True, unit="of ADC counts (m_tr)",
        why="None: 5 counts on the e-puck and r-one [T20], 8 on the Droplet; at most the detector's full swing "
        "m_max - m_min = 4080 - 150 counts [T20 Eqs. (15)-(22)]",
        help="detector threshold m_tr (ADC counts); ``None``: 5 on e-puck and r-one [T20], 8 on the Droplet",
    ),
    "code": _CodeSetting((15, 15), why="the BCH codes SwarmCom implements [T20 Sec. 4.3]", help="BCH code (n, k): ``(15, 15)`` uncoded, ``(15, 11)``, ``(15, 7)``, ``(15, 5)``, ``(15, 1)``"),
    "comm_mode": Choice("broadcast", choices=("broadcast", "flooding"), help='``"broadcast"`` or ``"flooding"`` [T20 Sec. 5]'),
    # range & bearing [F14]
    "rb_schedule": Choice(
        "timer", choices=("timer", "contention", "every_step"),
        why="timer: each robot fires on its own timer, as the Droplet firmware; contention: an oracle that never lets two "
        "linked robots fire together (ablation); every_step: every robot every step, each measured alone (idealised)",
        help='range & bearing firing: ``"timer"`` (each robot on its own timer, as the Droplet firmware: robots that see each other can collide), ``"contention"`` (oracle ablation: no two linked robots fire in one step) or ``"every_step"`` (idealised)',
    ),
    "rb_period": Real(
        1.0, low=0.1, high=3600.0, unit="of seconds",
        why="1 s: the Droplet example application's R&B timer; at least one 0.1 s control step (a robot fires at most "
        "once per step); an hour is far beyond any firmware timer",
        help='s between a robot\'s range & bearing firings (``"timer"``)',
    ),
    "rb_jitter": Real(
        0.2, low=0.0, high=3600.0, unit="of seconds",
        why="largest late start of a firing after its timer expires (uniform), ~0.19 s: an R&B measurement blocks the "
        "Droplet's main loop that polls the timer (an assumption); at most an hour, like the period",
        help="s, largest late start of a firing after its timer expires (uniform)",
    ),
    "rb_max_age": Int(
        None, "steps a reading persists", low=1, high=100_000, allow_none=True,
        why="None: until the neighbour's next firing is due at its latest (ceil((rb_period + rb_jitter) / 0.1 s) + 1 "
        "steps under the timer schedule, 13 at the defaults; 10 under the others); 100,000 steps are 2.8 h of "
        "simulated time, far longer than a reading of a moving robot means anything",
        help="steps a range & bearing reading persists; ``None``: until the neighbour's next timer firing is due (13 at the defaults)",
    ),
    "rb_noise": Real(
        None, low=0.0, high=1000.0, allow_none=True, unit="of ADC counts",
        why="None: 2 counts on the Droplet, sqrt(2.5) on the e-puck; 1,000 counts exceed the Droplet's 8-bit "
        "ADC range (255) and a quarter of the e-puck's, so every reading is noise",
        help="ADC noise sigma (counts); ``None``: 2 on the Droplet, sqrt(2.5) on the e-puck",
    ),
    "rb_near_model": Flag(False, help="Droplet only: the firmware's low-power near-range fit instead of the power ladder"),
    # per-robot hardware variation of the IR channels (docs/design.md#hardware-variation); no paper gives the spreads
    "hw_variation": Flag(True, why="each robot's emitters and detectors differ from the nominal platform [F14 Sec. VI]; droplet and epuck", help="droplet / epuck: each robot's emitter powers, detector gains and axis angles drawn at reset (the range & bearing estimator keeps the nominal calibration)"),
    "hw_emitter_spread": Real(
        0.1, "standard deviation of ln(emitter power multiplier)", low=0.0, high=1.0,
        why="standard deviation of each emitter's log power multiplier (an assumption); at 1.0 two sigmas span a "
        "factor e^4 = 55, beyond any working LED",
        help="standard deviation of ln(emitter power multiplier) (an assumption)",
    ),
    "hw_detector_spread": Real(
        0.1, "standard deviation of ln(detector gain multiplier)", low=0.0, high=1.0,
        why="standard deviation of each detector's log gain multiplier (an assumption); at 1.0 two sigmas span a "
        "factor e^4 = 55, beyond any working detector",
        help="standard deviation of ln(detector gain multiplier) (an assumption)",
    ),
    "hw_angle_spread": Real(
        3.0, "standard deviation of each axis angle", low=0.0, high=30.0, unit="of degrees",
        why="standard deviation of each emitter's and detector's axis angle (an assumption); 30 degrees is half the "
        "Droplet's 60-degree channel spacing, where neighbouring channels would swap",
        help="degrees, standard deviation of each emitter's and detector's axis angle (an assumption)",
    ),
    # bearing-only sensing and scale-free coordinates [L]
    "bearing_source": Choice(None, choices=(None, "sectors", "range_bearing"), help='``"sectors"`` (r-one) or ``"range_bearing"``; ``None``: sectors on the r-one, R&B elsewhere'),
    "bearing_noise": Flag(True, help="r-one: sector readings with each robot's own receiver arcs, drawn at reset from the measured 63-74 degree spread, mean 68 [L Sec. 3.2.1]"),
    "exchange": Choice("network", choices=("network", "ideal"), help='bearing lists for scale-free coordinates over SwarmCom (``"network"``) or ``"ideal"``'),
    "scale_free_method": Choice("two_hop", choices=("two_hop", "null_space"), help='``"two_hop"`` [L Algs. 1-4] or ``"null_space"`` [L Eq. (5.1)] (slow)'),
    "scale_free_k": Int(1, "hops of the null-space method", low=1, high=4, why="a robot's k-hop neighbourhood, and the null-space method's work, grow with degree^k", help="hops k of the null-space method"),
    # the platform's motion error (per-wheel gains, per-step noise, dead zone; docs/design.md#motion-error)
    "motion_noise": Flag(True, help="the platform's motion error: per-wheel speed gains drawn per episode, per-step wheel-speed noise, the r-one's 15 mm/s dead zone [L Sec. 3.1] (``docs/design.md#motion-error``); ``False``: exact differential-drive kinematics"),
    "physics_substeps": Int(
        None, "pymunk sub-steps per control step", low=1, high=MAX_SUBSTEPS, allow_none=True,
        why="None: the platform's default (8 Droplet, 21 e-puck, 32 r-one; swarm_envs.sim.control.default_substeps), at "
        "which robots overlap each other, and reach past a wall, by at most 2 % of a diameter at the default arena size, also when driven "
        "at full speed into each other and into the walls; at least the platform's minimum (3 Droplet, 8 e-puck, "
        f"11 r-one; fewer let robots close more than 5 % of a diameter per sub-step, or leave their arcs); at most {MAX_SUBSTEPS} "
        "(the cost grows linearly: 1,000 sub-steps of 10 robots take ~5 ms per step)",
        help="pymunk sub-steps per control step; ``None``: the platform's (8 Droplet, 21 e-puck, 32 r-one), at which robots overlap by at most 2 % of a diameter at the default arena size",
    ),
}


@dataclass(frozen=True)
class Default:
    """A task's default for a common setting (``Task.SETTINGS = {"n_robots": Default(5, help=...)}``), with
    what the argument means for this task (``help``; empty: the common setting's). A plain value
    (``{"n_robots": 5}``) gives only the default."""

    value: Any
    help: str = ""


#: The default of every common setting.
COMMON_DEFAULTS: dict[str, Any] = {key: s.default for key, s in COMMON_SETTINGS.items()}


def task_settings(own: Mapping[str, Any], owner: str = "task") -> dict[str, Setting]:
    """The settings a task declares in ``own`` (``Task.SETTINGS``), resolved against the common ones:
    a :class:`Setting` declares a setting (or replaces a common rule); a plain value or a :class:`Default`
    gives a common setting another default (checked against its rule). ``TypeError`` for a plain value of
    a new name."""
    out: dict[str, Setting] = {}
    for key, value in own.items():
        if not isinstance(key, str) or not key.isidentifier():
            raise TypeError(f"{owner}: setting names must be identifiers, got {key!r}")
        if isinstance(value, Setting):
            setting = value
        elif key in COMMON_SETTINGS and isinstance(value, Default):
            common = COMMON_SETTINGS[key]
            setting = replace(common, default=value.value, help=value.help or common.help)
        elif key in COMMON_SETTINGS:
            setting = replace(COMMON_SETTINGS[key], default=value)
        else:
            raise TypeError(
                f"{owner}: the new setting {key!r} needs a rule: declare it as Int(...), Real(...), Choice(...) "
                "or Flag(...) from swarm_envs.tasks.task"
            )
        try:
            setting.check(key, setting.default)
        except SettingsError as err:
            raise TypeError(f"{owner}: the default of {key!r} breaks its own rule: {err}") from None
        out[key] = setting
    return out


def validate_settings(task: Any, settings: Mapping[str, Any]) -> dict[str, Any]:
    """Check ``settings`` (keyword arguments) for ``task`` (a ``Task`` subclass, or an env class whose
    ``TASK`` it is; for a registered id use ``swarm_envs.registry.task_class(id)``) and return the resolved
    settings: every default filled in, every value in its canonical type.

    Raises ``TypeError`` for unknown keys and :class:`SettingsError` (``ValueError``) naming the key for a
    bad value."""
    cls = getattr(task, "TASK", task)
    if not callable(getattr(cls, "settings", None)):
        raise TypeError(f"validate_settings needs a swarm_envs.tasks.task.Task subclass or an env class, got {task!r:.80}")
    rules = {**COMMON_SETTINGS, **cls.settings()}
    if not isinstance(settings, Mapping):
        raise TypeError(f"settings must be a dict of keyword arguments, got {type(settings).__name__}")
    unknown = sorted((k for k in settings if k not in rules), key=str)
    if unknown:
        raise TypeError(f"{cls.__name__} got unknown keyword argument(s) {unknown}; allowed: {sorted(rules)}")
    cfg = {key: rule.check(key, settings[key]) if key in settings else rule.default for key, rule in rules.items()}

    platform = get_platform(cfg["platform"])
    substeps = cfg["physics_substeps"]
    if substeps is not None and substeps < min_substeps(platform):
        raise SettingsError(
            "physics_substeps",
            f"physics_substeps={substeps} is too few for platform {platform.name!r}: at least {min_substeps(platform)} "
            f"(fewer let two robots close more than {MAX_CLOSING:.0%} of a diameter per sub-step; None: its default {default_substeps(platform)})",
        )
    if cfg["rb_near_model"] and platform.name != "droplet":
        raise SettingsError("rb_near_model", "rb_near_model=True is the Droplet firmware's low-power fit; use platform='droplet'")
    if cfg["bearing_source"] == "range_bearing" and not hasattr(platform.ir_model, "amplitude_inverse"):
        raise SettingsError(
            "bearing_source", f"bearing_source='range_bearing' needs a range & bearing platform; {platform.name!r} has none (use 'sectors')"
        )
    return cfg


def ordered_settings(settings: Mapping[str, Setting]) -> dict[str, Setting]:
    """A task's keyword arguments in the order its factory takes them: ``n_robots``, the task's own
    settings (declaration order), then the other common settings. ``settings`` are the task's own
    (``Task.settings()``), resolved against :data:`COMMON_SETTINGS`."""
    rules = {**COMMON_SETTINGS, **settings}
    own = [key for key in settings if key not in COMMON_SETTINGS]
    order = ["n_robots", *own, *(key for key in COMMON_SETTINGS if key != "n_robots")]
    return {key: rules[key] for key in order}


