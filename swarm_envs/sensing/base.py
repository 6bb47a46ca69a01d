"""What a sensing stack hands to the observation builder each control step.

Sensing stacks (:mod:`swarm_envs.sensing.ideal`, :mod:`swarm_envs.sensing.full`) turn the physical
state into these per-link readings; the env packs them into fixed observation slots. Stacks see the
true state only through the physics they model (the ideal stack is the noiseless ablation).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["NeighbourReadings", "MessageReadings", "ScaleFreeReadings", "SensorFrame"]


def _empty(dtype: type = float) -> np.ndarray:
    return np.zeros(0, dtype=dtype)


@dataclass
class NeighbourReadings:
    """Range & bearing readings, one entry per (receiver rx, neighbour tx). Units: m, rad, steps."""

    rx: np.ndarray = field(default_factory=lambda: _empty(np.int64))
    tx: np.ndarray = field(default_factory=lambda: _empty(np.int64))
    range: np.ndarray = field(default_factory=_empty)
    bearing: np.ndarray = field(default_factory=_empty)
    heading: np.ndarray = field(default_factory=_empty)
    age: np.ndarray = field(default_factory=_empty)
    #: optional, from a stack that already picked each robot's k nearest readings (the ideal one): ``slots``
    #: (N, k) reading index per observation slot (-1 empty; :func:`swarm_envs.sensing.observation.nearest_slots`
    #: of ``rx`` by ``range``) and ``slot_cos_sin`` (N, k, 2) cos and sin of those bearings (of reading 0 in
    #: empty slots); the observation builder then reuses them instead of selecting again
    slots: np.ndarray | None = None
    slot_cos_sin: np.ndarray | None = None
    #: optional, from a stack that also built them (the full one, on its worker thread): ``rows`` (N, k, 7)
    #: float32, the observation rows of ``slots`` (:func:`swarm_envs.sensing.observation.range_bearing_rows`)
    rows: np.ndarray | None = None

    @property
    def valid(self) -> np.ndarray:
        """(P,) bool: the reading has a bearing."""
        return np.isfinite(self.bearing)


@dataclass
class MessageReadings:
    """Messages decoded this step: receiver, sender (origin) id, sender bearing (rad), payload bits (P, b)."""

    receiver: np.ndarray = field(default_factory=lambda: _empty(np.int64))
    sender: np.ndarray = field(default_factory=lambda: _empty(np.int64))
    bearing: np.ndarray = field(default_factory=_empty)
    payload: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    distance_hint: np.ndarray | None = None  # ordering key for slot packing (smaller first); None = arrival order


@dataclass
class ScaleFreeReadings:
    """Per robot: K neighbour positions in its frame, scaled to mean neighbour distance 1."""

    xy: np.ndarray  # (N, K, 2)
    valid: np.ndarray  # (N, K) bool
    rigid: np.ndarray  # (N,) bool
    #: (N, K) int robot row each slot's coordinates belong to, as the robot knows it (the decoded id its
    #: bearing exchange stored; -1 empty); None from a stack that does not say
    ids: np.ndarray | None = None


@dataclass
class SensorFrame:
    """Everything one sensing step produced, plus per-robot statistics for ``infos``."""

    neighbours: NeighbourReadings
    messages: MessageReadings
    scale_free: ScaleFreeReadings
    stats: dict[str, np.ndarray] = field(default_factory=dict)
