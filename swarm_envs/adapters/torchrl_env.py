"""TorchRL: ``B`` copies of a swarm task as one batched multi-agent ``EnvBase`` over one batched core.

:func:`make_torchrl` (also ``swarm_envs.make_torchrl``) returns a :class:`SwarmTorchRLEnv` with
``batch_size=[B]`` that steps one :class:`swarm_envs.adapters.batch.CoreBatch`: one array program for all
copies, arrays in and out, no Python loop over copies or agents here (the global state's task markers are
computed copy by copy, :meth:`CoreBatch.states`). The tensordict layout is the one of
TorchRL's own multi-agent envs (VMAS, PettingZoo): every robot is an agent of one group (``"agents"``
by default, agents ``robot_0 .. robot_{N-1}``), per-agent entries have shape ``[B, N, ...]``:

- ``(group, "observation")``: the robots' observations from the sensing stack; a nested tensordict
  with one entry per part (``range_bearing`` ``[B, N, K, 7]``, ``messages``, ``scale_free``,
  ``rigid``, ``proprio``) or, with ``flatten=True``, one ``[B, N, D]`` tensor;
- ``(group, "action")`` ``[B, N, 2 + message_bits]`` in [-1, 1] (float32);
- ``(group, "reward")`` ``[B, N, 1]``; ``(group, "done" / "terminated" / "truncated")`` ``[B, N, 1]``
  and the same three at the root ``[B, 1]``;
- ``(group, "info", name)``: per-agent infos as float32 tensors, names ``reward_terms_<term>``,
  ``ground_truth_position`` (m), ``ground_truth_heading`` (rad), ``ground_truth_velocity`` (m/s),
  ``sensing_<statistic>`` (full sensing);
- ``("info", name)`` ``[B]``: the task's metrics per copy (e.g. ``polarisation``) and ``episode_step``;
- ``"state"`` ``[B, state_dim]``: the global ground-truth state (:meth:`CoreBatch.states`, row b
  equal to ``SwarmEnv.state()`` of copy b), for centralised critics only.

The info entries are flat (one level under ``"info"``), which is what BenchMARL's logger reads.

Episodes and resets: every copy of a swarm task runs ``max_cycles`` steps and then truncates, and all
copies start together, so every copy ends at the same step and TorchRL resets them all at once
(``rollout``, collectors). A reset costs one sensing step of the whole batch (the core senses every
copy in one step; the reset copies' step is their first observation), so a reset of only some copies
would move the others: a ``"_reset"`` mask that selects some copies but not all raises ``ValueError``,
an all-false mask leaves everything as it is.

Seeding: ``set_seed(s)`` (or ``seed=s``) makes the next reset seed copy b with ``s + b``; later resets
continue each copy's generator. Copy b then equals copy b of ``swarm_envs.make_vec(env_id, B, ...)`` reset
with ``seed=s`` under the same actions, and a single env reset with ``s + b``, bit for bit.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import torch
from gymnasium import spaces
from tensordict import TensorDict, TensorDictBase
from torchrl.data import Bounded, Categorical, Composite, Unbounded
from torchrl.envs import EnvBase

from swarm_envs._text import shown
from swarm_envs.adapters.torch_threads import set_torch_threads
from swarm_envs.adapters.batch import CoreBatch
from swarm_envs.registry import resolve

__all__ = ["SwarmTorchRLEnv", "make_torchrl"]

#: per-agent info groups of :class:`swarm_envs.adapters.batch.CoreBatch` (``(B, N, ...)`` arrays)
AGENT_INFO_GROUPS = ("reward_terms", "ground_truth", "sensing")


def _box_spec(space: spaces.Box, lead: tuple[int, ...], device: torch.device) -> Bounded:
    low = torch.as_tensor(np.broadcast_to(space.low, lead + space.shape).copy(), dtype=torch.float32)
    high = torch.as_tensor(np.broadcast_to(space.high, lead + space.shape).copy(), dtype=torch.float32)
    return Bounded(low=low, high=high, shape=lead + space.shape, dtype=torch.float32, device=device)


def _check_device(device: Any) -> torch.device | None:
    """``device`` as a ``torch.device``: a ``torch.device`` or a string torch reads (``"cpu"``, ``"cuda:0"``) of a
    device this torch build can allocate on (the simulation runs on the CPU; its tensors are moved there), or
    None (TorchRL's env without a device; the tensors stay on the CPU). ``TypeError`` / ``ValueError`` (one
    line) otherwise."""
    if device is None:
        return None
    if not isinstance(device, (str, torch.device)):
        raise TypeError(f"device must be a torch.device or a device string such as 'cpu' or 'cuda:0', got {shown(device)}")
    try:
        parsed = torch.device(device)
    except (RuntimeError, ValueError):
        raise ValueError(f"device={shown(device)} is not a torch device; use 'cpu' (or an accelerator of this machine such as 'cuda:0')") from None
    if parsed.type == "meta":
        raise ValueError(f"device={shown(device)} holds no data; use 'cpu' (or an accelerator of this machine such as 'cuda:0')")
    if parsed.type != "cpu":
        try:
            torch.empty(1, device=parsed)
        except Exception as err:  # torch raises AssertionError, RuntimeError, NotImplementedError ... for a missing device
            detail = " ".join(str(err).split())[:120]
            raise ValueError(
                f"device={shown(device)} is not available in this torch build ({type(err).__name__}: {detail}); the simulation runs on "
                "the CPU, use device='cpu'"
            ) from None
    return parsed


def _keys(tensordict: TensorDictBase) -> str:
    """The tensordict's keys, nested ones as tuples, cut short for an error message."""
    return shown(sorted(map(str, tensordict.keys(include_nested=True, leaves_only=True))), 160)


def _agent_infos(infos: dict[str, Any]) -> dict[str, np.ndarray]:
    """The vector env's per-agent infos as flat ``<group>_<name>`` -> (B, N, ...) float32 arrays."""
    return {
        f"{group}_{name}": np.asarray(value, dtype=np.float32)
        for group in AGENT_INFO_GROUPS
        for name, value in infos[group].items()
    }


def _copy_infos(infos: dict[str, Any]) -> dict[str, np.ndarray]:
    """The vector env's per-copy infos (metrics, episode step) as name -> (B,) float32 arrays."""
    out = {name: np.asarray(value, dtype=np.float32) for name, value in infos["metrics"].items()}
    out["episode_step"] = np.asarray(infos["episode_step"], dtype=np.float32)
    return out


class SwarmTorchRLEnv(EnvBase):
    """``num_envs`` copies of the registered task ``env_id`` as one TorchRL multi-agent env (module docstring).

    Args:
        env_id: a registered id, e.g. ``"swarm_envs/Flocking-v0"``, or a ``Task`` / ``SwarmEnv`` subclass.
        num_envs: number of copies B (the env's ``batch_size``).
        device: device of the returned tensors (the simulation runs on the CPU): a ``torch.device`` or a string
            torch reads, of a device this torch build has (``"cpu"``, ``"cuda:0"``); ``TypeError`` /
            ``ValueError`` otherwise.
        group: name of the agent group (the tensordict key of the per-agent entries).
        seed: if given, seeds the first reset (:meth:`set_seed`).
        torch_threads: torch's intra-op thread count, set at construction
            (:func:`swarm_envs.adapters.torch_threads.set_torch_threads`: None = 1 on at most 2 cores, else
            ``min(4, cores // 2)``, or ``OMP_NUM_THREADS`` if set); ``0`` leaves torch's setting alone.
        **env_kwargs: the task's settings, as for ``swarm_envs.make_vec`` (e.g. ``n_robots``, ``sensing``,
            ``flatten``, ``max_cycles``).
    """

    def __init__(
        self,
        env_id: str | type,
        num_envs: int,
        *,
        device: str | torch.device = "cpu",
        group: str = "agents",
        seed: int | None = None,
        torch_threads: int | None = None,
        **env_kwargs: Any,
    ) -> None:
        if not isinstance(group, str) or not group or group in ("info", "state", "done", "terminated", "truncated", "next"):
            raise ValueError(f"group must be a non-empty name other than the root keys, got {group!r}")
        device = _check_device(device)
        if torch_threads != 0:
            set_torch_threads(torch_threads)
        entry, defaults = resolve(env_id)  # an id (with its default settings) or a Task / SwarmEnv class
        vec = CoreBatch(entry, num_envs, **{**defaults, **env_kwargs})
        super().__init__(device=device, batch_size=torch.Size([vec.num_envs]))
        self.env_id = env_id
        self.vec = vec
        self.group = group
        self.n_agents = vec.n_agents
        self.max_cycles = vec.max_cycles
        #: group name -> agent names, as TorchRL's multi-agent envs have it
        self.group_map: dict[str, list[str]] = {group: list(vec.possible_agents)}
        self._seed: int | None = None
        self._episode_over = np.zeros(vec.num_envs, dtype=bool)
        self._last: TensorDictBase | None = None
        # the info names and shapes come from the task and the sensing mode: read them off one reset
        _, infos = vec.reset()
        self._make_specs(infos)
        if seed is not None:
            self.set_seed(seed)

    # -- specs ----------------------------------------------------------------------------------------
    def _make_specs(self, infos: dict[str, Any]) -> None:
        B, N, dev = self.vec.num_envs, self.n_agents, self.device
        space = self.vec.agent_observation_space
        if isinstance(space, spaces.Dict):
            observation = Composite({k: _box_spec(v, (B, N), dev) for k, v in space.spaces.items()}, shape=(B, N), device=dev)
        else:
            observation = _box_spec(space, (B, N), dev)
        agent_info = Composite(
            {k: Unbounded(shape=v.shape, dtype=torch.float32, device=dev) for k, v in _agent_infos(infos).items()}, shape=(B, N), device=dev
        )
        copy_info = Composite(
            {k: Unbounded(shape=(B,), dtype=torch.float32, device=dev) for k in _copy_infos(infos)}, shape=(B,), device=dev
        )
        state_dim = self.vec.states().shape[1]
        self.observation_spec = Composite(
            {
                self.group: Composite({"observation": observation, "info": agent_info}, shape=(B, N), device=dev),
                "info": copy_info,
                "state": Unbounded(shape=(B, state_dim), dtype=torch.float32, device=dev),
            },
            shape=(B,),
            device=dev,
        )
        action = _box_spec(self.vec.agent_action_space, (B, N), dev)
        self.action_spec = Composite({self.group: Composite({"action": action}, shape=(B, N), device=dev)}, shape=(B,), device=dev)
        self.reward_spec = Composite(
            {self.group: Composite({"reward": Unbounded(shape=(B, N, 1), dtype=torch.float32, device=dev)}, shape=(B, N), device=dev)},
            shape=(B,),
            device=dev,
        )

        def flags(shape: tuple[int, ...]) -> dict[str, Categorical]:
            return {k: Categorical(n=2, shape=shape, dtype=torch.bool, device=dev) for k in ("done", "terminated", "truncated")}

        self.done_spec = Composite(
            {**flags((B, 1)), self.group: Composite(flags((B, N, 1)), shape=(B, N), device=dev)}, shape=(B,), device=dev
        )

    # -- reset / step ---------------------------------------------------------------------------------
    def _set_seed(self, seed: int | None) -> None:
        self._seed = seed

    def _reset(self, tensordict: TensorDictBase | None = None, **kwargs: Any) -> TensorDictBase:
        mask = self._reset_mask(tensordict)
        if mask is not None and not mask.any():
            if self._last is None:
                raise RuntimeError("reset with an all-false '_reset' mask before the first reset")
            return self._last.clone()
        if mask is not None and not mask.all():
            raise ValueError(
                f"'_reset' selects copies {np.flatnonzero(mask).tolist()[:8]} but not all {mask.size}: the batched core "
                "senses every copy in one step, so resetting some copies would move the others; reset all copies"
            )
        seed, self._seed = self._seed, None
        obs, infos = self.vec.reset(seed=seed)
        self._episode_over[:] = False
        B, N = self.vec.num_envs, self.n_agents
        no = np.zeros((B, N, 1), dtype=bool)
        out = self._tensordict(obs, infos, None, no, no)
        self._last = out
        return out

    def _step(self, tensordict: TensorDictBase) -> TensorDictBase:
        if self._episode_over.any():
            raise RuntimeError("step after the episodes ended: reset the env (TorchRL's rollout and collectors do)")
        action = tensordict.get((self.group, "action"), None)
        if not isinstance(action, torch.Tensor):
            got = "it has no such entry" if action is None else f"it holds a {type(action).__name__}"
            raise ValueError(
                f"step needs the actions as the tensor entry {(self.group, 'action')!r} of shape "
                f"{tuple(self.action_spec[self.group, 'action'].shape)}; {got} (keys: {_keys(tensordict)})"
            )
        obs, rewards, terminations, truncations, infos = self.vec.step(action.detach().cpu().numpy())
        self._episode_over = terminations.any(axis=1) | truncations.any(axis=1)
        out = self._tensordict(obs, infos, rewards, terminations[..., None], truncations[..., None])
        self._last = out.exclude((self.group, "reward"))
        return out

    # -- helpers --------------------------------------------------------------------------------------
    def _reset_mask(self, tensordict: TensorDictBase | None) -> np.ndarray | None:
        """(B,) copies a ``"_reset"`` entry (root or group) selects; None when there is none."""
        if tensordict is None:
            return None
        mask = None
        for key in ("_reset", (self.group, "_reset")):
            value = tensordict.get(key, None)
            if value is not None:
                m = value.reshape(self.vec.num_envs, -1).any(dim=1).cpu().numpy()
                mask = m if mask is None else mask | m
        return mask

    def _tensordict(self, obs: Any, infos: dict[str, Any], rewards: np.ndarray | None, terminated: np.ndarray, truncated: np.ndarray) -> TensorDictBase:
        """The output tensordict from the vector env's arrays (``torch.from_numpy``: no copies of fresh arrays)."""
        B, N = self.vec.num_envs, self.n_agents
        if isinstance(obs, dict):
            observation: Any = TensorDict({k: torch.from_numpy(v) for k, v in obs.items()}, batch_size=(B, N))
        else:
            observation = torch.from_numpy(obs)
        terminated_t = torch.from_numpy(terminated)
        truncated_t = torch.from_numpy(truncated)
        done_t = terminated_t | truncated_t
        agent = {
            "observation": observation,
            "info": TensorDict({k: torch.from_numpy(v) for k, v in _agent_infos(infos).items()}, batch_size=(B, N)),
            "done": done_t,
            "terminated": terminated_t,
            "truncated": truncated_t,
        }
        if rewards is not None:
            agent["reward"] = torch.from_numpy(rewards).unsqueeze(-1)
        out = TensorDict(
            {
                self.group: TensorDict(agent, batch_size=(B, N)),
                "info": TensorDict({k: torch.from_numpy(v) for k, v in _copy_infos(infos).items()}, batch_size=(B,)),
                "state": torch.from_numpy(self.vec.states()),
                "done": done_t.any(dim=1),
                "terminated": terminated_t.any(dim=1),
                "truncated": truncated_t.any(dim=1),
            },
            batch_size=(B,),
        )
        return out if self.device == torch.device("cpu") else out.to(self.device)


def make_torchrl(env_id: str | type, num_envs: int, *, device: str | torch.device = "cpu", group: str = "agents", **env_kwargs: Any) -> SwarmTorchRLEnv:
    """``num_envs`` copies of the registered task ``env_id`` as one batched TorchRL multi-agent env.

    Example::

        env = swarm_envs.make_torchrl("swarm_envs/Flocking-v0", 64, n_robots=10, seed=0)
        td = env.rollout(100)            # [100, 64]; td["next", "agents", "reward"]: [100, 64, 10, 1]

    Keyword arguments besides ``device`` and ``group`` go to :class:`SwarmTorchRLEnv` (``seed``,
    ``torch_threads``) and to the task (``n_robots``, ``sensing``, ``flatten``, ...).
    """
    return SwarmTorchRLEnv(env_id, num_envs, device=device, group=group, **env_kwargs)
