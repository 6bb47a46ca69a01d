"""Policy classes as configuration: what ``train.py`` builds around PPO from the config's ``agent`` section.

Every variant is made of stable-baselines3 / sb3-contrib extension points, never a PPO of its own:

- ``algorithm``: ``"ppo"`` (SB3 ``PPO``) or ``"recurrent_ppo"`` (sb3-contrib ``RecurrentPPO``, an LSTM in
  the actor and the critic; episode starts come from the ``VecEnv``'s dones, so autoresets cut the memory);
- ``encoder``: ``"mlp"`` (the flat observation into the MLP) or ``"deepsets"`` (:class:`SetEncoder`, a
  permutation-invariant encoder over the neighbour and message rows that masks empty rows: the mean
  embedding of Huettenrauch et al., JMLR 2019);
- ``odometry``: turn every stale body-frame reading back by the robot's own rotation since it was measured
  (:class:`Odometry`, from the robot's last wheel commands and the reading's ``age``: what the firmware can
  compute from its own sensing and odometry; the scripted baselines do the same);
- ``action_repeat``: the policy decides every ``k`` control steps and the action is held in between
  (:class:`DecisionVecEnv`; the discount ``gamma`` applies per decision, the rewards of the held steps are
  summed);
- ``frame_stack``: the policy sees its last ``n`` decision-time observations (SB3 ``VecFrameStack``).

The same pipeline runs at evaluation (:class:`TrainedPolicy`), on the env's own observations: odometry every
control step, decisions every ``action_repeat`` steps, frames stacked per decision (SB3's
``StackedObservations``), the LSTM state carried between decisions and cleared at reset.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import torch
from stable_baselines3.common.torch_layers import BaseFeaturesExtractor
from stable_baselines3.common.vec_env import VecEnv, VecEnvWrapper

from swarm_envs.agents.base import Policy, flatten_batch
from swarm_envs.adapters.env import DT
from swarm_envs.sensing.observation import ObservationLayout
from swarm_envs.sim.platforms import Platform
from swarm_envs.sim.world import N_BUMP_SECTORS
from swarm_envs.sim.motion import wheel_limited

__all__ = [
    "PolicySpec",
    "Odometry",
    "DecisionVecEnv",
    "SetEncoder",
    "row_groups",
    "wrap_training_env",
    "build_model",
    "algorithm_class",
    "TrainedPolicy",
    "part_indices",
]

#: the row blocks of the observation that :class:`SetEncoder` pools over: base part, its id part
ROW_PARTS = (("range_bearing", "range_bearing_ids"), ("scale_free", "scale_free_ids"), ("messages", "message_ids"))


@dataclass(frozen=True)
class PolicySpec:
    """The policy variant of a config's ``agent`` section (module docstring)."""

    algorithm: str = "ppo"
    encoder: str = "mlp"
    odometry: bool = False
    action_repeat: int = 1
    frame_stack: int = 1
    set_embedding: int = 64
    lstm_hidden: int = 64

    @classmethod
    def from_agent(cls, agent: dict[str, Any]) -> PolicySpec:
        """The spec of a resolved ``agent`` config section (keys missing there take the defaults)."""
        return cls(**{k: agent[k] for k in cls.__dataclass_fields__ if k in agent})

    @property
    def name(self) -> str:
        """A short label, e.g. ``ppo+deepsets+odometry``."""
        parts = [self.algorithm, *(["deepsets"] if self.encoder == "deepsets" else [])]
        parts += ["odometry"] if self.odometry else []
        parts += [f"repeat{self.action_repeat}"] if self.action_repeat > 1 else []
        parts += [f"stack{self.frame_stack}"] if self.frame_stack > 1 else []
        return "+".join(parts)


# -- odometry ---------------------------------------------------------------------------------------------
def part_indices(layout: ObservationLayout) -> dict[str, np.ndarray]:
    """``{part: flat indices in the part's shape}``: the layout's own unflattening of ``0 .. D - 1``."""
    size = sum(int(np.prod(box.shape)) for box in layout.dict_space().spaces.values())
    return layout.unflatten(np.arange(size))


def _rotate(cos_sin: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """(..., 2) unit vectors turned by ``-angle`` (rad)."""
    c, s = np.cos(angle), np.sin(angle)
    x, y = cos_sin[..., 0], cos_sin[..., 1]
    return np.stack([x * c + y * s, y * c - x * s], axis=-1)


class Odometry:
    """Turn stale body-frame readings back by the robot's own rotation since they were measured.

    An r-one sector bearing refreshes only when a frame of that neighbour is decoded (once per beacon
    round, [L Sec. 3.2.2]); a Droplet / e-puck reading persists ``age`` steps. In the body frame such a
    reading is off by however much the robot turned since. The robot knows its wheel commands: from the last
    action in ``proprio`` (wheel-limited as the motors take it) it integrates its rotation over the last
    ``max_age`` steps and turns each ``range_bearing`` row's bearing and relative heading back by the
    rotation since the row's ``age``; the ``scale_free`` block, which has no age column, is turned back by
    the rotation since it last changed. Works on flat rows (N, D) in place of the env's layout.
    """

    def __init__(self, layout: ObservationLayout, platform: Platform) -> None:
        index = part_indices(layout)
        self.rb_index, self.sf_index = index["range_bearing"], index["scale_free"]  # (K, 7), (K, 3)
        self.action_index = index["proprio"][N_BUMP_SECTORS : N_BUMP_SECTORS + 2]  # last (linear, angular) command
        self.history = int(layout.max_age) + 1
        self.platform = platform
        self.reset(0)

    def reset(self, n: int) -> None:
        """Start a new episode for ``n`` rows."""
        self.turned = np.zeros((n, self.history))  # own rotation (rad) per step, newest first
        self.sf_since = np.zeros(n, dtype=np.int64)  # steps since the scale_free block changed
        self.sf_last: np.ndarray | None = None

    def __call__(self, flat: np.ndarray) -> np.ndarray:
        """The next step's flat observations (N, D) with the readings turned to the current body frame."""
        flat = np.array(flat, dtype=np.float32)
        n = len(flat)
        if self.turned.shape[0] != n:
            self.reset(n)
        command = flat[:, self.action_index].astype(np.float64)
        _, angular = wheel_limited(self.platform, command[:, 0] * self.platform.max_speed, command[:, 1] * self.platform.max_angular_speed)
        self.turned = np.roll(self.turned, 1, axis=1)
        self.turned[:, 0] = angular * DT
        since = np.concatenate([np.zeros((n, 1)), np.cumsum(self.turned, axis=1)], axis=1)  # since[:, a] = a steps

        rb = flat[:, self.rb_index]
        age = np.clip(np.rint(rb[..., 6]).astype(np.int64), 0, self.history)
        angle = np.take_along_axis(since, age, axis=1) * (rb[..., 0] > 0.5)
        rb[..., 2:4] = _rotate(rb[..., 2:4], angle)
        rb[..., 4:6] = _rotate(rb[..., 4:6], angle)
        flat[:, self.rb_index] = rb

        sf = flat[:, self.sf_index]
        if self.sf_last is not None:
            changed = np.any(sf != self.sf_last, axis=(1, 2))
            self.sf_since = np.where(changed, 0, np.minimum(self.sf_since + 1, self.history))
        self.sf_last = sf.copy()
        sf_angle = since[np.arange(n), self.sf_since][:, None] * (sf[..., 0] > 0.5)
        sf[..., 1:3] = _rotate(sf[..., 1:3], sf_angle)
        flat[:, self.sf_index] = sf
        return flat


# -- decisions --------------------------------------------------------------------------------------------
class DecisionVecEnv(VecEnvWrapper):
    """A swarm ``VecEnv`` seen at decision times: :class:`Odometry` on every control step (if ``odometry``),
    and each action held for ``action_repeat`` control steps, their rewards summed (``gamma`` then discounts
    per decision). An episode that ends inside a held action ends the decision there."""

    def __init__(self, venv: VecEnv, layout: ObservationLayout, platform: Platform, odometry: bool, action_repeat: int) -> None:
        super().__init__(venv)
        self.odometry = Odometry(layout, platform) if odometry else None
        self.action_repeat = int(action_repeat)
        self._actions: np.ndarray | None = None

    def _features(self, obs: np.ndarray) -> np.ndarray:
        return obs if self.odometry is None else self.odometry(obs)

    def reset(self) -> np.ndarray:
        obs = self.venv.reset()
        if self.odometry is not None:
            self.odometry.reset(len(obs))
        return self._features(obs)

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = np.asarray(actions)

    def step_wait(self):
        total = np.zeros(self.num_envs, dtype=np.float32)
        for _ in range(self.action_repeat):
            obs, rewards, dones, infos = self.venv.step(self._actions)
            total += rewards
            if dones.any():
                if self.odometry is not None:
                    for info in infos:
                        if "terminal_observation" in info:
                            info["terminal_observation"] = self._features(info["terminal_observation"][None])[0]
                    self.odometry.reset(len(obs))
                return self._features(obs), total, dones, infos
            obs = self._features(obs)
        return obs, total, dones, infos


def wrap_training_env(venv: VecEnv, spec: PolicySpec, layout: ObservationLayout, platform: Platform) -> VecEnv:
    """The swarm ``VecEnv`` as the policy variant ``spec`` sees it (odometry, action repeat, frame stack)."""
    if spec.odometry or spec.action_repeat > 1:
        venv = DecisionVecEnv(venv, layout, platform, spec.odometry, spec.action_repeat)
    if spec.frame_stack > 1:
        from stable_baselines3.common.vec_env import VecFrameStack

        venv = VecFrameStack(venv, spec.frame_stack)
    return venv


# -- set encoder ------------------------------------------------------------------------------------------
def row_groups(layout: ObservationLayout) -> dict[str, Any]:
    """What :class:`SetEncoder` needs of a layout, as plain numbers (saved with the model): per row block,
    the flat indices of each row's features (base part, then its id part, whose rows are the same
    neighbours); and the indices of the rest (``proprio``, ``rigid``, ``own_id``)."""
    index = part_indices(layout)
    groups, used = [], []
    for base, ids in ROW_PARTS:
        rows = index[base] if ids not in index else np.concatenate([index[base], index[ids]], axis=1)
        groups.append({"index": rows.tolist()})
        used.append(rows.ravel())
    size = sum(part.size for part in index.values())
    rest = np.setdiff1d(np.arange(size), np.concatenate(used))
    return {"groups": groups, "rest": rest.tolist(), "size": size}


class SetEncoder(BaseFeaturesExtractor):
    """DeepSets over each row block: ``phi`` (a 2-layer MLP per block) on every row, the mean over valid rows
    (an empty block gives zeros) and the share of valid rows, concatenated with the other parts; the same
    weights for each stacked frame. Permutation-invariant within a block; empty rows never reach the mean.

    Args:
        observation_space: the (stacked) flat observation space.
        groups: :func:`row_groups` of the env's layout.
        embedding: width of ``phi``'s output per block.
        n_stack: stacked frames in one observation.
    """

    def __init__(self, observation_space, groups: dict[str, Any], embedding: int = 64, n_stack: int = 1) -> None:
        rest, size = groups["rest"], groups["size"]
        per_frame = len(groups["groups"]) * (embedding + 1) + len(rest)
        super().__init__(observation_space, per_frame * n_stack)
        if observation_space.shape[-1] != size * n_stack:
            raise ValueError(f"SetEncoder: observation size {observation_space.shape[-1]} is not {n_stack} x {size}")
        self.size, self.n_stack = size, n_stack
        for i, g in enumerate(groups["groups"]):
            self.register_buffer(f"_index{i}", torch.as_tensor(g["index"], dtype=torch.long), persistent=False)
        self.register_buffer("_rest", torch.as_tensor(rest, dtype=torch.long), persistent=False)
        self.phis = torch.nn.ModuleList(
            torch.nn.Sequential(torch.nn.Linear(len(g["index"][0]), embedding), torch.nn.Tanh(), torch.nn.Linear(embedding, embedding), torch.nn.Tanh())
            for g in groups["groups"]
        )

    def forward(self, observations: torch.Tensor) -> torch.Tensor:
        frames = observations.reshape(-1, self.size)  # (batch * n_stack, size)
        parts = []
        for i, phi in enumerate(self.phis):
            rows = frames[:, getattr(self, f"_index{i}")]  # (B, K, F)
            valid = (rows[..., 0] > 0.5).to(rows.dtype)  # column 0 of every base part is ``valid``
            count = valid.sum(dim=1, keepdim=True)
            pooled = (phi(rows) * valid[..., None]).sum(dim=1) / count.clamp(min=1.0)
            parts += [pooled, count / rows.shape[1]]
        parts.append(frames[:, self._rest])
        return torch.cat(parts, dim=1).reshape(observations.shape[0], -1)


# -- models -----------------------------------------------------------------------------------------------
def algorithm_class(spec: PolicySpec):
    """SB3 ``PPO`` or sb3-contrib ``RecurrentPPO``."""
    if spec.algorithm == "recurrent_ppo":
        from sb3_contrib import RecurrentPPO

        return RecurrentPPO
    from stable_baselines3 import PPO

    return PPO


def build_model(agent: dict[str, Any], vec_env: VecEnv, layout: ObservationLayout, seed: int):
    """The model of an ``agent`` config section for ``vec_env`` (already wrapped by :func:`wrap_training_env`)."""
    spec = PolicySpec.from_agent(agent)
    activation = {"tanh": torch.nn.Tanh, "relu": torch.nn.ReLU}[agent["activation"]]
    policy_kwargs: dict[str, Any] = {"net_arch": list(agent["net_arch"]), "activation_fn": activation, "log_std_init": agent["log_std_init"]}
    if spec.encoder == "deepsets":
        policy_kwargs["features_extractor_class"] = SetEncoder
        policy_kwargs["features_extractor_kwargs"] = {"groups": row_groups(layout), "embedding": spec.set_embedding, "n_stack": spec.frame_stack}
    if spec.algorithm == "recurrent_ppo":
        policy_kwargs["lstm_hidden_size"] = spec.lstm_hidden
    cls = algorithm_class(spec)
    return cls(
        "MlpLstmPolicy" if spec.algorithm == "recurrent_ppo" else "MlpPolicy",
        vec_env,
        learning_rate=agent["learning_rate"],
        n_steps=agent["n_steps"],
        batch_size=agent["batch_size"],
        n_epochs=agent["n_epochs"],
        gamma=agent["gamma"],
        gae_lambda=agent["gae_lambda"],
        clip_range=agent["clip_range"],
        ent_coef=agent["ent_coef"],
        vf_coef=agent["vf_coef"],
        max_grad_norm=agent["max_grad_norm"],
        policy_kwargs=policy_kwargs,
        seed=seed,
        device="cpu",
        verbose=0,
    )


class TrainedPolicy(Policy):
    """A trained model as a :class:`Policy` on the env's own observations, through the same pipeline as in
    training: odometry every control step, a decision every ``action_repeat`` steps (the action held in
    between), the last ``frame_stack`` decision observations, the LSTM state of a recurrent model."""

    name = "ppo"

    def __init__(self, model, platform: Platform, layout: ObservationLayout, spec: PolicySpec | None = None, deterministic: bool = True) -> None:
        super().__init__(platform, layout)
        self.model = model
        self.spec = spec or PolicySpec()
        self.deterministic = deterministic
        self.odometry = Odometry(layout, platform) if self.spec.odometry else None
        self.reset(0)

    def reset(self, n: int, rng: np.random.Generator | None = None) -> None:
        super().reset(n, rng)
        if self.odometry is not None:
            self.odometry.reset(n)
        self._step = 0
        self._held: np.ndarray | None = None
        self._state = None
        self._stack = None
        self._started = False

    def act_batch(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        flat = flatten_batch(self.layout, obs)
        if self.odometry is not None:
            flat = self.odometry(flat)
        decide = self._step % self.spec.action_repeat == 0
        self._step += 1
        if not decide and self._held is not None:
            return self._held
        first, self._started = not self._started, True
        if self.spec.frame_stack > 1:
            from gymnasium import spaces
            from stable_baselines3.common.vec_env.stacked_observations import StackedObservations

            if self._stack is None:
                space = spaces.Box(-np.inf, np.inf, (flat.shape[1],), np.float32)
                self._stack = StackedObservations(len(flat), self.spec.frame_stack, space)
                flat = self._stack.reset(flat)
            else:
                flat, _ = self._stack.update(flat, np.zeros(len(flat), dtype=bool), [{} for _ in range(len(flat))])
        if self.spec.algorithm == "recurrent_ppo":
            starts = np.full(len(flat), first)
            actions, self._state = self.model.predict(flat, state=self._state, episode_start=starts, deterministic=self.deterministic)
        else:
            actions, _ = self.model.predict(flat, deterministic=self.deterministic)
        self._held = np.clip(np.asarray(actions, dtype=np.float32), -1.0, 1.0)
        return self._held
