"""Scripted swarm behaviours from the papers, batched over robots, reading observations by name only.

Every controller implements :class:`agents.base.Policy` and works the same with ``sensing="full"`` and
``sensing="ideal"`` (the observation layout is shared). None reads ``infos`` or ground truth.

- :class:`RandomWalk` - [T20] Alg. 1: rotate by a random angle theta in (-pi, pi], then drive with a random
  velocity v in [-v_max, v_max] (the e-puck's +-128 mm/s) for t_m = 2 s; repeat.
- :class:`OrientationFlocking` - [L] Sec. 6.4.1, Alg. 5: average the neighbours' orientations (headings from
  ``range_bearing``), steer to that heading at a fixed forward speed; on a bump stop and turn away
  (``heading = theta_u + pi``).
- :class:`ReynoldsFlocking` - Reynolds (1987) alignment + cohesion + separation from the ``range_bearing``
  rows (alignment alone is Alg. 5; [L] Sec. 6.4.3 suggests adding clustering to it); bump -> turn away.
- :class:`BearingAggregation` - [L] Sec. 6.4.3, Alg. 7 generalised to one cluster (every robot is in the same
  "even/odd" group): steer towards the average neighbour bearing at a fixed speed; bump -> turn away.
- :class:`CentroidSeeker` - [L] Sec. 6.2.2: pause, take the centroid of the scale-free neighbour coordinates,
  turn to its bearing and drive a fixed ``d_step`` (11 cm in the thesis) towards it; repeat.
- :class:`SortedFollowing` - [L] Sec. 6.4.2, Alg. 6: a robot follows (steers to the bearing of) a neighbour
  whose decoded id is lower than its own; the lowest id leads, driving straight and avoiding obstacles.
- :class:`ParityClustering` - [L] Sec. 6.4.3, Alg. 7: steer towards the average bearing of the neighbours
  whose decoded id has the robot's parity; bump -> turn away; it never stops.
- :class:`MidAngleNavigation` - [L] Sec. 6.4.4, Alg. 8: a seeker steers to the goal robot when it senses it,
  else through the mid-angle of two neighbours with the lowest hop count to the goal (heard in their
  messages).

The last three (:mod:`swarm_envs.agents.thesis_behaviours`) read the ids the robots' sensing decoded (the env's
``observe_ids=True``: ``own_id``, ``range_bearing_ids``, ``message_ids``), never a true id. The state and
helpers all controllers share are in :mod:`swarm_envs.agents.scripted_base`; this module holds the others, the
registry of controllers by name and their argument rules.

Speeds are fractions of the platform maximum (the thesis' 20 mm/s is 0.067 of the r-one's 0.30 m/s; the
defaults here are faster so that 20-50 s episodes show the behaviour; every speed is a constructor argument).
Where an algorithm is undefined (no neighbour in range) the robot falls back to the random walk, which
the thesis leaves open (the r-one "keeps its last pose").
"""

from __future__ import annotations

import importlib
import inspect

import numpy as np

from swarm_envs.agents.base import Policy
from swarm_envs.adapters.env import DT
from swarm_envs.sensing.observation import ObservationLayout
from swarm_envs.sim.platforms import Platform
from swarm_envs.tasks.settings import Choice, Flag, Int, Real, Setting, SettingsError
from swarm_envs.agents.scripted_base import ScriptedPolicy, bump_direction, circular_mean, decoded_ids
from swarm_envs.agents.thesis_behaviours import MidAngleNavigation, ParityClustering, SortedFollowing

__all__ = [
    "RandomWalk",
    "OrientationFlocking",
    "ReynoldsFlocking",
    "BearingAggregation",
    "CentroidSeeker",
    "SortedFollowing",  # the thesis behaviours (swarm_envs.agents.thesis_behaviours), by name here
    "ParityClustering",
    "MidAngleNavigation",
    "decoded_ids",  # helpers of swarm_envs.agents.scripted_base
    "SCRIPTED",
    "scripted_class",
    "check_scripted_kwargs",
    "make_scripted",
    "circular_mean",
    "bump_direction",
]


class RandomWalk(ScriptedPolicy):
    """[T20] Alg. 1 random walk (rotate by theta ~ U(-pi, pi], drive v ~ U[-v_max, v_max] for t_m = 2 s)."""

    name = "random_walk"

    def act_batch(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        n = len(obs["proprio"])
        self._ensure(n)
        lin, ang = self._random_walk(np.ones(n, dtype=bool))
        return self.compose(lin, ang)


class OrientationFlocking(ScriptedPolicy):
    """[L] Alg. 5: ``psi_avg = average(psi(v), v in N(u))``; ``PoseSet(tv, heading = psi_avg)``; bump -> turn away.

    Neighbour orientations are the ``cos/sin heading`` columns of ``range_bearing`` (relative to the robot,
    so the robot's own heading is 0). ``speed`` is the forward speed (fraction of max), ``gain`` the
    fraction of the heading error corrected per step. Defaults (speed 1.0, gain 0.2) were picked on
    ``sensing="full"``, whose heading estimates are noisy: polarisation 0.40 vs 0.21 with (0.6, 0.5) over
    6 seeds of 200 steps (ideal sensing: 0.57).
    """

    name = "orientation_flocking"

    def __init__(self, platform: Platform, layout: ObservationLayout, rng: np.random.Generator | None = None,
                 speed: float = 1.0, gain: float = 0.2, t_m: float = 2.0) -> None:
        self.speed, self.gain = float(speed), float(gain)
        super().__init__(platform, layout, rng, t_m)

    def act_batch(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        rb = obs["range_bearing"]
        n = len(rb)
        self._ensure(n)
        psi, has = circular_mean(rb[..., 4], rb[..., 5], rb[..., 0] > 0.5)
        lin = np.full(n, self.speed)
        ang = np.where(has, self.turn_towards(psi, self.gain), 0.0)
        escaping, e_lin, e_ang = self._bump_escape(obs["proprio"])
        lin, ang = np.where(escaping, e_lin, lin), np.where(escaping, e_ang, ang)
        return self.compose(lin, ang)


class ReynoldsFlocking(ScriptedPolicy):
    """Alignment + cohesion + separation (Reynolds 1987, "Flocks, herds and schools") on the robot's own
    ``range_bearing`` rows; bump -> turn away as [L] Alg. 5.

    [L] Alg. 5 (:class:`OrientationFlocking`) is the alignment rule alone; of its clustering (steering to the
    neighbours' bearings, Alg. 7) [L] Sec. 6.4.3 says that "clustering with angle-only flocking has the
    potential to enhance flocking on the r-one".
    Here each robot steers, at a fixed forward speed ``speed``, to the direction of

    ``align_weight x a + cohesion_weight x c + separation_weight x s``

    (body frame): ``a`` the mean of the neighbours' heading unit vectors (length 1 when they agree, ~0 when
    they do not); ``c`` the mean neighbour position (range x bearing unit vector; the bearing alone where a
    platform measures no range, the r-one) divided by ``cohesion_range`` metres and clipped to length 1;
    ``s`` the sum over neighbours closer than ``separation`` metres of ``-(1 - range / separation)`` times
    their bearing unit vector (none without range). ``gain`` is the fraction of the heading error corrected
    per step. ``odometry`` (default on) turns each reading's bearing and relative heading back by the
    robot's own rotation since the reading was measured (its ``age``; the Droplet refreshes a neighbour
    about once a second). No neighbour in range -> drive straight on. Ranges in metres; ``None`` distances
    scale with the platform: ``separation`` 3 body diameters, ``cohesion_range`` half the IR range.
    The default weights (3, 0.5, 2) were picked on 16 Droplets in a 1 m arena, ``sensing="full"``, 90 s,
    seeds 0-9, from a grid of align 1-4, cohesion 0.25-1, separation 0.5-4: polarisation 0.65 and cohesion
    0.73, against 0.59 and 0.63 for :class:`OrientationFlocking` (weights 1, 1, 1: 0.48 and 0.88); on the
    held-out seeds 10-29, 0.60 and 0.73 against 0.56 and 0.62.
    """

    name = "reynolds_flocking"

    def __init__(self, platform: Platform, layout: ObservationLayout, rng: np.random.Generator | None = None,
                 speed: float = 1.0, gain: float = 0.2, align_weight: float = 3.0, cohesion_weight: float = 0.5,
                 separation_weight: float = 2.0, separation: float | None = None, cohesion_range: float | None = None,
                 odometry: bool = True, t_m: float = 2.0) -> None:
        self.speed, self.gain = float(speed), float(gain)
        self.align_weight, self.cohesion_weight = float(align_weight), float(cohesion_weight)
        self.separation_weight = float(separation_weight)
        self.separation = 3.0 * platform.diameter if separation is None else float(separation)
        self.cohesion_range = 0.5 * platform.ir_range if cohesion_range is None else float(cohesion_range)
        if self.cohesion_range <= 0:
            raise ValueError(f"cohesion_range must be > 0 m, got {self.cohesion_range}")
        self.odometry = bool(odometry)
        super().__init__(platform, layout, rng, t_m)

    def steering(self, obs: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        """The desired direction (rad, body frame) per robot, and whether it has one (a neighbour in range
        and a non-zero resultant). Call once per step (the odometry keeps the robot's recent rotation)."""
        rb = obs["range_bearing"]
        valid = rb[..., 0] > 0.5
        w = valid.astype(np.float64)
        count = np.maximum(w.sum(axis=1), 1.0)
        if self.odometry:
            since = self._rotation_since(obs)
            bearing = self._current_bearings(rb, since)
            age = np.clip(np.rint(rb[..., 6]).astype(np.int64), 0, since.shape[1] - 1)
            heading = np.arctan2(rb[..., 5], rb[..., 4]) - np.take_along_axis(since, age, axis=1)
        else:
            bearing, heading = np.arctan2(rb[..., 3], rb[..., 2]), np.arctan2(rb[..., 5], rb[..., 4])
        ub = np.stack([np.cos(bearing), np.sin(bearing)], axis=-1)  # (N, K, 2)
        align = (np.stack([np.cos(heading), np.sin(heading)], axis=-1) * w[..., None]).sum(axis=1) / count[:, None]
        ranged = rb[..., 1] > 0
        dist = np.where(ranged, rb[..., 1], 1.0)  # no range (r-one): the bearing alone
        centre = (ub * (dist * w)[..., None]).sum(axis=1) / count[:, None]
        centre = centre / np.where(ranged.any(axis=1), self.cohesion_range, 1.0)[:, None]
        centre = centre / np.maximum(1.0, np.linalg.norm(centre, axis=1))[:, None]
        push = np.where(valid & ranged, np.clip(1.0 - rb[..., 1] / self.separation, 0.0, 1.0), 0.0) if self.separation > 0 else np.zeros_like(w)
        apart = -(ub * push[..., None]).sum(axis=1)
        total = self.align_weight * align + self.cohesion_weight * centre + self.separation_weight * apart
        has = valid.any(axis=1) & (np.linalg.norm(total, axis=1) > 1e-9)
        return np.where(has, np.arctan2(total[:, 1], total[:, 0]), 0.0), has

    def act_batch(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        n = len(obs["range_bearing"])
        self._ensure(n)
        theta, has = self.steering(obs)
        lin = np.full(n, self.speed)
        ang = np.where(has, self.turn_towards(theta, self.gain), 0.0)
        escaping, e_lin, e_ang = self._bump_escape(obs["proprio"])
        lin, ang = np.where(escaping, e_lin, lin), np.where(escaping, e_ang, ang)
        return self.compose(lin, ang)


class BearingAggregation(ScriptedPolicy):
    """[L] Alg. 7 with one group: ``theta_avg = average(theta(v))``; ``PoseSet(tv, heading = theta_avg)``.

    Bump -> turn away as in the thesis (``turn_away_on_bump=True``); with ``False`` the robot instead stops
    driving while its front half is in contact (it has reached the cluster). The thesis notes clustering
    has no stopping condition without range; where ``range_bearing`` carries ranges (R&B platforms) the
    robot stops driving when its nearest neighbour is closer than ``stop_range`` metres (0 disables).
    No neighbour in range -> random walk ([T20] Alg. 1) to find one.
    """

    name = "bearing_aggregation"

    def __init__(self, platform: Platform, layout: ObservationLayout, rng: np.random.Generator | None = None,
                 speed: float = 0.8, gain: float = 0.5, turn_away_on_bump: bool = True, stop_range: float = 0.0,
                 t_m: float = 2.0) -> None:
        self.speed, self.gain = float(speed), float(gain)
        self.turn_away_on_bump, self.stop_range = bool(turn_away_on_bump), float(stop_range)
        super().__init__(platform, layout, rng, t_m)

    def act_batch(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        rb = obs["range_bearing"]
        n = len(rb)
        self._ensure(n)
        valid = rb[..., 0] > 0.5
        theta, has = circular_mean(rb[..., 2], rb[..., 3], valid)
        lin = np.full(n, self.speed)
        ang = self.turn_towards(theta, self.gain)
        if self.stop_range > 0:
            ranges = np.where(valid & (rb[..., 1] > 0), rb[..., 1], np.inf)
            lin = np.where(ranges.min(axis=1) < self.stop_range, 0.0, lin)
        if self.turn_away_on_bump:
            escaping, e_lin, e_ang = self._bump_escape(obs["proprio"])
            lin, ang = np.where(escaping, e_lin, lin), np.where(escaping, e_ang, ang)
        else:
            direction, bumped = bump_direction(obs["proprio"])
            front = bumped & (np.cos(direction) > 0)
            lin = np.where(front, 0.0, lin)
        rw_lin, rw_ang = self._random_walk(~has)
        lin, ang = np.where(has, lin, rw_lin), np.where(has, ang, rw_ang)
        return self.compose(lin, ang)


class CentroidSeeker(ScriptedPolicy):
    """[L] Sec. 6.2.2 centroid controller, one step of ``d_step`` per sensing round.

    Cycle per robot: pause (the thesis's robot pauses for each neighbour round) -> read the centroid of the valid ``scale_free`` neighbour coordinates (the robot's own frame, scaled so
    the mean neighbour distance is 1; only the direction is used) -> turn in place to its bearing ->
    drive ``d_step`` metres (11 cm in the thesis) at ``speed`` -> repeat. Without (complete, rigid) scale-free
    coordinates the direction is the mean neighbour bearing of ``range_bearing`` (see :meth:`centroid_bearing`;
    with ``sensing="full"`` this fallback halves the error: 0.14 m vs 0.22 m over 8 seeds, 200 steps);
    without neighbours, a random walk.
    The robot "has no notion of exact distance to the centroid" so it keeps circling within ~d_step.

    The pause: ``pause_steps`` control steps, or with ``pause_steps=None`` (default) until every
    ``range_bearing`` reading is younger than the pause (measured after the robot stopped), at most
    :attr:`MAX_PAUSE` steps: a few steps on range & bearing platforms, up to two rounds (~48 steps) on the
    r-one, whose readings are those of its last complete round [L Sec. 3.2.2].
    """

    #: the longest pause (control steps) of ``pause_steps=None``
    MAX_PAUSE = 60

    name = "centroid_seeker"

    def __init__(self, platform: Platform, layout: ObservationLayout, rng: np.random.Generator | None = None,
                 d_step: float = 0.11, speed: float = 1.0, pause_steps: int | None = None, min_scale_free: int = 3,
                 t_m: float = 2.0) -> None:
        self.d_step, self.speed = float(d_step), float(speed)
        self.pause_steps = None if pause_steps is None else int(pause_steps)
        self.min_scale_free = int(min_scale_free)
        super().__init__(platform, layout, rng, t_m)

    def reset(self, n: int, rng: np.random.Generator | None = None) -> None:
        super().reset(n, rng)
        self._phase = np.zeros(n, dtype=np.int64)  # 0 pause/measure, 1 turn, 2 drive
        self._timer = np.zeros(n, dtype=np.int64)
        self._turn = np.zeros(n)

    def centroid_bearing(self, obs: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        """Bearing (rad, body frame) of the scale-free centroid (fallback: mean neighbour bearing), has-mask.

        The scale-free centroid is used when the robot is ``rigid`` and its scale-free coordinates cover at
        least ``min_scale_free`` neighbours and every neighbour it currently senses in ``range_bearing``
        (a centroid of a subset of the polygon points the wrong way); otherwise the mean neighbour bearing.
        """
        sf = obs["scale_free"]
        valid = sf[..., 0] > 0.5
        count = valid.sum(axis=1)
        cx = (sf[..., 1] * valid).sum(axis=1) / np.maximum(count, 1)
        cy = (sf[..., 2] * valid).sum(axis=1) / np.maximum(count, 1)
        rb = obs["range_bearing"]
        rb_valid = rb[..., 0] > 0.5
        complete = (obs["rigid"][:, 0] > 0.5) & (count >= np.maximum(self.min_scale_free, rb_valid.sum(axis=1)))
        has_sf = complete & (np.hypot(cx, cy) > 1e-9)
        theta_rb, has_rb = circular_mean(rb[..., 2], rb[..., 3], rb_valid)
        bearing = np.where(has_sf, np.arctan2(cy, cx), theta_rb)
        return bearing, has_sf | has_rb

    def act_batch(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        n = len(obs["proprio"])
        self._ensure(n)
        step_turn = self.platform.max_angular_speed * DT
        lin, ang = np.zeros(n), np.zeros(n)
        bearing, has = self.centroid_bearing(obs)
        # phase 0: pause until the timer runs out (or the readings are fresh), then measure and plan the turn
        pausing = self._phase == 0
        self._timer[pausing] -= 1
        if self.pause_steps is None:  # the timer counts the pause up from -1: fresh = every reading younger
            rb = obs["range_bearing"]
            oldest = np.where(rb[..., 0] > 0.5, rb[..., 6], 0.0).max(axis=1)
            paused = -self._timer
            ready = (oldest < paused) | (paused >= self.MAX_PAUSE)
        else:
            ready = self._timer <= 0
        plan = pausing & ready & has
        self._turn[plan] = bearing[plan]
        self._phase[plan] = 1
        # phase 1: in-place turn (open loop, as the robot does not re-measure while moving)
        turning = self._phase == 1
        delta = np.clip(self._turn, -step_turn, step_turn)
        ang[turning] = delta[turning] / step_turn
        self._turn[turning] -= delta[turning]
        done_turn = turning & (np.abs(self._turn) < 1e-9)
        drive_steps = max(1, int(round(self.d_step / (self.speed * self.platform.max_speed * DT))))
        self._phase[done_turn] = 2
        self._timer[done_turn] = drive_steps
        # phase 2: drive d_step (starts the step after the turn completes)
        driving = (self._phase == 2) & ~done_turn
        lin[driving] = self.speed
        self._timer[driving] -= 1
        finished = driving & (self._timer <= 0)
        self._phase[finished] = 0
        self._timer[finished] = 0 if self.pause_steps is None else self.pause_steps
        # nobody to seek: random walk
        lost = pausing & ~has
        rw_lin, rw_ang = self._random_walk(lost)
        lin, ang = np.where(lost, rw_lin, lin), np.where(lost, rw_ang, ang)
        return self.compose(lin, ang)


#: name -> class of every scripted controller
SCRIPTED: dict[str, type[Policy]] = {
    cls.name: cls
    for cls in (RandomWalk, OrientationFlocking, ReynoldsFlocking, BearingAggregation, CentroidSeeker, SortedFollowing, ParityClustering, MidAngleNavigation)
}


def scripted_class(name: str) -> type[Policy]:
    """The controller class of ``name``: a name of :data:`SCRIPTED` or ``"module:Class"`` of any
    :class:`~swarm_envs.agents.base.Policy` subclass (e.g. a task's ``SCRIPTED_POLICY``)."""
    if isinstance(name, str) and ":" in name:
        module_name, _, attr = name.partition(":")
        try:
            cls = getattr(importlib.import_module(module_name), attr)
        except (ImportError, AttributeError) as err:
            raise ValueError(f"cannot load scripted policy {name!r}: {err}") from None
        if not (isinstance(cls, type) and issubclass(cls, Policy)):
            raise ValueError(f"scripted policy {name!r} is not a swarm_envs.agents.base.Policy subclass")
        return cls
    if name not in SCRIPTED:
        raise ValueError(f"unknown scripted policy {name!r}; available: {sorted(SCRIPTED)} or 'module:Class'")
    return SCRIPTED[name]


def make_scripted(name: str, env, rng: np.random.Generator | None = None, **kwargs) -> Policy:
    """Build scripted controller ``name`` (see :func:`scripted_class`) for ``env`` (reads only its platform
    spec and observation layout); ``kwargs`` go to the controller. ``ValueError`` for an unknown name or
    keyword."""
    cls = check_scripted_kwargs(name, kwargs)
    return cls(env.platform, env.layout, rng, **kwargs)


#: the rule of every keyword argument of the controllers above (the same rule classes as the env settings)
KWARG_RULES: dict[str, Setting] = {
    "t_m": Real(2.0, "random walk: forward leg", low=0.0, high=3600.0, low_open=True, unit="s"),
    "speed": Real(1.0, "a fraction of the platform's maximum speed", low=0.0, high=1.0),
    "leader_speed": Real(0.2, "a fraction of the platform's maximum speed", low=0.0, high=1.0),
    "gain": Real(0.5, "turn rate per radian of heading error", low=0.0, high=100.0),
    "stop_range": Real(0.0, "stop driving with a neighbour this close; 0 disables", high=100.0, unit="m"),
    "avoid_range": Real(0.15, "turn away from a neighbour ahead this close", high=100.0, unit="m"),
    "d_step": Real(0.11, "step length towards the centroid estimate", low=0.0, high=100.0, low_open=True, unit="m"),
    "align_weight": Real(3.0, "weight of the neighbours' mean heading", low=0.0, high=100.0),
    "cohesion_weight": Real(0.5, "weight of the pull to the neighbours' mean position", low=0.0, high=100.0),
    "separation_weight": Real(2.0, "weight of the push from neighbours closer than separation", low=0.0, high=100.0),
    "separation": Real(None, "push apart below this range; None: 3 body diameters", high=100.0, unit="m", allow_none=True),
    "cohesion_range": Real(None, "the pull is full at this distance; None: half the IR range", low=0.0, high=100.0, low_open=True, unit="m", allow_none=True),
    "passing_angle": Real(2.5, "rad between two relays the seeker passes between", low=0.0, high=6.2832),
    "pause_steps": Int(None, "control steps; None: until the readings are fresh", low=0, high=1_000_000, allow_none=True),
    "min_scale_free": Int(3, "scale-free neighbours needed", low=1, high=1_000),
    "memory": Int(300, "control steps", low=1, high=1_000_000),
    "evade_steps": Int(5, "control steps", low=0, high=1_000_000),
    "turn_away_on_bump": Flag(True),
    "odometry": Flag(True),
    "pick": Choice("next_lower", choices=("next_lower", "nearest")),
}


def check_scripted_kwargs(name: str, kwargs: dict) -> type[Policy]:
    """The controller class of ``name``, after checking ``kwargs`` (before any env is built): ``ValueError``
    naming an unknown keyword and listing the allowed ones, or naming a keyword whose value breaks its
    rule (:data:`KWARG_RULES`: type, finite, range). A controller of your own (``"module:Class"``) has its
    keywords' names checked here and their values by its constructor (``train.py`` builds it once on the
    config's env before training)."""
    cls = scripted_class(name)
    params = inspect.signature(cls.__init__).parameters
    kinds = (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)
    allowed = [key for key, p in params.items() if key not in ("self", "platform", "layout", "rng") and p.kind in kinds]
    takes_any = any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params.values())
    unknown = sorted(k for k in kwargs if k not in allowed)
    if unknown and not takes_any:
        raise ValueError(f"scripted policy {name!r} takes no keyword argument(s) {unknown}; allowed: {allowed}")
    if cls in SCRIPTED.values():
        for key, value in kwargs.items():
            try:
                KWARG_RULES[key].check(key, value)
            except SettingsError as err:
                raise ValueError(f"scripted policy {name!r}: {err}") from None
    return cls
