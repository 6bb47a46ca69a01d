"""Scripted swarm behaviours from the papers, batched over robots, reading observations by name only.

Every controller implements :class:`agents.base.Policy` and works the same with ``sensing="full"`` and
``sensing="ideal"`` (the observation layout is shared). None reads ``infos`` or ground truth.

- :class:`RandomWalk` - [T20] Alg. 1: rotate by a random angle theta in (-pi, pi], then drive with a random
  velocity v in [-v_max, v_max] (the e-puck's +-128 mm/s) for t_m = 2 s; repeat.
- :class:`OrientationFlocking` - [L] Sec. 6.4.1, Alg. 5: average the neighbours' orientations (headings from
  ``range_bearing``), steer to that heading at a fixed forward speed; on a bump stop and turn away
  (``heading = theta_u + pi``).
- :class:`BearingAggregation` - [L] Sec. 6.4.3, Alg. 7 generalised to one cluster (every robot is in the same
  "even/odd" group): steer towards the average neighbour bearing at a fixed speed; bump -> turn away.
- :class:`CentroidSeeker` - [L] Sec. 6.2.2: pause, take the centroid of the scale-free neighbour coordinates,
  turn to its bearing and drive a fixed ``d_step`` (11 cm in the thesis) towards it; repeat.
- :class:`SortedFollowing` - [L] Sec. 6.4.2, Alg. 6 (bonus): each robot broadcasts its id in the message bits;
  a robot follows (steers to the bearing of) the neighbour with the next-lower id; the lowest id leads,
  driving straight and avoiding obstacles.

Speeds are fractions of the platform maximum (the thesis' 20 mm/s is 0.067 of the r-one's 0.30 m/s; the
defaults here are faster so that 20-50 s episodes show the behaviour; every speed is a constructor argument).
Where an algorithm is undefined (no neighbour in range) the robot falls back to the random walk, which
the thesis leaves open (the r-one "keeps its last pose").
"""

from __future__ import annotations

import importlib
import inspect

import numpy as np

from swarm_envs.agents.base import Policy, wrap_angle
from swarm_envs.env import DT
from swarm_envs.observation import ObservationLayout
from swarm_envs.platforms import Platform
from swarm_envs.world import N_BUMP_SECTORS

__all__ = [
    "RandomWalk",
    "OrientationFlocking",
    "BearingAggregation",
    "CentroidSeeker",
    "SortedFollowing",
    "SCRIPTED",
    "scripted_class",
    "check_scripted_kwargs",
    "make_scripted",
    "circular_mean",
    "bump_direction",
]

_SECTOR_ANGLES = np.arange(N_BUMP_SECTORS) * (2 * np.pi / N_BUMP_SECTORS)  # sector i centred at 45 i deg (body frame)


def circular_mean(cos: np.ndarray, sin: np.ndarray, valid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Angle (rad) of the mean of the valid unit vectors per row ``(N, K) -> (N,)``, and a has-any mask.

    Rows with no valid entry (or a zero resultant) get angle 0 and ``False``.
    """
    w = valid.astype(np.float64)
    c, s = (cos * w).sum(axis=1), (sin * w).sum(axis=1)
    has = (w.sum(axis=1) > 0) & (np.hypot(c, s) > 1e-9)
    return np.where(has, np.arctan2(s, c), 0.0), has


def bump_direction(proprio: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Body-frame direction (rad) of the bumped sectors per robot, and whether any sector is bumped."""
    bumps = proprio[:, :N_BUMP_SECTORS] > 0.5
    return circular_mean(np.cos(_SECTOR_ANGLES)[None], np.sin(_SECTOR_ANGLES)[None], bumps)


class _Stateful(Policy):
    """Shared machinery: a bump escape manoeuvre and a random-walk fallback, both with per-row state."""

    def __init__(
        self,
        platform: Platform,
        layout: ObservationLayout,
        rng: np.random.Generator | None = None,
        t_m: float = 2.0,
    ) -> None:
        super().__init__(platform, layout, rng)
        self.t_m = float(t_m)
        self.reset(0)

    def reset(self, n: int, rng: np.random.Generator | None = None) -> None:
        super().reset(n, rng)
        self._escape = np.zeros(n)  # remaining in-place turn (rad, signed) of a bump escape
        self._rw_turn = np.zeros(n)  # random walk: remaining rotation (rad, signed)
        self._rw_steps = np.zeros(n, dtype=np.int64)  # random walk: remaining forward steps
        self._rw_speed = np.zeros(n)  # random walk: forward speed fraction

    def _ensure(self, n: int) -> None:
        if n != self.n:
            self.reset(n)

    # -- [T20] Alg. 1 --------------------------------------------------------------------------------
    def _random_walk(self, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """One step of the random walk for the selected rows (bool mask); returns (linear, angular)."""
        n = self.n
        lin, ang = np.zeros(n), np.zeros(n)
        if not rows.any():
            return lin, ang
        step_turn = self.platform.max_angular_speed * DT  # rad per step at full angular speed
        # start a new cycle where both phases are over: theta in (-pi, pi], v in [-vmax, vmax]
        new = rows & (np.abs(self._rw_turn) < 1e-9) & (self._rw_steps <= 0)
        k = int(new.sum())
        if k:
            self._rw_turn[new] = -self.rng.uniform(-np.pi, np.pi, k)  # -U[-pi, pi) = U(-pi, pi]
            self._rw_speed[new] = self.rng.uniform(-1.0, 1.0, k)
            self._rw_steps[new] = int(round(self.t_m / DT))
        turning = rows & (np.abs(self._rw_turn) >= 1e-9)
        delta = np.clip(self._rw_turn, -step_turn, step_turn)
        ang[turning] = delta[turning] / step_turn
        self._rw_turn[turning] -= delta[turning]
        moving = rows & ~turning & (self._rw_steps > 0)
        lin[moving] = self._rw_speed[moving]
        self._rw_steps[moving] -= 1
        return lin, ang

    # -- [L] Algs. 5-7, "if CheckBumpObstacle(u): PoseSet(tv = 0, heading = theta_u + pi)" ----------------------
    def _bump_escape(self, proprio: np.ndarray, turn_away: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Start/continue the escape turn; returns (escaping mask, linear, angular).

        A new bump on the front half (outside an escape) starts an in-place turn that puts the bump direction
        behind the robot (for a frontal bump this is exactly ``theta_u + pi``); the robot does not drive while
        escaping. Contacts on the rear half are ignored (turning around would face the obstacle).
        """
        n = self.n
        step_turn = self.platform.max_angular_speed * DT
        direction, bumped = bump_direction(proprio)
        if turn_away:
            # only contacts on the front half stop the robot (a push from behind does not block it)
            start = bumped & (np.cos(direction) > 0) & (np.abs(self._escape) < 1e-9)
            # turn so that the bump direction ends up at pi (behind): rotate by direction - pi (wrapped)
            self._escape[start] = wrap_angle(direction[start] - np.pi)
        escaping = np.abs(self._escape) >= 1e-9
        delta = np.clip(self._escape, -step_turn, step_turn)
        ang = np.where(escaping, delta / step_turn, 0.0)
        self._escape[escaping] -= delta[escaping]
        return escaping, np.zeros(n), ang


class RandomWalk(_Stateful):
    """[T20] Alg. 1 random walk (rotate by theta ~ U(-pi, pi], drive v ~ U[-v_max, v_max] for t_m = 2 s)."""

    name = "random_walk"

    def act_batch(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        n = len(obs["proprio"])
        self._ensure(n)
        lin, ang = self._random_walk(np.ones(n, dtype=bool))
        return self.compose(lin, ang)


class OrientationFlocking(_Stateful):
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


class BearingAggregation(_Stateful):
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


class CentroidSeeker(_Stateful):
    """[L] Sec. 6.2.2 centroid controller, one step of ``d_step`` per sensing round.

    Cycle per robot: pause ``pause_steps`` control steps (the thesis pauses for each neighbour round) ->
    read the centroid of the valid ``scale_free`` neighbour coordinates (the robot's own frame, scaled so
    the mean neighbour distance is 1; only the direction is used) -> turn in place to its bearing ->
    drive ``d_step`` metres (11 cm in the thesis) at ``speed`` -> repeat. Without (complete, rigid) scale-free
    coordinates the direction is the mean neighbour bearing of ``range_bearing`` (see :meth:`centroid_bearing`;
    with ``sensing="full"`` this fallback halves the error: 0.14 m vs 0.22 m over 8 seeds, 200 steps);
    without neighbours, a random walk.
    The robot "has no notion of exact distance to the centroid" so it keeps circling within ~d_step.
    """

    name = "centroid_seeker"

    def __init__(self, platform: Platform, layout: ObservationLayout, rng: np.random.Generator | None = None,
                 d_step: float = 0.11, speed: float = 1.0, pause_steps: int = 2, min_scale_free: int = 3,
                 t_m: float = 2.0) -> None:
        self.d_step, self.speed, self.pause_steps = float(d_step), float(speed), int(pause_steps)
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
        # phase 0: pause until the timer runs out, then measure and plan the turn
        pausing = self._phase == 0
        self._timer[pausing] -= 1
        plan = pausing & (self._timer <= 0) & has
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
        self._timer[finished] = self.pause_steps
        # nobody to seek: random walk
        lost = pausing & ~has
        rw_lin, rw_ang = self._random_walk(lost)
        lin, ang = np.where(lost, rw_lin, lin), np.where(lost, rw_ang, ang)
        return self.compose(lin, ang)


class SortedFollowing(_Stateful):
    """[L] Alg. 6 sorted following (needs ``message_bits >= ceil(log2(n_robots))``).

    Robot ids are the batch rows (``robot_i`` is row i). Each robot sends its id as the message payload
    (bit j of the id -> message action 2 + j). From the received messages ([valid, bearing/pi, bits])
    the robot follows, at ``speed``, the bearing of the sender with the largest id below its own (Alg. 6
    takes the first lower id it finds; following the next-lower id gives the sorted line the thesis
    describes). The lowest id robot (no lower id heard) leads: drives straight and turns away from
    neighbours closer than ``avoid_range`` ahead and from bumps (AvoidIRObstacle).
    """

    name = "sorted_following"

    def __init__(self, platform: Platform, layout: ObservationLayout, rng: np.random.Generator | None = None,
                 speed: float = 0.5, gain: float = 0.5, avoid_range: float = 0.15, t_m: float = 2.0) -> None:
        if layout.message_bits < 1:
            raise ValueError("SortedFollowing needs message_bits >= 1 to broadcast robot ids (env kwarg message_bits)")
        self.speed, self.gain, self.avoid_range = float(speed), float(gain), float(avoid_range)
        super().__init__(platform, layout, rng, t_m)

    def act_batch(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        msgs, rb = obs["messages"], obs["range_bearing"]
        n, b = len(msgs), self.layout.message_bits
        if n > 2**b:
            raise ValueError(f"{n} robots need message_bits >= {int(np.ceil(np.log2(n)))}, env has {b}")
        self._ensure(n)
        own = np.arange(n)
        weights = 2 ** np.arange(b)
        ids = ((msgs[..., 2:] > 0.5) * weights).sum(axis=-1)  # (N, M)
        lower = (msgs[..., 0] > 0.5) & (ids < own[:, None])
        cand = np.where(lower, ids, -1)
        best = cand.argmax(axis=1)
        following = cand.max(axis=1) >= 0
        target = msgs[np.arange(n), best, 1] * np.pi
        lin = np.full(n, self.speed)
        ang = np.where(following, self.turn_towards(target, self.gain), 0.0)
        # leader: AvoidIRObstacle - turn away from close neighbours ahead
        valid = rb[..., 0] > 0.5
        close = valid & (rb[..., 1] > 0) & (rb[..., 1] < self.avoid_range) & (rb[..., 2] > 0.5)
        away, has_close = circular_mean(rb[..., 2], rb[..., 3], close)
        avoid = ~following & has_close
        ang = np.where(avoid, -np.sign(away + 1e-12), ang)
        escaping, e_lin, e_ang = self._bump_escape(obs["proprio"])
        lin, ang = np.where(escaping, e_lin, lin), np.where(escaping, e_ang, ang)
        out = self.compose(lin, ang)
        bits = (own[:, None] >> np.arange(b)[None]) & 1
        out[:, 2:] = np.where(bits > 0, 1.0, -1.0)
        return out


#: name -> class of every scripted controller
SCRIPTED: dict[str, type[Policy]] = {
    cls.name: cls for cls in (RandomWalk, OrientationFlocking, BearingAggregation, CentroidSeeker, SortedFollowing)
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


def check_scripted_kwargs(name: str, kwargs: dict) -> type[Policy]:
    """The controller class of ``name``, after checking that it takes ``kwargs``: ``ValueError`` naming an
    unknown keyword and listing the allowed ones (before any env is built)."""
    cls = scripted_class(name)
    params = inspect.signature(cls.__init__).parameters
    kinds = (inspect.Parameter.POSITIONAL_OR_KEYWORD, inspect.Parameter.KEYWORD_ONLY)
    allowed = [key for key, p in params.items() if key not in ("self", "platform", "layout", "rng") and p.kind in kinds]
    takes_any = any(p.kind is inspect.Parameter.VAR_KEYWORD for p in params.values())
    unknown = sorted(k for k in kwargs if k not in allowed)
    if unknown and not takes_any:
        raise ValueError(f"scripted policy {name!r} takes no keyword argument(s) {unknown}; allowed: {allowed}")
    return cls
