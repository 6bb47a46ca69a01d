"""``make_vec``: many copies of a swarm task stepped by one batched core, with array inputs and outputs.

A :class:`SwarmVectorEnv` is a Gymnasium 1.x ``VectorEnv`` over ``B = num_envs`` copies of one task, each
copy a whole swarm of ``N`` agents. Everything is an array with leading axes ``(B, N)``:

- ``step(actions)`` takes ``(B, N, A)`` actions (A = 2 + message_bits, clipped to [-1, 1]; NaN/inf,
  complex, non-numeric or wrongly shaped actions raise ``ValueError``/``TypeError`` before anything moves);
- observations: a dict of ``(B, N, ...)`` float32 arrays, or ``(B, N, D)`` with ``flatten=True``;
- rewards, terminations, truncations: ``(B, N)``;
- infos: arrays, no per-agent dicts: ``metrics[name]`` ``(B,)``, ``reward_terms[name]`` ``(B, N)``,
  ``ground_truth["position"]`` ``(B, N, 2)`` m, ``["heading"]`` ``(B, N)`` rad, ``["velocity"]``
  ``(B, N, 2)`` m/s, ``sensing[name]`` ``(B, N)``, and ``episode_step`` ``(B,)``.

Autoreset: Gymnasium's ``NEXT_STEP`` mode (the 1.x default). When copy b's episode ends at step t, step t
returns its last observation (and infos) with ``truncations[b] = True``; the next ``step`` resets copy b
(its actions are ignored) and returns its first observation with zero reward and no termination or
truncation, while the other copies step on. Seeding: ``reset(seed=s)`` seeds copy b with ``s + b``;
``reset(seed=[s0, s1, ...])`` seeds each copy; copy b seeded with ``s`` reproduces
``swarm_envs.make(env_id, ...)`` reset with ``s`` bit for bit, given the same actions.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from typing import Any

import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv

from swarm_envs.tasks._task_checks import checked_markers
from swarm_envs.core import SwarmCore
from swarm_envs.sim.platforms import get_platform
from swarm_envs.tasks.settings import SettingsError
from swarm_envs.tasks.task import Task
from swarm_envs.adapters.views import check_finite_actions, check_reset_options, check_seed, info_arrays, make_layout, real_actions, resolve_config
from swarm_envs.sim.world import COPY_LOG_BYTES

#: copies of one batched core at most, and robots over all its copies at most (memory grows with both)
MAX_COPIES = 100_000
MAX_TOTAL_ROBOTS = 200_000

# Memory of one env copy (bytes), measured as the growth of the process's resident memory (VmRSS, peak
# VmHWM) of make_vec(B) over its build, reset and steps (e-puck, full sensing; docs/settings.md#make_vec):
#: per copy (its physics space, random generators and sensing state): 320-330 KB with one robot
COPY_BYTES = 320_000
#: per robot of a copy, at the peak of a step (34-57 KB measured from 10 to 5,000 robots per copy)
ROBOT_BYTES = 60_000
#: per wall segment of a copy's physics space (a circle arena's 64 add ~87 KB)
WALL_BYTES = 1_500
#: per control step of an episode, besides 16 bytes per robot: a world's command log for exact copies
#: (swarm_envs.sim.world.COPY_LOG_BYTES; 0.4-0.6 KB per step measured)
LOG_STEP_BYTES = 500

__all__ = [
    "SwarmVectorEnv",
    "AgentsAsEnvs",
    "MAX_COPIES",
    "MAX_TOTAL_ROBOTS",
    "copy_memory",
    "available_memory",
    "check_memory",
]


def copy_memory(task: Task) -> int:
    """Estimated peak memory (bytes) of one copy of ``task`` (a task built for one copy) over an episode of
    ``max_cycles`` steps: :data:`COPY_BYTES`, :data:`ROBOT_BYTES` per robot, :data:`WALL_BYTES` per wall
    segment, the task's own arrays and the world's command log (16 bytes per robot + :data:`LOG_STEP_BYTES`
    per step, until the log reaches ``COPY_LOG_BYTES``)."""
    n = task.n_world
    segments = len(task.arena.wall_segments()) + len(task.obstacle_segments)
    own = sum(value.nbytes for value in vars(task).values() if isinstance(value, np.ndarray))
    steps = min(task.max_cycles, COPY_LOG_BYTES // (16 * n) + 1)
    return COPY_BYTES + ROBOT_BYTES * n + WALL_BYTES * segments + own + steps * (16 * n + LOG_STEP_BYTES)


def _read_number(path: str) -> int | None:
    try:
        with open(path, encoding="ascii") as f:
            return int(f.read().split()[0])
    except (OSError, ValueError, IndexError):
        return None


def available_memory() -> int | None:
    """Memory (bytes) this process can still take: ``MemAvailable`` of ``/proc/meminfo`` (else the free
    physical pages, ``os.sysconf``), or less when the process's memory cgroup allows less; None if unknown."""
    available = None
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    available = int(line.split()[1]) * 1024  # kB
                    break
    except (OSError, ValueError, IndexError):
        pass
    if available is None:
        try:
            available = os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
        except (AttributeError, ValueError, OSError):
            return None
    for limit_path, usage_path in (
        ("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory.current"),  # cgroup v2 ("max": no limit)
        ("/sys/fs/cgroup/memory/memory.limit_in_bytes", "/sys/fs/cgroup/memory/memory.usage_in_bytes"),  # v1
    ):
        limit, usage = _read_number(limit_path), _read_number(usage_path)
        if limit is not None and usage is not None and limit < 1 << 60:
            available = min(available, max(limit - usage, 0))
    return available


def check_memory(task: Task, num_envs: int) -> None:
    """:class:`SettingsError` naming ``num_envs`` when ``num_envs`` copies of ``task`` (built for one copy)
    would need more memory (:func:`copy_memory`) than is available (:func:`available_memory`)."""
    available = available_memory()
    per_copy = copy_memory(task)
    if available is None or num_envs * per_copy <= available:
        return
    raise SettingsError(
        "num_envs",
        f"num_envs={num_envs} copies of {task.n_world} robot(s) would need ~{num_envs * per_copy / 2**30:.2f} GiB of memory "
        f"(~{per_copy / 1e3:,.0f} KB per copy over an episode of {task.max_cycles:,} steps), but the machine has "
        f"{available / 2**30:.2f} GiB available; use at most {available // per_copy:,} copies, fewer robots or a shorter max_cycles",
    )


def _batch_space(space: spaces.Box, lead: tuple[int, ...]) -> spaces.Box:
    low = np.broadcast_to(space.low, lead + space.shape)
    high = np.broadcast_to(space.high, lead + space.shape)
    return spaces.Box(low, high, dtype=space.dtype)


class SwarmVectorEnv(VectorEnv):
    """``num_envs`` copies of ``task`` (a :class:`swarm_envs.tasks.task.Task` subclass, its env class or a registered id).
    Copies whose estimated memory exceeds the machine's available memory are refused (:func:`check_memory`).

    Args:
        task: the task (e.g. :class:`swarm_envs.tasks.aggregation_v0.AggregationTask`).
        num_envs: number of copies B.
        **kwargs: env settings, as for the single env.
    """

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}

    def __init__(self, task: type, num_envs: int, **kwargs: Any) -> None:
        if isinstance(num_envs, bool) or not isinstance(num_envs, (int, np.integer)) or not 1 <= num_envs <= MAX_COPIES:
            raise SettingsError("num_envs", f"num_envs must be an integer in [1, {MAX_COPIES}], got {num_envs!r:.80}")
        if kwargs.get("render_mode") is not None:
            raise SettingsError("render_mode", "make_vec does not render; use the single env (swarm_envs.make) with render_mode")
        task_cls = getattr(task, "TASK", task)  # an env class's task
        if not (isinstance(task_cls, type) and issubclass(task_cls, Task)) or task_cls is Task:
            raise TypeError(
                f"SwarmVectorEnv needs a subclass of swarm_envs.Task that implements the hooks (at least rewards), got {task!r:.80}"
            )
        cfg = resolve_config(task_cls, kwargs)
        self.config = cfg
        self.platform = get_platform(cfg["platform"])
        # one copy first: its robots, walls and arrays size the batch before the copies are allocated
        task = task_cls(cfg, self.platform, n_copies=1)
        if task.n_world * int(num_envs) > MAX_TOTAL_ROBOTS:
            raise SettingsError(
                "num_envs", f"{num_envs} copies of {task.n_world} robots exceed {MAX_TOTAL_ROBOTS} robots in one batched core; use fewer copies"
            )
        check_memory(task, int(num_envs))
        self.task = task if num_envs == 1 else task_cls(cfg, self.platform, n_copies=int(num_envs))
        self.layout = make_layout(cfg, self.platform, self.task.n_world)
        self.core = SwarmCore(self.task, self.layout)
        self.num_envs = int(num_envs)
        self.n_agents = self.task.n_agents
        self.possible_agents = [f"robot_{i}" for i in range(self.n_agents)]
        self.max_cycles = self.task.max_cycles
        agent_obs = self.layout.space()
        agent_act = self.layout.action_space()
        lead = (self.n_agents,)
        if isinstance(agent_obs, spaces.Dict):
            self.single_observation_space = spaces.Dict({k: _batch_space(v, lead) for k, v in agent_obs.spaces.items()})
            self.observation_space = spaces.Dict({k: _batch_space(v, (self.num_envs,) + lead) for k, v in agent_obs.spaces.items()})
        else:
            self.single_observation_space = _batch_space(agent_obs, lead)
            self.observation_space = _batch_space(agent_obs, (self.num_envs,) + lead)
        self.single_action_space = _batch_space(agent_act, lead)
        self.action_space = _batch_space(agent_act, (self.num_envs,) + lead)
        self.agent_observation_space = agent_obs
        self.agent_action_space = agent_act
        self._rows = self.core.agent_rows()  # (B, N)
        self._needs_reset = np.zeros(self.num_envs, dtype=bool)
        self._started = False

    # -- API --------------------------------------------------------------------------------------------
    def reset(self, *, seed: int | Sequence[int | None] | None = None, options: dict[str, Any] | None = None):
        """Reset every copy; returns (observations, infos). ``options`` as for the single env, applied to all."""
        seeds = self._seeds(seed)
        pose = check_reset_options(options, self.core.worlds[0])
        for b, s in enumerate(seeds):
            self.core.seed(b, s)
        self.core.start(np.arange(self.num_envs), [pose] * self.num_envs)
        self.core.step(None)
        self._needs_reset[:] = False
        self._started = True
        return self._observations(), self._infos()

    def step(self, actions: np.ndarray):
        """Step every copy with ``actions`` (B, N, A); see the module docstring for outputs and autoreset."""
        if not self._started:
            raise RuntimeError("step() called before reset()")
        act = self._check_actions(actions)
        restart = np.flatnonzero(self._needs_reset)
        if restart.size:
            self.core.start(restart)
        full = np.zeros((self.core.n_total, self.layout.action_size))
        full[self._rows.reshape(-1)] = act.reshape(-1, self.layout.action_size)
        self.core.step(full)
        rewards = self.core.rewards.astype(np.float32)
        rewards[restart] = 0.0
        truncated = self.core.num_cycles >= self.max_cycles
        truncated[restart] = False
        self._needs_reset = truncated.copy()
        truncations = np.repeat(truncated[:, None], self.n_agents, axis=1)
        terminations = np.zeros((self.num_envs, self.n_agents), dtype=bool)
        return self._observations(), rewards, terminations, truncations, self._infos()

    def states(self) -> np.ndarray:
        """Global ground-truth state of every copy, ``(B, state_dim)`` float32: row b is what
        :meth:`swarm_envs.adapters.env.SwarmEnv.state` returns for a single env in copy b's place (robots'
        ``STATE_ROBOT_FIELDS`` in world order, the task's markers (m) sorted by name, episode progress).
        For centralised critics only: never part of an observation. Call after :meth:`reset`. The markers
        come from the task copy by copy (``Task.markers`` takes one copy's positions)."""
        if not self._started:
            raise RuntimeError("states() needs started episodes; call reset() first")
        core, B, n = self.core, self.num_envs, self.task.n_world
        positions = core.positions.reshape(B, n, 2)
        headings = core.headings.reshape(B, n)
        spin = np.stack([w.angular_velocities for w in core.worlds])
        fields = [positions, np.cos(headings)[..., None], np.sin(headings)[..., None], core.velocities.reshape(B, n, 2), spin[..., None]]
        robots = np.concatenate(fields, axis=2).reshape(B, -1)
        _, points = checked_markers(self.task, [self.task.markers(positions[b]) for b in range(B)])
        points = points.reshape(B, -1)
        progress = np.minimum(core.num_cycles / self.max_cycles, 1.0)
        return np.concatenate([robots, points, progress[:, None]], axis=1).astype(np.float32)

    def close_extras(self, **kwargs: Any) -> None:
        pass

    # -- helpers ----------------------------------------------------------------------------------------
    def _seeds(self, seed: int | Sequence[int | None] | None) -> list[int | None]:
        B = self.num_envs
        if seed is None:
            return [None] * B
        if isinstance(seed, (int, np.integer)) and not isinstance(seed, bool):
            return [check_seed(seed) + b for b in range(B)]
        if isinstance(seed, Sequence) and not isinstance(seed, (str, bytes)):
            seeds = list(seed)
            if len(seeds) != B:
                raise ValueError(f"seed list must have one entry per copy ({B}), got {len(seeds)}")
            return [check_seed(s) for s in seeds]
        raise TypeError(f"seed must be an int, a list of ints (one per copy) or None, got {type(seed).__name__}")

    def _check_actions(self, actions: Any) -> np.ndarray:
        B, N, size = shape = (self.num_envs, self.n_agents, self.layout.action_size)
        arr = real_actions(actions, shape, "actions", f"(num_envs, n_agents, action_size) = {shape}")
        names = self.possible_agents
        return check_finite_actions(arr.reshape(B * N, size), lambda row: f"{names[row % N]} of copy {row // N}").reshape(shape)

    def _observations(self) -> dict[str, np.ndarray] | np.ndarray:
        parts = self.core.observations()  # fresh arrays every step
        B, N = self._rows.shape
        if self.task.n_static == 0:  # every robot is an agent: the rows are in order, reshape (no copy)
            named = {k: v.reshape(B, N, *v.shape[1:]) for k, v in parts.items()}
        else:
            named = {k: v[self._rows] for k, v in parts.items()}  # (B, N, ...)
        if not self.layout.flatten:
            return named
        flat = [named[k].reshape(B, N, -1) for k in sorted(named)]  # gymnasium.spaces.flatten order for Dict
        return np.concatenate(flat, axis=2).astype(np.float32)

    def _infos(self) -> dict[str, Any]:
        return {**info_arrays(self.core, self._rows), "episode_step": self.core.num_cycles.copy()}


class AgentsAsEnvs(VectorEnv):
    """Every robot of every copy as one sub-env: ``num_envs = B x N`` rows (row ``b * N + i`` is agent i of
    copy b), for Gymnasium's vector wrappers and single-agent libraries (parameter sharing, as SuperSuit's
    ``pettingzoo_env_to_vec_env_v1`` does). A view of one :class:`SwarmVectorEnv`: observations ``(B N, ...)``,
    actions ``(B N, A)``, rewards, terminations and truncations ``(B N,)``, infos with ``B N`` rows (per-copy
    values repeated for each of its robots). Autoreset as :class:`SwarmVectorEnv` (``NEXT_STEP``): all robots
    of a copy end and restart together.

    Example::

        vec = swarm_envs.make_vec("swarm_envs/Flocking-v0", 16, agents_as_envs=True, flatten=True)
        vec = gymnasium.wrappers.vector.RecordEpisodeStatistics(vec)
        vec = gymnasium.wrappers.vector.NormalizeObservation(vec)
    """

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}

    def __init__(self, vec: SwarmVectorEnv) -> None:
        from gymnasium.vector.utils import batch_space

        self.vec = vec
        self.copies, self.n_agents = vec.num_envs, vec.n_agents
        self.num_envs = self.copies * self.n_agents
        self.single_observation_space = vec.agent_observation_space
        self.single_action_space = vec.agent_action_space
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.layout, self.platform, self.config = vec.layout, vec.platform, vec.config

    def reset(self, *, seed: int | Sequence[int | None] | None = None, options: dict[str, Any] | None = None):
        """Reset every copy (``seed``: an int, or one per *copy*, as :meth:`SwarmVectorEnv.reset`)."""
        obs, infos = self.vec.reset(seed=seed, options=options)
        return self._rows(obs), self._info_rows(infos)

    def step(self, actions: np.ndarray):
        """Step with ``(B N, A)`` actions."""
        arr = np.asarray(actions)
        if arr.ndim != 2 or arr.shape[0] != self.num_envs:
            raise ValueError(f"actions must have shape (num_envs, action_size) = ({self.num_envs}, {self.vec.layout.action_size}), got {arr.shape}")
        obs, rewards, terminations, truncations, infos = self.vec.step(arr.reshape(self.copies, self.n_agents, -1))
        return self._rows(obs), rewards.reshape(-1), terminations.reshape(-1), truncations.reshape(-1), self._info_rows(infos)

    def close_extras(self, **kwargs: Any) -> None:
        self.vec.close()

    def _rows(self, value: Any) -> Any:
        """(B, N, ...) arrays (or a dict of them) as (B N, ...) rows; (B,) per-copy values repeated per robot."""
        if isinstance(value, dict):
            return {k: self._rows(v) for k, v in value.items()}
        value = np.asarray(value)
        if value.shape[:2] == (self.copies, self.n_agents):
            return value.reshape(self.num_envs, *value.shape[2:])
        return np.repeat(value, self.n_agents, axis=0)

    def _info_rows(self, infos: dict[str, Any]) -> dict[str, Any]:
        return {k: self._rows(v) for k, v in infos.items()}
