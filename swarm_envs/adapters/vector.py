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

from collections.abc import Sequence
from typing import Any

import numpy as np
from gymnasium import spaces
from gymnasium.vector import AutoresetMode, VectorEnv

from swarm_envs.adapters.batch import CoreBatch

__all__ = ["SwarmVectorEnv", "AgentsAsEnvs"]


def _batch_space(space: spaces.Box, lead: tuple[int, ...]) -> spaces.Box:
    low = np.broadcast_to(space.low, lead + space.shape)
    high = np.broadcast_to(space.high, lead + space.shape)
    return spaces.Box(low, high, dtype=space.dtype)


class SwarmVectorEnv(VectorEnv):
    """``num_envs`` copies of ``task`` (a ``Task`` subclass or an env class) as a Gymnasium ``VectorEnv``: the
    Gymnasium view of one :class:`swarm_envs.adapters.batch.CoreBatch` (module docstring). ``kwargs``: the
    task's settings."""

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}

    def __init__(self, task: type, num_envs: int, **kwargs: Any) -> None:
        self.batch = batch = CoreBatch(task, num_envs, **kwargs)
        self.config, self.platform, self.task, self.layout, self.core = batch.config, batch.platform, batch.task, batch.layout, batch.core
        self.num_envs, self.n_agents, self.max_cycles = batch.num_envs, batch.n_agents, batch.max_cycles
        self.possible_agents = batch.possible_agents
        self.agent_observation_space = agent_obs = batch.agent_observation_space
        self.agent_action_space = agent_act = batch.agent_action_space
        lead = (self.n_agents,)
        if isinstance(agent_obs, spaces.Dict):
            self.single_observation_space = spaces.Dict({k: _batch_space(v, lead) for k, v in agent_obs.spaces.items()})
            self.observation_space = spaces.Dict({k: _batch_space(v, (self.num_envs,) + lead) for k, v in agent_obs.spaces.items()})
        else:
            self.single_observation_space = _batch_space(agent_obs, lead)
            self.observation_space = _batch_space(agent_obs, (self.num_envs,) + lead)
        self.single_action_space = _batch_space(agent_act, lead)
        self.action_space = _batch_space(agent_act, (self.num_envs,) + lead)

    def reset(self, *, seed: int | Sequence[int | None] | None = None, options: dict[str, Any] | None = None):
        """Reset every copy; returns (observations, infos). ``options`` as for the single env, applied to all."""
        return self.batch.reset(seed=seed, options=options)

    def step(self, actions: np.ndarray):
        """Step every copy with ``actions`` (B, N, A); see the module docstring for outputs and autoreset."""
        return self.batch.step(actions)

    def states(self) -> np.ndarray:
        """Global ground-truth state of every copy, ``(B, state_dim)`` float32
        (:meth:`swarm_envs.adapters.batch.CoreBatch.states`). For centralised critics only."""
        return self.batch.states()

    def close_extras(self, **kwargs: Any) -> None:
        pass


class AgentsAsEnvs(VectorEnv):
    """Every robot of every copy as one sub-env: ``num_envs = B x N`` rows (row ``b * N + i`` is agent i of
    copy b), for Gymnasium's vector wrappers and single-agent libraries (parameter sharing, as SuperSuit's
    ``pettingzoo_env_to_vec_env_v1`` does). A view of one :class:`swarm_envs.adapters.batch.CoreBatch` (or :class:`SwarmVectorEnv`): observations ``(B N, ...)``,
    actions ``(B N, A)``, rewards, terminations and truncations ``(B N,)``, infos with ``B N`` rows (per-copy
    values repeated for each of its robots). Autoreset as :class:`SwarmVectorEnv` (``NEXT_STEP``): all robots
    of a copy end and restart together.

    Example::

        vec = swarm_envs.make_vec("swarm_envs/Flocking-v0", 16, agents_as_envs=True, flatten=True)
        vec = gymnasium.wrappers.vector.RecordEpisodeStatistics(vec)
        vec = gymnasium.wrappers.vector.NormalizeObservation(vec)
    """

    metadata = {"autoreset_mode": AutoresetMode.NEXT_STEP, "render_modes": []}

    def __init__(self, vec: CoreBatch | SwarmVectorEnv) -> None:
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
