"""The sensing stacks (the ``sensing`` setting): their names, the protocol the core drives them through, and
how one is built. A new stack is a module with a class following :class:`SensingStack` and one entry in
:data:`SENSING_STACKS`; the core needs no edit."""

from __future__ import annotations

import importlib
from typing import Any, Protocol

import numpy as np

from swarm_envs.sensing.base import SensorFrame
from swarm_envs.sim.platforms import Platform

__all__ = ["SENSING_STACKS", "SensingStack", "build_stack"]

#: setting value -> ``"module:Class"`` of the stack (imported when first built)
SENSING_STACKS: dict[str, str] = {
    "full": "swarm_envs.sensing.full:FullSensing",  # the modelled infrared stack
    "ideal": "swarm_envs.sensing.ideal:IdealSensing",  # exact, noiseless, lossless values in the same layout
}


class SensingStack(Protocol):
    """What the core calls on a sensing stack, once per control step for all robots of all copies."""

    @classmethod
    def from_config(
        cls, platform: Platform, n_robots: int, config: dict[str, Any], n_copies: int = 1, obstacles: np.ndarray | None = None
    ) -> SensingStack:
        """A stack for ``n_copies`` copies of ``n_robots`` robots (a task's resolved settings ``config``;
        ``obstacles`` (S, 2, 2) m wall segments or None)."""

    def reset(self, copies: np.ndarray, rngs: list[np.random.Generator]) -> None:
        """New episodes in ``copies``, each copy's sensing drawing from its generator in ``rngs``."""

    def step(
        self,
        positions: np.ndarray,
        headings: np.ndarray,
        payloads: np.ndarray | None = None,
        sending: np.ndarray | None = None,
        *,
        silent: np.ndarray | None = None,
        emit_off: np.ndarray | None = None,
        detect_off: np.ndarray | None = None,
    ) -> SensorFrame:
        """The readings of every robot at ``positions`` (n, 2) m and ``headings`` (n,) rad; ``payloads``
        (n, b) bool message bits sent by the robots marked in ``sending`` (n,); ``silent``, ``emit_off``,
        ``detect_off`` (n,) bool switched-off robots, transmitters and receivers. A stack that sets
        ``large_scene = True`` also offers ``prepare_step(payloads, sending)`` and ``step(..., prepared=...)``
        (the core then overlaps the preparation with the physics)."""


def build_stack(
    name: str, platform: Platform, n_robots: int, config: dict[str, Any], n_copies: int = 1, obstacles: np.ndarray | None = None
) -> SensingStack:
    """The stack registered as ``name`` in :data:`SENSING_STACKS`, built for the given robots and settings."""
    try:
        module, _, cls = SENSING_STACKS[name].partition(":")
    except KeyError:
        raise ValueError(f"unknown sensing stack {name!r}; choose one of {sorted(SENSING_STACKS)}") from None
    stack = getattr(importlib.import_module(module), cls)
    return stack.from_config(platform, n_robots, config, n_copies, obstacles)
