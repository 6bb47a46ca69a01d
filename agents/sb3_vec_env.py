"""Adapter: the batched core (``swarm_envs.make_vec``) as one stable-baselines3 ``VecEnv`` (parameter sharing).

Every robot of every env copy is one row: row ``c * n_agents + i`` is agent ``possible_agents[i]`` of copy
``c``, so one policy network acts for all robots (parameter sharing). ``num_envs = n_copies * n_agents``.
All copies are stepped by one :class:`swarm_envs.adapters.batch.CoreBatch` (one array program, no loop over
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
- seeding: :meth:`seed` (SB3) gives each row a seed; copy ``c`` resets with the seed of its first row;
- ``n_workers > 1`` splits the copies over that many worker processes (SB3 ``SubprocVecEnv``-style, one
  batched core each, contiguous blocks of copies), for machines with several cores; the workers share the
  trainer's numba threads (``NUMBA_NUM_THREADS``), each ``threads // n_workers`` (at least 1). Each copy
  keeps its own streams, so the rows are the same as with one process. One process already uses every
  core for a large batch (``docs/design.md``, Threads).

Also :class:`SB3Policy`, which wraps a trained SB3 model as an :class:`agents.base.Policy`.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
from stable_baselines3.common.vec_env import VecEnv

from swarm_envs.agents.policies import TrainedPolicy
from swarm_envs.registry import resolve

__all__ = ["SwarmVecEnv", "SB3Policy"]


def _env_entry(env: str | type | Callable[..., Any]) -> tuple[type, dict[str, Any]]:
    """(entry class, default settings) of an env id, a Task or env class, or a task module's ``parallel_env``."""
    if isinstance(env, (str, type)):
        return resolve(env)
    module = sys.modules.get(getattr(env, "__module__", ""), None)
    if module is None or not hasattr(module, "raw_env"):
        raise TypeError(f"expected an env id, a swarm task or env class, or a task's parallel_env function, got {env!r}")
    return module.raw_env, {}


class SwarmVecEnv(VecEnv):
    """``n_copies`` copies of a swarm task as one SB3 ``VecEnv`` (one row per robot).

    Args:
        env: an env id (``"swarm_envs/Aggregation-v0"``), a task's env class, or its ``parallel_env``.
        n_copies: env copies stepped together by the batched core.
        env_kwargs: env settings (``flatten`` is forced to True).
        torch_threads: torch's intra-op thread count, set here for the policy that steps this env
            (:func:`swarm_envs.adapters.torch_threads.set_torch_threads`: None = 1 on at most 2 cores, else
            ``min(4, cores // 2)``, or ``OMP_NUM_THREADS`` if set; torch's default threads made PPO up
            to 25x slower on a loaded 2-core machine); ``0`` leaves torch's setting alone.
    """

    def __init__(
        self, env: str | type | Callable[..., Any], n_copies: int = 1, env_kwargs: dict[str, Any] | None = None, n_workers: int = 1,
        torch_threads: int | None = None,
    ) -> None:
        from swarm_envs.adapters.torch_threads import set_torch_threads
        from swarm_envs.adapters.batch import CoreBatch

        if torch_threads != 0:
            set_torch_threads(torch_threads)

        if isinstance(n_copies, bool) or not isinstance(n_copies, (int, np.integer)) or n_copies < 1:
            raise ValueError(f"n_copies must be an integer >= 1, got {n_copies!r}")
        if isinstance(n_workers, bool) or not isinstance(n_workers, (int, np.integer)) or not 1 <= n_workers <= n_copies:
            raise ValueError(f"n_workers must be an integer in [1, n_copies={n_copies}], got {n_workers!r}")
        env_cls, defaults = _env_entry(env)
        kwargs = {**defaults, **(env_kwargs or {}), "flatten": True}
        self.vec = CoreBatch(env_cls, int(n_copies), **kwargs) if n_workers == 1 else _WorkerVec(env_cls, int(n_copies), kwargs, int(n_workers))
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


def _merge(parts: list[Any]) -> Any:
    """Join the array infos of consecutive copy blocks (dicts of arrays, leading axis = copy)."""
    if isinstance(parts[0], dict):
        return {k: _merge([p[k] for p in parts]) for k in parts[0]}
    return np.concatenate(parts, axis=0)


def _worker(conn, env_cls: type, n_copies: int, kwargs: dict[str, Any], threads: int = 1) -> None:  # pragma: no cover - runs in a child
    import signal

    import numba

    from swarm_envs.adapters.batch import CoreBatch

    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the trainer's to handle; it closes the workers
    numba.set_num_threads(threads)  # the worker's share of the trainer's threads

    vec = CoreBatch(env_cls, n_copies, **kwargs)
    while True:
        cmd, arg = conn.recv()
        if cmd == "reset":
            conn.send(vec.reset(seed=arg[0], options=arg[1]))
        elif cmd == "step":
            conn.send(vec.step(arg))
        elif cmd == "attr":
            conn.send(getattr(vec, arg))
        elif cmd == "close":
            vec.close()
            conn.close()
            return


class _WorkerVec:
    """``n_copies`` copies split over ``n_workers`` processes, each a :class:`swarm_envs.adapters.batch.CoreBatch`
    of a contiguous block of copies; the same reset/step interface as one vector env."""

    def __init__(self, env_cls: type, n_copies: int, kwargs: dict[str, Any], n_workers: int) -> None:
        import multiprocessing as mp

        from swarm_envs.adapters.batch import CoreBatch

        import numba

        ctx = mp.get_context("forkserver" if "forkserver" in mp.get_all_start_methods() else "spawn")
        self.blocks = np.array_split(np.arange(n_copies), n_workers)
        threads = max(1, numba.get_num_threads() // n_workers)  # the workers share this process's threads
        self.conns, self.procs = [], []
        for block in self.blocks:
            parent, child = ctx.Pipe()
            proc = ctx.Process(target=_worker, args=(child, env_cls, len(block), kwargs, threads), daemon=True)
            proc.start()
            child.close()
            self.conns.append(parent)
            self.procs.append(proc)
        probe = CoreBatch(env_cls, 1, **kwargs)  # spaces and layout, without stepping
        self.possible_agents, self.layout, self.platform = probe.possible_agents, probe.layout, probe.platform
        self.agent_observation_space, self.agent_action_space = probe.agent_observation_space, probe.agent_action_space
        self.max_cycles, self.config = probe.max_cycles, probe.config

    def _gather(self, cmd: str, args: list[Any]):
        for conn, arg in zip(self.conns, args):
            conn.send((cmd, arg))
        return [conn.recv() for conn in self.conns]

    def reset(self, *, seed: list[int | None] | None = None, options: dict | None = None):
        seeds = [None] * sum(len(b) for b in self.blocks) if seed is None else list(seed)
        out = self._gather("reset", [([seeds[c] for c in block], options) for block in self.blocks])
        return np.concatenate([o for o, _ in out], axis=0), _merge([i for _, i in out])

    def step(self, actions: np.ndarray):
        out = self._gather("step", [actions[block] for block in self.blocks])
        cat = [np.concatenate([o[k] for o in out], axis=0) for k in range(4)]
        return (*cat, _merge([o[4] for o in out]))

    def close(self) -> None:
        for conn in self.conns:
            try:
                conn.send(("close", None))
            except (BrokenPipeError, OSError):
                pass
        for proc in self.procs:
            proc.join(timeout=5)
            if proc.is_alive():
                proc.terminate()


class SB3Policy(TrainedPolicy):
    """A trained SB3 model (e.g. PPO) of the plain variant as a :class:`Policy`: the flat observation in the
    env's order, one action per step (:class:`swarm_envs.agents.policies.TrainedPolicy` with its defaults)."""

    name = "ppo"

    def __init__(self, model, platform, layout, deterministic: bool = True) -> None:
        super().__init__(model, platform, layout, deterministic=deterministic)
