"""The policy interface every baseline (scripted, random, RL) implements.

A policy maps observations to actions for a batch of robots at once:

- :meth:`Policy.act_batch` takes the **named, batched** observation dict (``range_bearing`` (N, K, 7),
  ``messages`` (N, M, 2+b), ``scale_free`` (N, K, 3), ``rigid`` (N, 1), ``proprio`` (N, 8+A); the layout of
  :class:`swarm_envs.sensing.observation.ObservationLayout`) and returns actions ``(N, A)`` in [-1, 1];
- :meth:`Policy.act` is the single-robot convenience (row 0 of a batch of one);
- :meth:`Policy.reset` starts a new episode for ``n`` robots (stateful behaviours such as the random walk keep
  per-row timers; row i is always the same robot within an episode).

Policies only ever see observations and their own platform's specification (speeds, wheel base); never
``infos`` or ground truth.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import Any

import numpy as np
from swarm_envs.sensing.observation import ObservationLayout
from swarm_envs.sim.platforms import Platform

__all__ = ["Policy", "RandomPolicy", "flatten_batch", "named_batch"]


def flatten_batch(layout: ObservationLayout, parts: dict[str, np.ndarray]) -> np.ndarray:
    """Named batched parts -> flat (N, D) float32 rows, in the exact order of ``gymnasium.spaces.flatten``.

    The inverse of :meth:`ObservationLayout.unflatten`.
    """
    names = list(layout.dict_space().spaces)
    n = len(parts[names[0]])
    return np.concatenate([np.asarray(parts[name], np.float32).reshape(n, -1) for name in names], axis=1)


def named_batch(layout: ObservationLayout, obs: Any) -> dict[str, np.ndarray]:
    """Accept a batch as a named dict or as flat (N, D) rows and return the named dict."""
    if isinstance(obs, dict):
        return obs
    return layout.unflatten(np.asarray(obs))


class Policy(ABC):
    """A (possibly stateful) controller for a batch of robots sharing one platform and layout."""

    #: short name used in result tables
    name: str = "policy"

    def __init__(self, platform: Platform, layout: ObservationLayout, rng: np.random.Generator | None = None) -> None:
        self.platform = platform
        self.layout = layout
        self.rng = rng if rng is not None else np.random.default_rng()
        self.n = 0

    @property
    def action_size(self) -> int:
        return self.layout.action_size

    def reset(self, n: int, rng: np.random.Generator | None = None) -> None:
        """Start a new episode for ``n`` robots (rows); optionally reseed the policy's own randomness."""
        self.n = int(n)
        if rng is not None:
            self.rng = rng

    @abstractmethod
    def act_batch(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        """Actions (N, A) in [-1, 1] for the named batched observation (see module docstring)."""

    def act(self, observation: Any) -> np.ndarray:
        """Action (A,) for one robot's observation (named dict or flat vector). Uses state row 0."""
        if isinstance(observation, dict):
            batch = {k: np.asarray(v)[None] for k, v in observation.items()}
        else:
            batch = self.layout.unflatten(np.asarray(observation)[None])
        if self.n < 1:
            self.reset(1)
        return self.act_batch(batch)[0]

    # -- helpers for differential-drive controllers ------------------------------------------------------
    def turn_towards(self, angle: np.ndarray, gain: float = 1.0) -> np.ndarray:
        """Angular command (fraction of max) that turns by ``angle`` (rad, body frame) in about one step,
        times ``gain``, clipped to [-1, 1]. Uses the platform's max angular speed and the 0.1 s step."""
        from swarm_envs.adapters.env import DT

        return np.clip(gain * np.asarray(angle) / (self.platform.max_angular_speed * DT), -1.0, 1.0)

    def compose(self, linear: np.ndarray, angular: np.ndarray) -> np.ndarray:
        """(N, A) actions from linear and angular fractions; message bits (if any) set to -1 (silent)."""
        out = -np.ones((len(linear), self.action_size), dtype=np.float32)
        out[:, 0] = np.clip(linear, -1, 1)
        out[:, 1] = np.clip(angular, -1, 1)
        return out


class RandomPolicy(Policy):
    """Uniform random actions in the action box every step (the lower-bound baseline)."""

    name = "random"

    def act_batch(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        n = len(next(iter(obs.values())))
        return self.rng.uniform(-1.0, 1.0, (n, self.action_size)).astype(np.float32)

