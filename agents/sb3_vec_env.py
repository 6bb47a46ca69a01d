"""Adapter: the batched core (``swarm_envs.make_vec``) as one stable-baselines3 ``VecEnv`` (parameter sharing).

Every robot of every env copy is one row: row ``c * n_agents + i`` is agent ``possible_agents[i]`` of copy
``c``, so one policy network acts for all robots (parameter sharing). ``num_envs = n_copies * n_agents``.
All copies are stepped by one :class:`swarm_envs.vector.SwarmVectorEnv` (one array program, no loop over
copies here).

- observations: the flat observation (``flatten=True`` is forced), float32 ``(num_envs, D)``;
- actions: ``(num_envs, A)``, reshaped to ``(n_copies, n_agents, A)``;
- auto-reset (SB3's convention: the returned observation after ``done`` is the next episode's first):
  the swarm tasks end every agent of every copy together (episodes truncate after ``max_cycles`` and all
  copies start together), so at an episode end all copies restart at once, continuing their generators;
  done rows get ``infos[row]["terminal_observation"]``, ``"TimeLimit.truncated"`` (so PPO bootstraps) and
  ``"episode" = {"r", "l", "t"}`` (what SB3's ``Monitor`` adds, so ``ep_rew_mean`` is logged);
- the vector env's array infos of the last step (metrics, reward terms, ground truth) are in
  :attr:`SwarmVecEnv.last_infos` rather than in per-row dicts;
- seeding: :meth:`seed` (SB3) gives each row a seed; copy ``c`` resets with the seed of its first row.

Also :class:`SB3Policy`, which wraps a trained SB3 model as an :class:`agents.base.Policy`.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from stable_baselines3.common.vec_env import VecEnv

from swarm_envs.agents.base import Policy, flatten_batch
from swarm_envs.registry import env_class

__all__ = ["SwarmVecEnv", "SB3Policy"]


def _env_class(env: str | type | Callable[..., Any]) -> type:
    """The task's env class from an env id, the class itself, or a task module's ``parallel_env``."""
    if isinstance(env, str):
        return env_class(env)
    if isinstance(env, type):
        return env
    module = sys.modules.get(getattr(env, "__module__", ""), None)
    if module is None or not hasattr(module, "raw_env"):
        raise TypeError(f"expected an env id, a swarm env class or a task's parallel_env function, got {env!r}")
    return module.raw_env


class SwarmVecEnv(VecEnv):
    """``n_copies`` copies of a swarm task as one SB3 ``VecEnv`` (one row per robot).

    Args:
        env: an env id (``"swarm_envs/Aggregation-v0"``), a task's env class, or its ``parallel_env``.
        n_copies: env copies stepped together by the batched core.
        env_kwargs: env settings (``flatten`` is forced to True).
    """

    def __init__(self, env: str | type | Callable[..., Any], n_copies: int = 1, env_kwargs: dict[str, Any] | None = None) -> None:
        from swarm_envs.vector import SwarmVectorEnv

        if isinstance(n_copies, bool) or not isinstance(n_copies, (int, np.integer)) or n_copies < 1:
            raise ValueError(f"n_copies must be an integer >= 1, got {n_copies!r}")
        kwargs = dict(env_kwargs or {})
        kwargs["flatten"] = True
        self.vec = SwarmVectorEnv(_env_class(env), int(n_copies), **kwargs)
        self.agents = list(self.vec.possible_agents)
        self.n_agents = len(self.agents)
        self.n_copies = int(n_copies)
        self.layout = self.vec.layout
        self.platform = self.vec.platform
        self.num_envs = self.n_copies * self.n_agents  # needed by get_attr during VecEnv.__init__
        super().__init__(self.num_envs, self.vec.agent_observation_space, self.vec.agent_action_space)
        self._actions: np.ndarray | None = None
        self._returns = np.zeros(self.num_envs)
        self._lengths = np.zeros(self.num_envs, dtype=np.int64)
        self._t0 = time.time()
        self.last_infos: dict[str, Any] = {}

    # -- row bookkeeping ---------------------------------------------------------------------------------
    def rows(self, copy: int) -> slice:
        """The rows of env copy ``copy``."""
        return slice(copy * self.n_agents, (copy + 1) * self.n_agents)

    def row_of(self, copy: int, agent: str) -> int:
        """The row of ``agent`` in env copy ``copy``."""
        return copy * self.n_agents + self.agents.index(agent)

    # -- VecEnv API ----------------------------------------------------------------------------------------
    def reset(self) -> np.ndarray:
        seeds = [self._seeds[c * self.n_agents] for c in range(self.n_copies)]
        options = self._options[0] or None
        obs, self.last_infos = self.vec.reset(seed=seeds, options=options)
        # seeds and options are used once (as in SB3's DummyVecEnv); later resets continue the generators
        self._reset_seeds()
        self._reset_options()
        self._returns[:] = 0.0
        self._lengths[:] = 0
        return obs.reshape(self.num_envs, -1)

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.asarray(actions)

    def step_wait(self):
        actions = self._actions
        if actions is None:
            raise RuntimeError("step_wait() called without step_async()")
        self._actions = None
        obs, rew, term, trunc, self.last_infos = self.vec.step(actions.reshape(self.n_copies, self.n_agents, -1))
        obs = obs.reshape(self.num_envs, -1)
        rewards = rew.reshape(-1).astype(np.float32)
        dones = (term | trunc).reshape(-1)
        self._returns += rewards
        self._lengths += 1
        infos: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        if dones.any():
            if not dones.all():
                raise NotImplementedError("copies ended at different times; the SB3 adapter needs all copies to end together")
            truncated = (trunc & ~term).reshape(-1)
            t = round(time.time() - self._t0, 6)
            for row in range(self.num_envs):
                infos[row] = {
                    "terminal_observation": obs[row],
                    "TimeLimit.truncated": bool(truncated[row]),
                    "episode": {"r": float(self._returns[row]), "l": int(self._lengths[row]), "t": t},
                }
            self._returns[:] = 0.0
            self._lengths[:] = 0
            obs, self.last_infos = self.vec.reset()  # every copy restarts now, continuing its generator
            obs = obs.reshape(self.num_envs, -1)
        return obs, rewards, dones, infos

    def close(self) -> None:
        self.vec.close()

    def get_attr(self, attr_name: str, indices=None) -> list[Any]:
        rows = list(self._get_indices(indices))
        value = None if attr_name == "render_mode" else getattr(self.vec, attr_name)
        return [value for _ in rows]

    def set_attr(self, attr_name: str, value: Any, indices=None) -> None:
        raise AttributeError("the copies share one batched core: set attributes on SwarmVecEnv.vec for all copies")

    def env_method(self, method_name: str, *method_args, indices=None, **method_kwargs) -> list[Any]:
        result = getattr(self.vec, method_name)(*method_args, **method_kwargs)
        return [result for _ in self._get_indices(indices)]

    def env_is_wrapped(self, wrapper_class, indices=None) -> list[bool]:
        return [False for _ in self._get_indices(indices)]

    def get_images(self) -> Sequence[np.ndarray | None]:
        return [None for _ in range(self.n_copies)]


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
