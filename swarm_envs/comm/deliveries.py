"""What a SwarmCom step hands over: the delivered frames (:class:`Deliveries`) and the draws prepared for a step
before its slot loop (:class:`PreparedStep`)."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from swarm_envs.comm.draws import StepDraws

__all__ = ["Deliveries", "PreparedStep"]


@dataclass
class Deliveries:
    """Frames delivered to the application during one step (D rows).

    Attributes:
        receiver: (D,) robot that received the message.
        origin: (D,) robot that created the message (header).
        sender: (D,) last hop (header; = origin in broadcast mode).
        seq: (D,) sequence number (mod 128).
        detector: (D,) index of the receiver's detector with the smallest ADC value during the frame
            (the brightest one: a coarse bearing of the sender).
        kind: (D,) object array of kind names (``"app"`` or the system kind).
        length: (D,) payload length (bits).
        payload: (D, Lmax) bool, row i valid up to ``length[i]``.
        slot: (D,) global bit slot at which the frame's start symbol was received.
        corrupt: (D,) ground truth: the decoded header/payload differs from what was sent (possible
            because [15,15], [15,11], [15,1] detect nothing). For metrics only, not an observation.
        transmitter: (D,) ground truth: the robot whose light started the frame (the strongest transmitter
            emitting a start symbol at the receiver when it detected the start; -1 for a noise start). Not an
            observation: a sensor may use it only to know *whose light* lit its receivers (physics), never
            to name the sender (use ``origin``).
        interference: (D,) ground truth: bitmask of the receiver's detectors (bit d = detector d) that
            another robot's light reached, at least ``relative_threshold`` counts of it, in a slot of the frame
            in which the frame's transmitter was dark: the detectors whose own copy of the frame that light
            corrupted (light adds on an on-off channel, so light in a slot where the frame's own bit is on
            changes nothing there). Physics, like ``transmitter``: a per-receiver decoder (the r-one's, [L Sec.
            3.2.1]) uses it to know which receivers' copies were clean; not an observation.
        stats: counters of this step (scalars) and per-robot arrays ``<name>_per_robot`` (N,).
    """

    receiver: np.ndarray
    origin: np.ndarray
    sender: np.ndarray
    seq: np.ndarray
    detector: np.ndarray
    kind: np.ndarray
    length: np.ndarray
    payload: np.ndarray
    slot: np.ndarray
    corrupt: np.ndarray
    transmitter: np.ndarray | None = None
    interference: np.ndarray | None = None
    stats: dict[str, Any] = field(default_factory=dict)

    def __len__(self) -> int:
        return int(self.receiver.shape[0])

    def payloads(self) -> list[np.ndarray]:
        """Payloads as a list of 1-D bool arrays of their own lengths."""
        return [self.payload[i, : self.length[i]] for i in range(len(self))]

    def for_kind(self, kind: str) -> "Deliveries":
        m = self.kind == kind
        return Deliveries(
            *(getattr(self, f)[m] for f in ("receiver", "origin", "sender", "seq", "detector", "kind", "length", "payload", "slot", "corrupt")),
            transmitter=None if self.transmitter is None else self.transmitter[m],
            interference=None if self.interference is None else self.interference[m],
            stats=self.stats,
        )


@dataclass(frozen=True)
class PreparedStep:
    """A step's slot count and random numbers drawn ahead (:meth:`Network.prepare_step`): ``slots`` bit
    slots, the network's slot clock ``first_slot`` and remainder ``carry_before`` it was drawn at, the
    remainder ``carry_after`` the step leaves, and ``draws``."""

    slots: int
    first_slot: int
    carry_before: float
    carry_after: float
    draws: StepDraws
