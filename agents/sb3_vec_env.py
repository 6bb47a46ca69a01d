"""Adapter: several copies of a swarm ``ParallelEnv`` as one stable-baselines3 ``VecEnv`` (parameter sharing).

Every robot of every env copy is one row: row ``c * n_agents + i`` is agent ``possible_agents[i]`` of copy
``c``, so one policy network acts for all robots (parameter sharing). ``num_envs = n_copies * n_agents``.

- observations: the env's flat observation (``flatten=True`` is forced), float32 ``(num_envs, D)``;
- actions: ``(num_envs, A)`` rows are dispatched to the agents of each copy;
- auto-reset: when a copy's episode ends (all its agents terminated or truncated; the swarm tasks end all
  agents together), its rows get ``done=True``, ``infos[row]["terminal_observation"]`` (the last
  observation), ``"TimeLimit.truncated"`` (truncated and not terminated, so PPO bootstraps), the episode
  statistics ``infos[row]["episode"] = {"r": return, "l": length, "t": wall time}`` (what SB3's ``Monitor``
  adds, so ``ep_rew_mean`` is logged), and the returned observation is the first of the next episode;
- seeding: :meth:`seed` (SB3) gives each row a seed; copy ``c`` resets with the seed of its first row.

Also :class:`SB3Policy`, which wraps a trained SB3 model as an :class:`agents.base.Policy`.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from stable_baselines3.common.vec_env import VecEnv

from swarm_envs.agents.base import Policy, flatten_batch

__all__ = ["SwarmVecEnv", "SB3Policy"]


class SwarmVecEnv(VecEnv):
    """``n_copies`` swarm envs built by ``env_fn(**env_kwargs)`` as one SB3 ``VecEnv`` (one row per robot)."""

    def __init__(self, env_fn: Callable[..., Any], n_copies: int = 1, env_kwargs: dict[str, Any] | None = None) -> None:
        if n_copies < 1:
            raise ValueError(f"n_copies must be >= 1, got {n_copies}")
        kwargs = dict(env_kwargs or {})
        kwargs["flatten"] = True
        self.envs = [env_fn(**kwargs) for _ in range(n_copies)]
        first = self.envs[0]
        self.agents = list(first.possible_agents)
        self.n_agents = len(self.agents)
        self.n_copies = n_copies
        obs_space = first.observation_space(self.agents[0])
        act_space = first.action_space(self.agents[0])
        self.num_envs = n_copies * self.n_agents  # needed by get_attr during VecEnv.__init__
        super().__init__(n_copies * self.n_agents, obs_space, act_space)
        self._actions: np.ndarray | None = None
        self._returns = np.zeros(self.num_envs)
        self._lengths = np.zeros(self.num_envs, dtype=np.int64)
        self._t0 = time.time()

    # -- row bookkeeping ---------------------------------------------------------------------------------
    def rows(self, copy: int) -> slice:
        """The rows of env copy ``copy``."""
        return slice(copy * self.n_agents, (copy + 1) * self.n_agents)

    def row_of(self, copy: int, agent: str) -> int:
        """The row of ``agent`` in env copy ``copy``."""
        return copy * self.n_agents + self.agents.index(agent)

    def _stack(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        return np.stack([obs[a] for a in self.agents]).astype(np.float32)

    # -- VecEnv API ----------------------------------------------------------------------------------------
    def reset(self) -> np.ndarray:
        out = np.zeros((self.num_envs,) + self.observation_space.shape, dtype=np.float32)
        for c, env in enumerate(self.envs):
            out[self.rows(c)] = self._reset_copy(c)
        self._returns[:] = 0.0
        self._lengths[:] = 0
        return out

    def _reset_copy(self, c: int) -> np.ndarray:
        first_row = c * self.n_agents
        seed = self._seeds[first_row]
        options = self._options[first_row] or None
        obs, infos = self.envs[c].reset(seed=seed, options=options)
        # seeds and options are used once (as in SB3's DummyVecEnv); later resets continue the env's generator
        for r in range(first_row, first_row + self.n_agents):
            self._seeds[r] = None
            self._options[r] = {}
        for i, a in enumerate(self.agents):
            self.reset_infos[first_row + i] = infos.get(a, {})
        return self._stack(obs)

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.asarray(actions)

    def step_wait(self):
        actions = self._actions
        if actions is None:
            raise RuntimeError("step_wait() called without step_async()")
        actions = actions.reshape(self.num_envs, -1)
        obs_out = np.zeros((self.num_envs,) + self.observation_space.shape, dtype=np.float32)
        rewards = np.zeros(self.num_envs, dtype=np.float32)
        dones = np.zeros(self.num_envs, dtype=bool)
        infos: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        for c, env in enumerate(self.envs):
            rows = self.rows(c)
            act = actions[rows]
            obs, rew, term, trunc, info = env.step({a: act[i] for i, a in enumerate(self.agents)})
            r = np.array([rew[a] for a in self.agents], dtype=np.float32)
            rewards[rows] = r
            self._returns[rows] += r
            self._lengths[rows] += 1
            flags = np.array([term[a] or trunc[a] for a in self.agents])
            if flags.any() and not flags.all():
                raise NotImplementedError("agents of one swarm env finished at different times; the adapter needs all agents to end together")
            stacked = self._stack(obs)
            for i, a in enumerate(self.agents):
                infos[rows.start + i] = dict(info.get(a, {}))
            if flags.all():
                dones[rows] = True
                for i, a in enumerate(self.agents):
                    row = rows.start + i
                    infos[row]["terminal_observation"] = stacked[i]
                    infos[row]["TimeLimit.truncated"] = bool(trunc[a] and not term[a])
                    infos[row]["episode"] = {
                        "r": float(self._returns[row]),
                        "l": int(self._lengths[row]),
                        "t": round(time.time() - self._t0, 6),
                    }
                self._returns[rows] = 0.0
                self._lengths[rows] = 0
                stacked = self._reset_copy(c)
            obs_out[rows] = stacked
        self._actions = None
        return obs_out, rewards, dones, infos

    def close(self) -> None:
        for env in self.envs:
            env.close()

    def _copies(self, indices) -> list[int]:
        rows = self._get_indices(indices)
        return sorted({r // self.n_agents for r in rows})

    def get_attr(self, attr_name: str, indices=None) -> list[Any]:
        rows = list(self._get_indices(indices))
        return [getattr(self.envs[r // self.n_agents], attr_name) for r in rows]

    def set_attr(self, attr_name: str, value: Any, indices=None) -> None:
        for c in self._copies(indices):
            setattr(self.envs[c], attr_name, value)

    def env_method(self, method_name: str, *method_args, indices=None, **method_kwargs) -> list[Any]:
        rows = list(self._get_indices(indices))
        results: dict[int, Any] = {}
        for c in sorted({r // self.n_agents for r in rows}):
            results[c] = getattr(self.envs[c], method_name)(*method_args, **method_kwargs)
        return [results[r // self.n_agents] for r in rows]

    def env_is_wrapped(self, wrapper_class, indices=None) -> list[bool]:
        return [False for _ in self._get_indices(indices)]

    def get_images(self) -> Sequence[np.ndarray | None]:
        return [env.render() for env in self.envs]


class SB3Policy(Policy):
    """A trained SB3 model (e.g. PPO) as a :class:`Policy`; flattens the named batch in the env's order."""

    name = "ppo"

    def __init__(self, model, platform, layout, deterministic: bool = True) -> None:
        super().__init__(platform, layout)
        self.model = model
        self.deterministic = deterministic

    def act_batch(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        flat = flatten_batch(self.layout, obs)
        actions, _ = self.model.predict(flat, deterministic=self.deterministic)
        return np.clip(np.asarray(actions, dtype=np.float32), -1.0, 1.0)
