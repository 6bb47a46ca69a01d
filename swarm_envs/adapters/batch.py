"""The batched episodes of one core: ``B`` copies of a task with array inputs and outputs, seeding, reset
options, action checks, autoreset and infos. Every array adapter is a thin view of a :class:`CoreBatch`:
Gymnasium's ``VectorEnv`` (:mod:`swarm_envs.adapters.vector`), TorchRL's ``EnvBase``
(:mod:`swarm_envs.adapters.torchrl_env`) and the stable-baselines3 ``VecEnv`` (``swarm_envs.agents.sb3_vec_env``).

Arrays have leading axes ``(B, N)`` (N agents per copy). Autoreset is Gymnasium's ``NEXT_STEP`` mode: when
copy b's episode ends at step t, step t returns its last observation with ``truncations[b] = True``; the next
``step`` resets copy b (its actions are ignored) and returns its first observation with zero reward, while the
other copies step on. ``reset(seed=s)`` seeds copy b with ``s + b``; copy b seeded with ``s`` reproduces
``swarm_envs.make(env_id, ...)`` reset with ``s`` bit for bit, given the same actions.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from gymnasium import spaces

from swarm_envs.adapters.memory import MAX_COPIES, MAX_TOTAL_ROBOTS, check_memory
from swarm_envs.adapters.views import check_finite_actions, check_reset_options, check_seed, info_arrays, make_layout, real_actions, resolve_config
from swarm_envs.core import SwarmCore
from swarm_envs.sim.platforms import get_platform
from swarm_envs.tasks._task_checks import checked_markers
from swarm_envs.tasks.settings import SettingsError
from swarm_envs.tasks.task import Task

__all__ = ["CoreBatch"]


class CoreBatch:
    """``num_envs`` copies of ``task`` (a ``Task`` subclass, or an env class with a ``TASK``) on one
    :class:`swarm_envs.core.SwarmCore`, with the task's settings ``kwargs`` (module docstring)."""

    def __init__(self, task: type, num_envs: int, **kwargs: Any) -> None:
        if isinstance(num_envs, bool) or not isinstance(num_envs, (int, np.integer)) or not 1 <= num_envs <= MAX_COPIES:
            raise SettingsError("num_envs", f"num_envs must be an integer in [1, {MAX_COPIES}], got {num_envs!r:.80}")
        if kwargs.get("render_mode") is not None:
            raise SettingsError("render_mode", "make_vec does not render; use the single env (swarm_envs.make) with render_mode")
        task_cls = getattr(task, "TASK", task)  # an env class's task
        if not (isinstance(task_cls, type) and issubclass(task_cls, Task)) or task_cls is Task:
            raise TypeError(
                f"a batched env needs a subclass of swarm_envs.Task that implements the hooks (at least rewards), got {task!r:.80}"
            )
        cfg = resolve_config(task_cls, kwargs)
        self.config = cfg
        self.platform = get_platform(cfg["platform"])
        # one copy first: its robots, walls and arrays size the batch before the copies are allocated
        one = task_cls(cfg, self.platform, n_copies=1)
        if one.n_world * int(num_envs) > MAX_TOTAL_ROBOTS:
            raise SettingsError(
                "num_envs", f"{num_envs} copies of {one.n_world} robots exceed {MAX_TOTAL_ROBOTS} robots in one batched core; use fewer copies"
            )
        check_memory(one, int(num_envs))
        self.task = one if num_envs == 1 else task_cls(cfg, self.platform, n_copies=int(num_envs))
        self.layout = make_layout(cfg, self.platform, self.task.n_world)
        self.core = SwarmCore(self.task, self.layout)
        self.num_envs = int(num_envs)
        self.n_agents = self.task.n_agents
        self.possible_agents = [f"robot_{i}" for i in range(self.n_agents)]
        self.max_cycles = self.task.max_cycles
        #: one agent's observation and action spaces
        self.agent_observation_space: spaces.Space = self.layout.space()
        self.agent_action_space: spaces.Box = self.layout.action_space()
        self.rows = self.core.agent_rows()  # (B, N) robot rows of the agents
        self._needs_reset = np.zeros(self.num_envs, dtype=bool)
        self.started = False

    def reset(self, *, seed: int | Sequence[int | None] | None = None, options: dict[str, Any] | None = None):
        """Reset every copy; returns (observations, infos). ``options`` as for the single env, applied to all."""
        seeds = self._seeds(seed)
        pose = check_reset_options(options, self.core.worlds[0])
        for b, s in enumerate(seeds):
            self.core.seed(b, s)
        self.core.start(np.arange(self.num_envs), [pose] * self.num_envs)
        self.core.step(None)
        self._needs_reset[:] = False
        self.started = True
        return self.observations(), self.infos()

    def step(self, actions: np.ndarray):
        """Step every copy with ``actions`` (B, N, A); returns (observations, rewards (B, N) float32,
        terminations, truncations (B, N) bool, infos), with autoreset (module docstring)."""
        if not self.started:
            raise RuntimeError("step() called before reset()")
        act = self._check_actions(actions)
        restart = np.flatnonzero(self._needs_reset)
        if restart.size:
            self.core.start(restart)
        full = np.zeros((self.core.n_total, self.layout.action_size))
        full[self.rows.reshape(-1)] = act.reshape(-1, self.layout.action_size)
        self.core.step(full)
        rewards = self.core.rewards.astype(np.float32)
        rewards[restart] = 0.0
        truncated = self.core.num_cycles >= self.max_cycles
        truncated[restart] = False
        self._needs_reset = truncated.copy()
        truncations = np.repeat(truncated[:, None], self.n_agents, axis=1)
        terminations = np.zeros((self.num_envs, self.n_agents), dtype=bool)
        return self.observations(), rewards, terminations, truncations, self.infos()

    def states(self) -> np.ndarray:
        """Global ground-truth state of every copy, ``(B, state_dim)`` float32: row b is what
        :meth:`swarm_envs.adapters.env.SwarmEnv.state` returns for a single env in copy b's place (robots'
        ``STATE_ROBOT_FIELDS`` in world order, the task's markers (m) sorted by name, episode progress).
        For centralised critics only: never part of an observation. Call after :meth:`reset`. The markers
        come from the task copy by copy (``Task.markers`` takes one copy's positions)."""
        if not self.started:
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

    def observations(self) -> dict[str, np.ndarray] | np.ndarray:
        """The agents' observations of the last step: a dict of (B, N, ...) float32 arrays, or (B, N, D)
        with ``flatten=True`` (keys in ``gymnasium.spaces.flatten``'s sorted order)."""
        parts = self.core.observations()  # fresh arrays every step
        B, N = self.rows.shape
        if self.task.n_static == 0:  # every robot is an agent: the rows are in order, reshape (no copy)
            named = {k: v.reshape(B, N, *v.shape[1:]) for k, v in parts.items()}
        else:
            named = {k: v[self.rows] for k, v in parts.items()}  # (B, N, ...)
        if not self.layout.flatten:
            return named
        flat = [named[k].reshape(B, N, -1) for k in sorted(named)]  # gymnasium.spaces.flatten order for Dict
        return np.concatenate(flat, axis=2).astype(np.float32)

    def infos(self) -> dict[str, Any]:
        """Infos of the last step as arrays (:func:`swarm_envs.adapters.views.info_arrays`) and ``episode_step`` (B,)."""
        return {**info_arrays(self.core, self.rows), "episode_step": self.core.num_cycles.copy()}

    def close(self) -> None:
        """Nothing to release: the copies' worlds and arrays go with the object."""

    # -- checks -----------------------------------------------------------------------------------------
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
