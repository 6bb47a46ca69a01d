"""The public task API: what a task adds to the simulation core -- its settings, robots, spawn, rewards
and metrics -- over all env copies at once.

A task is one :class:`Task` subclass. The simulator owns physics and sensing, so a task never writes an
observation (observations come only from the sensing stack). It sees the ground truth of ``B`` env
copies as ``(B, n_world, ...)`` arrays (:class:`BatchState`) and returns rewards and reward terms per
agent ``(B, n_agents)`` and metrics per copy ``(B,)``; rewards and metrics reach the agents only as
rewards and ``infos``, never as observations. The suite's own tasks are written with exactly this API
(they import only this module)::

    import numpy as np
    import swarm_envs
    from swarm_envs.tasks.task import Real, Task, nearest_distances

    class Spread(Task):
        SETTINGS = {"target": Real(0.3, low=0.0, unit="m")}
        METRICS = {"mean_spacing": "mean"}
        HEADLINE = ("mean_spacing", +1)

        def rewards(self, state, first):
            pos = self.agents_of(state.positions)                       # (B, N, 2) m
            spacing = nearest_distances(pos).mean(axis=1)              # (B,)
            reward = -np.abs(spacing - self.config["target"])
            return np.repeat(reward[:, None], self.n_agents, 1), {}, {"mean_spacing": spacing}

    swarm_envs.register("my_lab/Spread-v0", Spread)     # then make / make_vec / pettingzoo.make / train.py

Everything a task needs is exported here: the base class, the state, the setting rules
(:class:`Int`, :class:`Real`, :class:`Choice`, :class:`Flag`, :class:`SettingsError`; :class:`Default` for
another default of a common setting), the platform (:class:`Platform`, :func:`get_platform`), the control
step :data:`DT` (s), spawn and fit
helpers (:func:`spawn_positions`, :func:`check_capacity`, :func:`lattice_positions`, :class:`Arena`,
:func:`obstacle_points`, :func:`distance_to_segments`, :func:`segments_crossed`) and metric helpers over copies
(:func:`pairs_within`, :func:`largest_component_fraction`, :func:`neighbourhood_sums`,
:func:`nearest_distances`, :func:`bump_any`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np
from scipy.spatial import cKDTree

from swarm_envs.tasks._task_checks import REDUCTIONS, check_declarations, checked_count, checked_length
from swarm_envs.tasks.metrics import largest_component_fraction, neighbourhood_sums
from swarm_envs.sim.platforms import Platform, get_platform
from swarm_envs.tasks.settings import MAX_ROBOTS, Choice, Default, Flag, Int, Real, Setting, SettingsError, reward_weight, task_settings
from swarm_envs.sim.world import N_BUMP_SECTORS
from swarm_envs.sim.control import DT
from swarm_envs.sim.spawning import check_capacity, lattice_positions, spawn_positions
from swarm_envs.sim.arena import Arena, check_obstacles, distance_to_segments, obstacle_points

__all__ = [
    "Task",
    "BatchState",
    "SPACING",
    "MESSAGE_RANGE",
    "message_range",
    "Setting",
    "Int",
    "Real",
    "reward_weight",
    "Choice",
    "Flag",
    "Default",
    "SettingsError",
    "Platform",
    "get_platform",
    "DT",
    "Arena",
    "N_BUMP_SECTORS",
    "spawn_positions",
    "check_capacity",
    "lattice_positions",
    "obstacle_points",
    "distance_to_segments",
    "segments_crossed",
    "pairs_within",
    "largest_component_fraction",
    "neighbourhood_sums",
    "nearest_distances",
    "bump_any",
]

#: default centre spacing (m) used to size the arena when ``arena_size`` is None
SPACING = {"droplet": 0.15, "epuck": 0.25, "rone": 0.45}

#: reliable message range (m) of each platform: the largest distance at which a facing pair exchanges
#: SwarmCom frames with bit error probability below 0.01 at 310 bps. e-puck 0.61 m [T20 Sec. 7]; Droplet
#: 0.43 m and r-one 1.0 m measured with that facing-pair experiment on our channel model (``swarm-validate
#: behaviours --message-range``; the r-one's binary receivers hear every frame within their arcs up to the
#: 1 m range of [L Sec. 6.1]). Tasks size neighbourhoods by it (:func:`message_range`).
MESSAGE_RANGE = {"droplet": 0.43, "epuck": 0.61, "rone": 1.0}


@dataclass
class BatchState:
    """Ground truth of ``B`` copies after a control step (world frame, SI).

    Attributes:
        positions: (B, n_world, 2) m.
        headings: (B, n_world) rad.
        velocities: (B, n_world, 2) m/s achieved over the last step.
        bumps: (B, n_world, N_BUMP_SECTORS) bool contact flags of the last step.
        num_cycles: (B,) control steps since each copy's reset.
    """

    positions: np.ndarray
    headings: np.ndarray
    velocities: np.ndarray
    bumps: np.ndarray
    num_cycles: np.ndarray


class Task:
    """Base class of every swarm task (the suite's and a user's).

    Declare on the subclass:

    - ``SETTINGS``: the task's own keyword arguments as rules with defaults (``Int``, ``Real``,
      ``Choice``, ``Flag``), or another default for a common setting (``{"n_robots": 1}``);
    - ``METRICS``: ``{name: "final" | "mean"}``, how each metric of :meth:`rewards` is reduced over an
      episode by the evaluators (``train.py``, ``swarm-benchmark``);
    - ``HEADLINE``: ``(metric, +1)`` if higher is better, ``(metric, -1)`` if lower is better;
    - ``SCRIPTED_POLICY``: ``"module:Class"`` of a scripted baseline (a ``swarm_envs.agents.base.Policy``),
      or None.

    Override :meth:`rewards` (required) and, if needed, :meth:`n_static_robots`, :meth:`check_layout`,
    :meth:`default_arena_size`, :meth:`spawn`, :meth:`markers`, :meth:`robot_groups` (two colours in
    drawings), :meth:`obstacles` (walls inside the
    arena), :meth:`static_messages` (what the static robots broadcast) and :meth:`switched_off` (robots
    taken out mid-episode). The constructor gets the resolved
    settings (``self.config``: every common setting, see :data:`swarm_envs.tasks.settings.COMMON_SETTINGS`,
    plus the task's own), the platform and the number of copies.

    The declarations are checked when the class is made, and whatever a hook returns into the env is checked
    when it returns (shapes, dtypes, finiteness, names; :mod:`swarm_envs.tasks._task_checks`): a malformed one
    raises a one-line ``TypeError`` or ``ValueError`` naming the class, the attribute or hook and the key.

    Args:
        config: resolved env settings.
        platform: the robots' platform.
        n_copies: number of env copies stepped together.
    """

    SETTINGS: ClassVar[dict[str, Any]] = {}
    METRICS: ClassVar[dict[str, str]] = {}
    HEADLINE: ClassVar[tuple[str, int] | None] = None
    SCRIPTED_POLICY: ClassVar[str | None] = None
    #: the task's own settings' defaults (derived from ``SETTINGS``; read-only)
    TASK_DEFAULTS: ClassVar[dict[str, Any]] = {}
    _settings: ClassVar[dict[str, Setting]] = {}

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        owner = f"{cls.__module__}.{cls.__qualname__}"
        check_declarations(cls, owner)  # SETTINGS, METRICS, HEADLINE, SCRIPTED_POLICY: TypeError naming the attribute
        declared = {**getattr(super(cls, cls), "_settings", {}), **task_settings(cls.__dict__.get("SETTINGS", {}), owner)}
        cls._settings = declared
        cls.TASK_DEFAULTS = {key: s.default for key, s in declared.items()}

    @classmethod
    def settings(cls) -> dict[str, Setting]:
        """The task's own settings (its ``SETTINGS`` and its bases'), resolved as rules."""
        return dict(cls._settings)

    def __init__(self, config: dict[str, Any], platform: Platform, n_copies: int = 1) -> None:
        self.config = config
        self.platform = platform
        self.n_copies = int(n_copies)
        self.n_static = checked_count(self, "n_static_robots", self.n_static_robots(), MAX_ROBOTS)
        self.n_agents = int(config["n_robots"])
        self.n_world = self.n_static + self.n_agents
        if self.n_world > MAX_ROBOTS:
            raise SettingsError("n_robots", f"{self.n_world} robots per copy (agents and static robots) is above the limit of {MAX_ROBOTS}")
        self.max_cycles = int(config["max_cycles"])
        self.reward_mode = config["reward_mode"]
        size = config["arena_size"] if config["arena_size"] is not None else checked_length(self, "default_arena_size", self.default_arena_size())
        self.arena = Arena(config["arena"], float(size))
        self.agent_robots = np.arange(self.n_static, self.n_world)
        # an exact fit test: it passes if and only if the spawner (whose last resort is the densest lattice
        # placement, robots touching) places the robots for every seed
        try:
            check_capacity(self.n_world, platform.radius, self.arena)
        except ValueError as err:
            who = f" ({self.n_agents} agents and {self.n_static} static robots)" if self.n_static else ""
            raise SettingsError(self.size_key, str(err).replace(f"{self.n_world} robots", f"{self.n_world} robots{who}", 1)) from None
        self.check_layout()

    @property
    def size_key(self) -> str:
        """The setting a fit error names: ``arena_size`` when it was given, else ``n_robots``."""
        return "arena_size" if self.config["arena_size"] is not None else "n_robots"

    # -- what a task may override --------------------------------------------------------------------
    def n_static_robots(self) -> int:
        """Number of static robots (world rows ``0 .. n_static - 1``): they sense, emit and talk like the
        agents but are never commanded (e.g. anchors). Read ``self.config`` for the task's settings."""
        return 0

    def check_layout(self) -> None:
        """Raise :class:`SettingsError` naming the setting when the task's initial layout cannot fit. A task
        that overrides :meth:`spawn` checks here that its spawner succeeds for every seed."""

    def default_arena_size(self) -> float:
        """Arena size (m) when ``arena_size=None``: the platform's spacing times sqrt(robots)."""
        return SPACING.get(self.platform.name, 4 * self.platform.diameter) * float(np.sqrt(self.n_world))

    def spawn(self, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """One copy's initial (positions (n_world, 2) m, headings (n_world,) rad), drawn from ``rng``:
        robots uniformly at random without overlap and clear of the task's :meth:`obstacles`
        (:func:`spawn_positions`), which succeeds for every seed once the build's fit test has passed
        (the fit test does not count the room walls take: a task with walls checks its own layout)."""
        avoid, distance = obstacle_points(self.obstacle_segments, self.platform.radius)
        positions = spawn_positions(rng, self.n_world, self.platform.radius, self.arena, avoid=avoid, avoid_distance=distance)
        return positions, rng.uniform(-np.pi, np.pi, self.n_world)

    def obstacles(self) -> np.ndarray:
        """Static obstacle segments (S, 2, 2) (m, arena frame) inside the arena, e.g. the walls of a
        corridor: like the arena walls they stop robots, and like robots they block infrared light per ray
        (a ray from an emitter to a detector that crosses a segment carries no light). The same in every
        copy and episode; read once when the env is built. Default: none."""
        return np.zeros((0, 2, 2))

    @property
    def obstacle_segments(self) -> np.ndarray:
        """:meth:`obstacles`, checked (shape, finite, inside the arena) and cached."""
        if getattr(self, "_obstacle_segments", None) is None:
            self._obstacle_segments = check_obstacles(self.obstacles(), self.arena, f"{type(self).__name__}.obstacles()")
        return self._obstacle_segments

    def static_messages(self, observations: dict[str, np.ndarray], first: np.ndarray) -> np.ndarray | None:
        """The static robots' firmware: message bits (B, n_static, message_bits) bool each static robot
        queues next (sent as an agent's message bits are: whenever its transmit queue is empty), computed
        from its own observation ``observations`` ``{part: (B, n_static, ...)}`` of this step, built by the
        sensing stack like an agent's and always with the id parts (``own_id``, ``message_ids``, ...: a
        robot knows its id and reads the ids in the headers it decodes). Called after every step and reset
        when ``message_bits > 0``; ``first`` (B,) marks the copies whose episode starts with this step.
        Default None: static robots send empty payloads."""
        return None

    def switched_off(self, num_cycles: np.ndarray) -> np.ndarray | None:
        """(B, n_world) bool robots switched off during the control step about to run, ``num_cycles``
        (B,) (0 = a copy's reset step), or None (none; the default). A switched-off robot is taken out of
        the swarm as if its power were cut: it stands still (its actions are ignored), emits and detects no
        infrared (no range & bearing, no messages either way), but its body stays where it stopped and
        still stops robots and blocks light. Its agent stays in the env, observing nothing new."""
        return None

    def transmit_off(self, num_cycles: np.ndarray) -> np.ndarray | None:
        """(B, n_world) bool robots whose infrared emitters are off during the control step about to run,
        ``num_cycles`` (B,) (0 = a copy's reset step), or None (none; the default): receive-only robots.
        Such a robot moves and senses as usual, but no robot detects it: no range & bearing of it, and none
        of its frames (its messages are not queued; its bearing beacons and exchange lists reach no one)."""
        return None

    def receive_off(self, num_cycles: np.ndarray) -> np.ndarray | None:
        """(B, n_world) bool robots whose infrared detectors are off during the control step about to run,
        ``num_cycles`` (B,), or None (none; the default): transmit-only robots. Such a robot moves and
        emits as usual (others sense it and decode its messages), but detects nothing: no range & bearing
        readings, no messages, no bearings."""
        return None

    def rewards(self, state: BatchState, first: np.ndarray) -> tuple[np.ndarray, dict[str, np.ndarray], dict[str, np.ndarray]]:
        """(rewards (B, n_agents), reward terms {name: (B, n_agents)}, metrics {name: (B,)}).

        Called after every control step and after every reset; ``first`` (B,) bool marks the copies whose
        episode starts with this state (their reset step), so per-copy memory (e.g. the previous spread)
        can be restarted there. Return the same term and metric names every step; the metric names are
        exactly those of ``METRICS`` when the task declares it. Rewards and terms are finite, metrics finite
        or NaN (undefined in that copy at that step); bool, integer and float arrays are taken as float64.
        """
        raise NotImplementedError(f"{type(self).__name__} must implement rewards(state, first)")

    def robot_groups(self) -> tuple[np.ndarray, tuple[str, str]] | None:
        """For drawing only: ((n_world,) group 0 or 1 of each robot, the two groups' legend labels), e.g.
        even and odd ids; the renderer draws group 1 in a second colour. Default None: one group."""
        return None

    def markers(self, positions: np.ndarray) -> dict[str, np.ndarray]:
        """Task markers of one copy (name -> world point (2,) m) from its positions (n_world, 2): drawn by
        the renderer and part of ``env.state()``. Return the same names every step."""
        return {}

    # -- helpers ---------------------------------------------------------------------------------------
    def agents_of(self, array: np.ndarray) -> np.ndarray:
        """The agent rows of a (B, n_world, ...) array."""
        return array[:, self.n_static :]


def segments_crossed(starts: np.ndarray, ends: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """(...,) bool: the straight line from ``starts`` (..., 2) to ``ends`` (..., 2) (m) crosses or touches
    one of ``segments`` (S, 2, 2) (m), e.g. a task's :meth:`Task.obstacles` (the test the IR layer uses
    for light)."""
    from swarm_envs.ir.blocking import rays_blocked

    segments = np.asarray(segments, dtype=float).reshape(-1, 2, 2)
    if len(segments) == 0:
        return np.zeros(np.broadcast_shapes(np.shape(starts), np.shape(ends))[:-1], dtype=bool)
    return rays_blocked(starts, ends, segments)


def message_range(platform: Platform) -> float:
    """The platform's reliable message range (m), :data:`MESSAGE_RANGE`; 0.6 IR ranges for a platform
    of your own."""
    return float(MESSAGE_RANGE.get(platform.name, 0.6 * platform.ir_range))


def bump_any(bumps: np.ndarray) -> np.ndarray:
    """True per robot in contact with anything this step; ``bumps`` (..., N_BUMP_SECTORS)."""
    return bumps.reshape(*bumps.shape[:-1], N_BUMP_SECTORS).any(axis=-1)


def pairs_within(positions: np.ndarray, distance: float) -> np.ndarray:
    """Unordered robot pairs (P, 2) of rows of ``positions`` (B, N, 2) whose centres are closer than
    ``distance`` (m), never across copies; row ``b * N + i`` is robot i of copy b."""
    from swarm_envs.sensing.ideal import copy_pairs

    B, N = positions.shape[:2]
    return copy_pairs(np.ascontiguousarray(positions, dtype=float).reshape(B * N, 2), float(distance), N)


def nearest_distances(positions: np.ndarray) -> np.ndarray:
    """(B, N) centre distance (m) of every robot to its nearest other robot of the same copy (inf alone)."""
    positions = np.asarray(positions, dtype=float)
    B, N = positions.shape[:2]
    if N < 2:
        return np.full((B, N), np.inf)
    if N <= 64:  # all pairs of every copy at once
        gaps = np.linalg.norm(positions[:, :, None, :] - positions[:, None, :, :], axis=-1)
        gaps[:, np.arange(N), np.arange(N)] = np.inf
        return gaps.min(axis=2)
    return np.stack([cKDTree(p).query(p, k=2)[0][:, 1] for p in positions])  # one KD-tree per copy
