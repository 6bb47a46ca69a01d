"""SwarmCom network simulator: bit-slot accurate infrared messaging for a whole swarm [T20 Secs. 3, 4, 6].

:class:`Network` is what an environment calls once per control step (``dt = 0.1 s``). A step carries
``bitrate * dt`` bit slots (the fractional remainder is carried to the next step, so frames run across
step boundaries). In every slot, vectorised over all robots:

1. CSMA (:class:`~swarm_envs.comm.protocol.CSMA`): robots with a queued frame sense and maybe start;
2. the robots that are sending emit their frame's current bit (OOK, all emitters on for an s1);
3. the received intensity of every detector is the superposition over the emitting transmitters in
   line of sight, ``y = min(1, sum gains)`` [T20 Eqs. (10),(11)], accumulated with ``np.bincount`` over
   the links of the emitting robots (links sorted by transmitter once per step);
4. the detector circuit follows y with a photocurrent-dependent speed, state carried across slots and
   steps (``rx_level``; :func:`swarm_envs.comm.channel.detector_response`, the e-puck's bit-rate
   dependence [T20 Secs. 5.2, 7]), and the 12-bit ADC turns its level into counts with Gaussian noise
   [T20 Eqs. (20)-(22)] (:func:`swarm_envs.comm.channel.adc`, same formula inlined here);
5. the detectors (:class:`~swarm_envs.comm.protocol.DetectorBank`) take ``min`` over their detectors,
   detect start symbols, apply the dynamic threshold and store bits; at check points the header is
   decoded (BCH) and the frame is aborted, continued or delivered.

Backends: ``backend="numba"`` (the default) runs all slots of a step in one compiled call
(:func:`swarm_envs.comm.kernels.slot_loop`); ``backend="numpy"`` runs the vectorised loop below, the
tested reference. Every random number of a step (ADC and intensity noise, CSMA access delays and backoffs)
is drawn before the slot loop by :func:`swarm_envs.comm.kernels.draw_copies` in arrays indexed by robot, so
both backends consume the same numbers and the stream does not depend on the robots' activity. Deliveries
are returned in a canonical order (by completion slot, then receiver).

Bit errors, collisions (superposed frames), losses (aborted / undecodable frames) and hidden terminals
thus all arise from the channel model; nothing is drawn from a fitted error rate.

Ground truth (for statistics and validation only, never for the receiver's decisions): at a start
detection the strongest transmitter currently emitting s1 towards the receiver is recorded; while the
frame lasts the bit that transmitter actually sent in each slot is stored beside the received bit. Bit
errors are counted on frames whose start coincided with the true start symbol ("aligned" frames).

Modes [T20 Sec. 6]: ``"broadcast"`` (local broadcast: a frame reaches the robots that decode it) and
``"flooding"`` (each robot re-sends every new ``"app"`` message once, deduplicated by (origin, seq)
within ``dedupe_window`` seconds; the header then also carries the last-hop id). System kinds queued by
:meth:`Network.queue_system` are always local broadcast.

Integrity (docs/design.md#swarmcom-messaging): frames carry the platform's CRC (``crc_bits``; the r-one's
and the Droplet's CRC-16 [L Sec. 3.2.1, Table 3.3], none on the e-puck [T20]) and a frame whose CRC fails
is dropped (``rx_crc_failed``). Flooding frames carry at least a CRC-8, our addition: without error
detection every corrupted copy has a "new" (origin, seq) or payload and is re-flooded by everyone
(validation (c) shows the resulting storm). In every mode a frame whose decoded origin or sender is the
receiver itself is not delivered (``rx_self_named``), as the Droplet firmware rejects its own sender id.

Queues: each robot holds up to ``queue_capacity`` frames (originals, relays, system traffic, FIFO); a new
frame for a full queue drops the oldest waiting one (``queue_dropped``). An env whose agents send every
step therefore keeps only the freshest messages when the channel cannot carry them all.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from swarm_envs.sim.copies import CopyRandom
from swarm_envs.comm.bch import BCHCode, code as bch_code
from swarm_envs.comm.channel import ADCModel, adc_model_for, detector_response
from swarm_envs.comm.kernels import COUNTERS, DELIVERY_FIELDS, PER_ROBOT, GeneratorList, StepDraws, build_frames, draw_copies, link_tables, slot_loop
from swarm_envs.comm.protocol import (
    CSMA,
    IDLE,
    MAX_PAYLOAD,
    RECV,
    SEQ_BITS,
    TYPE_BITS,
    DetectorBank,
    FrameFormat,
    KindRegistry,
    bits_to_uint,
    crc_table,
)
from swarm_envs.sim.platforms import Platform, get_platform

__all__ = ["Network", "Deliveries", "PreparedStep", "BITRATES", "COMM_MODES", "BACKENDS"]

BITRATES = (310, 650, 1080, 1160, 1670, 1800)  # bps offered by the e-puck hardware [T20 Sec. 5]
COMM_MODES = ("broadcast", "flooding")
BACKENDS = ("numpy", "numba")



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


def _ranges(start: np.ndarray, stop: np.ndarray) -> np.ndarray:
    """Concatenate ``arange(start[i], stop[i])`` for all i (vectorised)."""
    counts = stop - start
    total = int(counts.sum())
    if total == 0:
        return np.zeros(0, dtype=np.int64)
    offs = np.repeat(start - np.concatenate([[0], np.cumsum(counts)[:-1]]), counts)
    return offs + np.arange(total)


class Network:
    """Bit-level SwarmCom simulation of ``n_robots`` robots (module docstring).

    Args:
        platform: robot platform (its IR model gives the gains, :func:`adc_model_for` the ADC).
        n_robots: swarm size N.
        rng: random generator (start-up ambient samples at reset, then :func:`~swarm_envs.comm.kernels.draw_copies`
            once per step).
        bitrate: bits per second (e-puck: 310 default, 650, 1080, 1160, 1670, 1800 [T20 Sec. 5]; r-one 1250
            [L Sec. 3.2.1]); with the e-puck's detector response
            (:func:`swarm_envs.comm.channel.detector_response`) the reliable range shrinks as the rate grows
            (~60 cm at 310 bps, 14 cm at 1800 bps [T20 Sec. 7]).
        relative_threshold: m_tr (counts) [T20 Eq. (33)], default 5.
        code: BCH code (n, k): (15, 15) default, (15, 11), (15, 7), (15, 5), (15, 1).
        comm_mode: ``"broadcast"`` or ``"flooding"``.
        payload_bits: default application payload length (bits) used by :meth:`send_many` checks.
        dt: control step (s).
        queue_capacity: frames waiting per robot; when full the oldest waiting frame is dropped.
        backoff_window: CSMA contention window (slots).
        ambient: true ambient value m_max (counts), scalar or (N,); default the platform's (4080 e-puck).
        startup_samples: idle samples averaged at reset for the start-up ambient estimate [Sec. 4.5].
        dedupe_window: seconds a flooded (origin, seq) is remembered.
        intensity_sigma: std of the intensity noise n_j [Eq. (11)] (0: all noise is ADC noise n_m).
        adc_model: override the platform's ADC model.
        crc_bits: 0, 8 or 16: width of the CRC over header + payload (:func:`swarm_envs.comm.protocol.crc`;
            frames failing it are dropped). Default None: the platform's own
            (:attr:`~swarm_envs.sim.platforms.Platform.frame_crc_bits`: CRC-16 on the r-one [L Table 3.3] and the
            Droplet, none on the e-puck as [T20]), at least 8 in flooding mode (our CRC-8 on the e-puck):
            without error detection a corrupted copy (e.g. from a collision) has a new (origin, seq) or payload
            and is re-flooded by everyone as a new message, a broadcast storm that the paper does not report
            (validation (c) shows both).
        backend: ``"numba"`` (the default): the compiled slot loop of
            :mod:`swarm_envs.comm.kernels`; ``"numpy"``: the vectorised reference. Both consume the same
            pre-drawn random numbers (:func:`swarm_envs.comm.kernels.draw_copies`) and give the same results.
        n_copies: env copies of ``n_robots`` robots each (rows copy-major); ``rng`` is then a
            :class:`swarm_envs.sim.copies.CopyRandom` with one generator per copy. Frames carry a copy's own
            robot numbers (header widths as in a single env), every random number of a copy comes from its
            own generator, and :meth:`reset_copies` restarts some copies only.
    """

    def __init__(
        self,
        platform: Platform | str,
        n_robots: int,
        rng: np.random.Generator,
        bitrate: float = 310,
        relative_threshold: float = 5,
        code: tuple[int, int] | BCHCode = (15, 15),
        comm_mode: str = "broadcast",
        payload_bits: int = 8,
        dt: float = 0.1,
        queue_capacity: int = 4,
        backoff_window: int = 32,
        ambient: float | np.ndarray | None = None,
        startup_samples: int = 64,
        dedupe_window: float = 5.0,
        intensity_sigma: float = 0.0,
        adc_model: ADCModel | None = None,
        crc_bits: int | None = None,
        backend: str = "numba",
        n_copies: int = 1,
    ) -> None:
        if backend not in BACKENDS:
            raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")
        self.backend = backend
        if comm_mode not in COMM_MODES:
            raise ValueError(f"comm_mode must be one of {COMM_MODES}, got {comm_mode!r}")
        if not bitrate > 0:
            raise ValueError(f"bitrate must be > 0 (e-puck rates: {BITRATES}), got {bitrate!r}")
        if not 0 <= payload_bits <= MAX_PAYLOAD:
            raise ValueError(f"payload_bits must be in [0, {MAX_PAYLOAD}], got {payload_bits}")
        self.platform = get_platform(platform)
        self.rng = rng if isinstance(rng, CopyRandom) else CopyRandom([rng] * int(n_copies))
        if self.rng.n_copies != int(n_copies):
            raise ValueError(f"need one generator per env copy ({n_copies}), got {self.rng.n_copies}")
        self.copy_size = int(n_robots)
        self.n_copies = int(n_copies)
        self.n = self.copy_size * self.n_copies
        self.copy_of = np.repeat(np.arange(self.n_copies), self.copy_size)
        self.offset = self.copy_of * self.copy_size  # first robot of each robot's copy: frames carry local ids
        if self.n_copies > 1 and abs(bitrate * dt - round(bitrate * dt)) > 1e-9:
            raise ValueError(f"env copies need a whole number of bit slots per step; bitrate * dt = {bitrate * dt}")
        self.bitrate = float(bitrate)
        self.dt = float(dt)
        self.m_tr = float(relative_threshold)
        self.code = code if isinstance(code, BCHCode) else bch_code(*tuple(code))
        self.comm_mode = comm_mode
        self.payload_bits = int(payload_bits)
        self.Q = int(queue_capacity)
        self.adc_model = adc_model if adc_model is not None else adc_model_for(self.platform)
        self.ambient = np.broadcast_to(
            np.asarray(self.adc_model.m_max if ambient is None else ambient, dtype=float), (self.n,)
        ).copy()
        self.startup_samples = int(startup_samples)
        self.dedupe_slots = int(round(dedupe_window * self.bitrate))
        self.intensity_sigma = float(intensity_sigma)
        # detector response: slot duration / charge constant (0 = instantaneous detector)
        self.response_kt = (1.0 / self.bitrate) / self.adc_model.response_c if self.adc_model.response_c > 0 else 0.0
        if crc_bits is None:  # the platform's own frame CRC; flooding needs at least our CRC-8
            crc_bits = max(self.platform.frame_crc_bits, 8 if comm_mode == "flooding" else 0)
        self.crc_bits = int(crc_bits)
        self.fmt = FrameFormat.for_swarm(self.copy_size, self.code, with_sender=(comm_mode == "flooding"), crc_bits=self.crc_bits)
        self.kinds = KindRegistry()
        self.n_det = self.platform.n_detectors
        self.det = DetectorBank(self.n, self.m_tr, max_bits=64)
        self.csma = CSMA(self.n, backoff_window)
        self._gen_list: GeneratorList | None = None  # the copies' generators as draw_copies takes them
        self.reset()

    def __getstate__(self) -> dict[str, Any]:
        """Pickle / deepcopy without the numba list of generators (not picklable; rebuilt from ``rng``)."""
        state = self.__dict__.copy()
        state["_gen_list"] = None
        return state

    # ------------------------------------------------------------------ state
    def reset(self) -> None:
        """Empty all queues, idle all transceivers (detector response levels to 0), zero the statistics, redo
        the start-up ambient estimate (mean of ``startup_samples`` noisy dark samples per detector) [T20 Sec. 4.5]."""
        n = self.n
        F = max(64, self.fmt.header_blocks * self.code.n + 1, self.frame_slots() + 1)
        self.slot = 0
        self.slot0 = np.zeros(self.n_copies, dtype=np.int64)  # global slot at each copy's reset
        self.carry = 0.0
        self.q_bits = np.zeros((n, self.Q, F), dtype=bool)
        self.q_slots = np.zeros((n, self.Q), dtype=np.int64)
        self.q_head = np.zeros(n, dtype=np.int64)
        self.q_count = np.zeros(n, dtype=np.int64)
        self.cur_bits = np.zeros((n, F), dtype=bool)
        self.cur_slots = np.zeros(n, dtype=np.int64)
        self.cur_pos = np.zeros(n, dtype=np.int64)
        self.cur_id = np.full(n, -1, dtype=np.int64)
        self.sending = np.zeros(n, dtype=bool)
        self.frame_counter = 0
        self.seq_next = np.zeros(n, dtype=np.int64)
        self.gt_tx = np.full(n, -1, dtype=np.int64)
        self.gt_id = np.full(n, -1, dtype=np.int64)
        self.gt_buf = np.zeros((n, F), dtype=bool)
        self.collided = np.zeros(n, dtype=bool)
        self.rx_foreign = np.zeros(n, dtype=np.int64)  # detectors hit by foreign light in dark slots (Deliveries.interference)
        self.rx_level = np.zeros((n, self.n_det))  # detector response state (channel.detector_response)
        self.seen_keys = np.zeros(0, dtype=np.int64)
        self.seen_slot = np.zeros(0, dtype=np.int64)
        self.det.reset(self._startup_ambient(np.arange(n)))
        self.csma.reset()
        self.stats: dict[str, Any] = {c: 0 for c in COUNTERS}
        for c in PER_ROBOT:
            self.stats[c + "_per_robot"] = np.zeros(n, dtype=np.int64)
        self._step_stats = self._new_step_stats()

    def _startup_ambient(self, rows: np.ndarray) -> np.ndarray:
        """Start-up ambient estimate of ``rows`` (sorted, whole copies): mean of noisy dark samples [Sec. 4.5]."""
        a = self.adc_model
        K = max(1, self.startup_samples)
        amb = self.ambient[rows, None]
        if a.noise_var > 0:
            dark = np.floor(amb + self.rng.normal(a.noise_sigma, self.copy_of[rows], (K * self.n_det,)))
        else:
            dark = np.repeat(amb, K * self.n_det, 1)
        return np.clip(dark, 0, a.m_sup).mean(axis=1)

    def reset_copies(self, copies: np.ndarray, rngs: list[np.random.Generator]) -> None:
        """Reset the robots of env ``copies`` as a fresh network would be (queues, transceivers, detector and
        its response level ``rx_level``, sequence numbers, per-robot statistics), drawing their start-up ambient from ``rngs`` (one per copy,
        which become those copies' streams). Other copies are untouched."""
        copies = np.asarray(copies, dtype=np.int64).reshape(-1)
        for b, g in zip(copies, rngs):
            self.rng.generators[b] = g
        rows = np.flatnonzero(np.isin(self.copy_of, copies))
        self.slot0[copies] = self.slot
        for arr, value in (
            (self.q_bits, False), (self.q_slots, 0), (self.q_head, 0), (self.q_count, 0), (self.cur_bits, False),
            (self.cur_slots, 0), (self.cur_pos, 0), (self.cur_id, -1), (self.sending, False), (self.seq_next, 0),
            (self.gt_tx, -1), (self.gt_id, -1), (self.gt_buf, False), (self.collided, False), (self.rx_level, 0.0),
            (self.rx_foreign, 0),
        ):  # fmt: skip
            arr[rows] = value
        det = self.det
        for arr in (det.state, det.thr, det.nbits, det.expect, det.phase, det.buf, det.best_m, det.best_det, det.last_s1, det.start_slot):
            arr[rows] = 0
        det.m_max_est[rows] = self._startup_ambient(rows)
        self.csma.backoff[rows] = 0
        receiver = self.seen_keys // (1 << SEQ_BITS) // self.n
        keep = ~np.isin(self.copy_of[receiver], copies) if self.seen_keys.size else np.zeros(0, bool)
        self.seen_keys, self.seen_slot = self.seen_keys[keep], self.seen_slot[keep]
        for c in PER_ROBOT:
            self.stats[c + "_per_robot"][rows] = 0

    def _new_step_stats(self) -> dict[str, Any]:
        s: dict[str, Any] = {c: 0 for c in COUNTERS}
        for c in PER_ROBOT:
            s[c + "_per_robot"] = np.zeros(self.n, dtype=np.int64)
        return s

    def _count(self, name: str, robots: np.ndarray | None = None, values: np.ndarray | int = 1) -> None:
        if robots is None:
            v = int(values)
            self.stats[name] += v
            self._step_stats[name] += v
            return
        robots = np.asarray(robots)
        vals = np.broadcast_to(np.asarray(values, dtype=np.int64), robots.shape)
        tot = int(vals.sum())
        self.stats[name] += tot
        self._step_stats[name] += tot
        if name in PER_ROBOT and robots.size:
            np.add.at(self.stats[name + "_per_robot"], robots, vals)
            np.add.at(self._step_stats[name + "_per_robot"], robots, vals)

    def _ensure_frame_capacity(self, F: int) -> None:
        cur = self.cur_bits.shape[1]
        if F <= cur:
            return
        F = max(F, 2 * cur, self.det.buf.shape[1])
        pad = F - cur
        self.q_bits = np.concatenate([self.q_bits, np.zeros((self.n, self.Q, pad), bool)], axis=2)
        self.cur_bits = np.concatenate([self.cur_bits, np.zeros((self.n, pad), bool)], axis=1)
        self.gt_buf = np.concatenate([self.gt_buf, np.zeros((self.n, pad), bool)], axis=1)
        dw = self.det.buf.shape[1]
        if dw < F:
            self.det.buf = np.concatenate([self.det.buf, np.zeros((self.n, F - dw), bool)], axis=1)

    @property
    def slots_per_step(self) -> float:
        return self.bitrate * self.dt

    def frame_slots(self, payload_len: int | None = None) -> int:
        """Bit slots one frame with this payload takes on air (start symbol + blocks)."""
        return int(self.fmt.frame_slots(self.payload_bits if payload_len is None else payload_len))

    # ------------------------------------------------------------------ queueing
    def send(self, robot: int, payload_bits: np.ndarray, kind: str = "app") -> int:
        """Queue one message of ``robot``; returns its sequence number."""
        p = np.asarray(payload_bits, dtype=bool).reshape(1, -1)
        return int(self.send_many(np.array([robot]), p, kind)[0])

    def send_many(self, robots: np.ndarray, payloads: np.ndarray, kind: str = "app", lengths: np.ndarray | None = None) -> np.ndarray:
        """Queue one message per entry of ``robots`` (M,), payloads (M, L) bool (all length L unless
        ``lengths`` (M,) is given). Returns the (M,) sequence numbers (mod 128)."""
        robots = np.asarray(robots, dtype=np.int64).reshape(-1)
        M = robots.size
        payloads = np.asarray(payloads, dtype=bool).reshape(M, -1)
        if M == 0:
            return np.zeros(0, dtype=np.int64)
        if (robots < 0).any() or (robots >= self.n).any():
            raise ValueError(f"robot index out of range [0, {self.n})")
        lengths = np.full(M, payloads.shape[1]) if lengths is None else np.asarray(lengths, dtype=np.int64)
        tcode = self.kinds.code(kind)
        # per-origin sequence numbers (robots may repeat within one call)
        order = np.argsort(robots, kind="stable")
        rs = robots[order]
        first = np.r_[True, rs[1:] != rs[:-1]]
        grp_start = np.maximum.accumulate(np.where(first, np.arange(M), 0))
        rank = np.empty(M, dtype=np.int64)
        rank[order] = np.arange(M) - grp_start
        seq = (self.seq_next[robots] + rank) % (1 << SEQ_BITS)
        np.add.at(self.seq_next, robots, 1)
        local = robots - self.offset[robots]  # frames carry a copy's own robot numbers
        bits, slots = self._build(np.full(M, tcode), seq, local, local, payloads, lengths)
        self._enqueue(robots, bits, slots, rank)
        return seq

    def _build(self, type_code, seq, origin, sender, payload, length) -> tuple[np.ndarray, np.ndarray]:
        """Frames on air (:meth:`swarm_envs.comm.protocol.FrameFormat.build`); the numba backend uses the compiled
        builder :func:`swarm_envs.comm.kernels.build_frames` (same bits and shape, tested against it)."""
        if self.backend != "numba":
            return self.fmt.build(type_code, seq, origin, sender, payload, length)
        fmt, c = self.fmt, self.code
        M = int(np.asarray(type_code).shape[0])
        payload = np.ascontiguousarray(np.asarray(payload, dtype=bool).reshape(M, -1))
        length = np.asarray(length, dtype=np.int64).reshape(M)
        if (length > MAX_PAYLOAD).any() or (length > payload.shape[1]).any() or (length < 0).any():
            raise ValueError(f"payload length negative, longer than {MAX_PAYLOAD} bits or than the given array")
        as_int = lambda v: np.ascontiguousarray(np.asarray(v, dtype=np.int64).reshape(M))  # noqa: E731
        return build_frames(
            as_int(type_code), as_int(seq), as_int(origin), as_int(sender), payload, length, fmt.header_bits, fmt.id_bits,
            fmt.with_sender, fmt.crc_bits, self._crc_table(), c.n, c.k, c._codewords,
        )  # fmt: skip

    def _crc_table(self) -> np.ndarray:
        """The CRC table of this network's frames for the compiled kernels (CRC-8's when frames carry none)."""
        fmt = self.fmt
        return crc_table(fmt.crc_bits or 8, fmt.header_bits + MAX_PAYLOAD + fmt.crc_bits + 1)

    def queue_system(self, robot: int | np.ndarray, bits: np.ndarray, kind: str, lengths: np.ndarray | None = None) -> np.ndarray:
        """Queue system traffic (any kind name other than ``"app"``, at most 255 bits, local broadcast)
        for one robot or an array of robots, payloads ``(M, L)``: all of length L, or of ``lengths`` (M,)
        (the first ``lengths[m]`` bits of row m)."""
        if kind == "app":
            raise ValueError("use send()/send_many() for application messages")
        robots = np.atleast_1d(np.asarray(robot, dtype=np.int64))
        b = np.asarray(bits, dtype=bool).reshape(robots.size, -1)
        return self.send_many(robots, b, kind=kind, lengths=lengths)

    def _enqueue(self, robots: np.ndarray, bits: np.ndarray, slots: np.ndarray, rank: np.ndarray) -> None:
        self._ensure_frame_capacity(bits.shape[1])
        F = bits.shape[1]
        for r in range(int(rank.max()) + 1):
            sel = np.flatnonzero(rank == r)
            rb = robots[sel]
            full = self.q_count[rb] >= self.Q
            if full.any():
                fr = rb[full]
                self.q_head[fr] = (self.q_head[fr] + 1) % self.Q
                self.q_count[fr] -= 1
                self._count("queue_dropped", values=int(full.sum()))
            pos = (self.q_head[rb] + self.q_count[rb]) % self.Q
            self.q_bits[rb, pos, :] = False
            self.q_bits[rb, pos, :F] = bits[sel]
            self.q_slots[rb, pos] = slots[sel]
            newly = rb[(self.q_count[rb] == 0) & ~self.sending[rb]]
            self.q_count[rb] += 1
            self.csma.request(newly)  # access delay before the first carrier sense, drawn next step

    # ------------------------------------------------------------------ the step
    def prepare_step(self) -> PreparedStep:
        """This step's slot count and every random number of it (:meth:`draw_step`), drawn ahead: they depend
        on neither the links nor the queues, so they can be drawn while the physics runs (another thread;
        :class:`swarm_envs.core.SwarmCore`). Pass the result to the next :meth:`step`; a prepared step that
        is never used leaves the streams advanced by one step's draws."""
        total = self.carry + self.bitrate * self.dt
        S = int(np.floor(total + 1e-9))
        return PreparedStep(S, self.slot, self.carry, total - S, self.draw_step(S))

    def step(self, links: Any, prepared: PreparedStep | None = None) -> Deliveries:
        """Simulate one control step of ``bitrate * dt`` bit slots over the given IR links
        (:class:`swarm_envs.ir.layer.IRLinks` of the current poses) and return what was delivered.
        ``prepared``: this step's draws from :meth:`prepare_step` (default: drawn now; same numbers)."""
        self._step_stats = self._new_step_stats()
        n, nd = self.n, self.n_det
        a = self.adc_model
        sums = None if links is None else getattr(links, "emitter_sums", None)
        if links is None or len(links.rx) == 0:
            rx = np.zeros(0, dtype=np.int64)
            tx = np.zeros(0, dtype=np.int64)
            gains = np.zeros((0, nd, 1))
        else:
            rx = np.asarray(links.rx, dtype=np.int64)
            tx = np.asarray(links.tx, dtype=np.int64)
            if sums is not None:
                # the IR layer's all-emitters-on sums (accumulated from 0.0 in emitter order, as below) as gains
                # of a single emitter: 0.0 + sum is the sum, so every backend gets the same G bit for bit while
                # reading (P, nd) instead of the (P, nd, n_emitters) gains
                sums = np.asarray(sums, dtype=np.float64)
                if sums.shape != (len(rx), nd):
                    raise ValueError(f"links.emitter_sums must have shape {(len(rx), nd)}, got {sums.shape}")
                gains = sums[:, :, None]
            else:
                gains = np.asarray(links.gains, dtype=np.float64)
        if self.backend == "numba":
            tx_ptr, rx, G, sig_ptr, sig_rx = link_tables(n, rx, tx, gains, float(a.intensity_scale), self.ambient, float(a.m_min), self.m_tr)
        else:
            # all emitters on, summed from 0.0 in emitter order (as the kernel); links grouped by transmitter
            acc = np.zeros(gains.shape[:2])
            for e in range(gains.shape[-1]):
                acc += gains[..., e]
            G = a.intensity_scale * acc  # (P, nd)
            order = np.argsort(tx, kind="stable")
            rx, tx, G = rx[order], tx[order], G[order]
            tx_ptr = np.searchsorted(tx, np.arange(n + 1))
            flat = (rx[:, None] * nd + np.arange(nd)[None, :]).ravel()
            strength = G.max(axis=1) if G.size else np.zeros(0)
            significant = strength * (self.ambient[rx] - a.m_min) > self.m_tr
            sig_rx = rx[significant]
            sig_ptr = np.searchsorted(tx[significant], np.arange(n + 1))

        if prepared is None:
            prepared = self.prepare_step()
        elif prepared.first_slot != self.slot or prepared.carry_before != self.carry:
            raise ValueError("prepared was made for another step of this network (prepare_step, then step, once each)")
        S, draws = prepared.slots, prepared.draws
        self.carry = prepared.carry_after
        self.csma.draw_requested(draws.access)
        if self.backend == "numba":
            deliveries = self._slots_kernel(S, draws, tx_ptr, rx, G, sig_ptr, sig_rx)
        else:
            deliveries = self._slots_numpy(S, draws, tx_ptr, rx, tx, G, flat, sig_ptr, sig_rx)
        self._count("slots", values=S)
        return self._finish_step(deliveries)

    def draw_step(self, S: int) -> StepDraws:
        """Every random number of a step of S slots, drawn before the slot loop (same for both backends): all
        copies in one call, copy b from its own generator (:func:`swarm_envs.comm.kernels.draw_copies`)."""
        a = self.adc_model
        gens = self.rng.generators
        if self._gen_list is None:
            self._gen_list = GeneratorList(gens)
        return draw_copies(
            self._gen_list.sync(gens), S, self.copy_size, self.n_det, a.noise_sigma if a.noise_var > 0 else 0.0, self.intensity_sigma, self.csma.window
        )

    def _kind_names(self, types: np.ndarray) -> np.ndarray:
        """(D,) object array of kind names of 3-bit type codes ("?" for unregistered), by table lookup."""
        table = np.array([self.kinds.name(c) for c in range(1 << TYPE_BITS)], dtype=object)
        types = np.asarray(types, dtype=np.int64)
        if types.size and (types.min() < 0 or types.max() >= table.size):
            return np.array([self.kinds.name(t) for t in types], dtype=object)
        return table[types]

    def _slots_kernel(self, S, draws, tx_ptr, rx, G, sig_ptr, sig_rx) -> list[dict[str, np.ndarray]]:
        """The compiled slot loop (:func:`swarm_envs.comm.kernels.slot_loop`)."""
        a, det, fmt, c = self.adc_model, self.det, self.fmt, self.code
        wmax = int(fmt.n_blocks(MAX_PAYLOAD)) * c.n + 1  # longest frame any header can announce
        det.ensure_capacity(wmax)
        if self.gt_buf.shape[1] < det.buf.shape[1]:
            self.gt_buf = np.concatenate([self.gt_buf, np.zeros((self.n, det.buf.shape[1] - self.gt_buf.shape[1]), bool)], axis=1)
        dcap = self.n * (1 + S // (fmt.header_blocks * c.n + 1))  # completions per robot and step are bounded
        d_int = np.zeros((dcap, len(DELIVERY_FIELDS)), dtype=np.int64)
        d_pay = np.zeros((dcap, MAX_PAYLOAD), dtype=bool)
        counts = np.zeros(len(COUNTERS), dtype=np.int64)
        per_robot = np.zeros((len(PER_ROBOT), self.n), dtype=np.int64)
        fc = np.array([self.frame_counter], dtype=np.int64)
        state = det.state.view(np.int8)
        D = slot_loop(
            S, self.slot, self.n_det, float(a.m_min), int(a.m_sup), self.m_tr, det.alpha, fmt.first_check_slots,
            tx_ptr, rx, G, sig_ptr, sig_rx, self.ambient, self.rx_level, self.response_kt, float(a.response_bias),
            draws.noise, draws.intensity_noise, draws.backoff,
            self.q_bits, self.q_slots, self.q_head, self.q_count, self.cur_bits, self.cur_slots, self.cur_pos, self.cur_id,
            self.sending, fc, self.csma.backoff,
            state, det.m_max_est, det.thr, det.nbits, det.expect, det.phase, det.buf, det.best_m, det.best_det,
            det.last_s1, det.start_slot,
            self.gt_tx, self.gt_id, self.gt_buf, self.collided,
            c.n, c.k, c._table_msg, c._table_ok, fmt.header_blocks, fmt.header_bits, fmt.id_bits, fmt.with_sender,
            fmt.crc_bits, self._crc_table(), self.kinds.valid_codes(),
            self.copy_size, counts, per_robot, d_int, d_pay, self.rx_foreign,
        )  # fmt: skip
        self.frame_counter = int(fc[0])
        self.slot += S
        for i, name in enumerate(COUNTERS):
            if counts[i]:
                self._count(name, values=int(counts[i]))
        for i, name in enumerate(PER_ROBOT):
            self.stats[name + "_per_robot"] += per_robot[i]
            self._step_stats[name + "_per_robot"] += per_robot[i]
        if D == 0:
            return []
        cols = {f: d_int[:D, i] for i, f in enumerate(DELIVERY_FIELDS)}
        L = cols["length"]
        Lmax = int(L.max())
        out = {k: cols[k] for k in ("receiver", "origin", "sender", "seq", "type", "length", "detector", "slot", "done_slot", "transmitter", "interference")}
        out["corrupt"] = cols["corrupt"].astype(bool)
        out["payload"] = d_pay[:D, :Lmax].copy()
        return [out]

    def _slots_numpy(self, S, draws, tx_ptr, rx, tx, G, flat, sig_ptr, sig_rx) -> list[dict[str, np.ndarray]]:
        """The vectorised numpy slot loop (the reference of the compiled kernel)."""
        n, nd = self.n, self.n_det
        a = self.adc_model
        noise = draws.noise
        span = (self.ambient - a.m_min)[:, None]
        deliveries: list[dict[str, np.ndarray]] = []
        first_check = self.fmt.first_check_slots
        # per link: the receiver's detectors that its light reaches with at least m_tr counts (bit d = detector d)
        lit_bits = ((G * (self.ambient[rx] - a.m_min)[:, None] > self.m_tr).astype(np.int64) << np.arange(nd, dtype=np.int64)).sum(1) if G.size else np.zeros(0, np.int64)
        for s in range(S):
            # 1. CSMA
            pending = (self.q_count > 0) & ~self.sending
            if pending.any():
                busy = (self.det.state == RECV) | self.det.last_s1
                go, defer = self.csma.decide(pending, busy, draws.backoff[:, s])
                if defer.size:
                    self._count("deferrals", defer)
                if go.size:
                    self._start_tx(go)
            # 2. emission
            snd = np.flatnonzero(self.sending)
            bit = self.cur_bits[snd, self.cur_pos[snd]] if snd.size else np.zeros(0, bool)
            on = snd[bit]
            foreign = self._foreign_light(on, tx_ptr, rx, tx, lit_bits)
            # 3. intensity (superposition over emitting transmitters)
            if self.response_kt > 0:  # detector response across slots (channel.detector_response)
                if on.size:
                    li = _ranges(tx_ptr[on], tx_ptr[on + 1])
                    ysum = np.bincount(flat.reshape(-1, nd)[li].ravel(), weights=G[li].ravel(), minlength=n * nd).reshape(n, nd)
                else:
                    ysum = np.zeros((n, nd))
                if self.intensity_sigma > 0:
                    ysum = ysum + draws.intensity_noise[s]
                yt = np.clip(ysum, 0.0, 1.0)
                v0 = self.rx_level
                v = detector_response(v0, yt, 1.0 / self.bitrate, a.response_c, a.response_bias)
                self.rx_level = v
                m = np.floor(span * (1.0 - v) + a.m_min + noise[s])
            elif on.size:
                li = _ranges(tx_ptr[on], tx_ptr[on + 1])
                ysum = np.bincount(flat.reshape(-1, nd)[li].ravel(), weights=G[li].ravel(), minlength=n * nd).reshape(n, nd)
                if self.intensity_sigma > 0:
                    ysum = ysum + draws.intensity_noise[s]
                y = np.minimum(ysum, 1.0)
                m = np.floor(span * (1.0 - y) + a.m_min + noise[s])
            else:
                y = None
                if self.intensity_sigma > 0:
                    yy = np.minimum(draws.intensity_noise[s], 1.0)
                    m = np.floor(span * (1.0 - yy) + a.m_min + noise[s])
                else:
                    m = np.floor(span + a.m_min + noise[s])
            np.clip(m, 0, a.m_sup, out=m)
            # 4./5. detectors
            listen = ~self.sending
            ev = self.det.sample(m, listen, first_check, self.slot)
            if ev["deaf"].size:
                self.det.finish(ev["deaf"])
            started, got = ev["started"], ev["got_bit"]
            if started.size:
                self._count("rx_starts", values=started.size)
                self._truth_on_start(started, on, tx_ptr, tx, rx, G)
            if got.size:
                if self.det.buf.shape[1] > self.gt_buf.shape[1]:
                    self._ensure_frame_capacity(self.det.buf.shape[1])
                self._truth_bits(got)
                self._interference(got, foreign)
                if snd.size:
                    sl = _ranges(sig_ptr[snd], sig_ptr[snd + 1])
                    if sl.size:
                        cnt = np.bincount(sig_rx[sl], minlength=n)
                        self.collided[got] |= cnt[got] >= 2
            # advance transmitters
            if snd.size:
                self.cur_pos[snd] += 1
                fin = snd[self.cur_pos[snd] >= self.cur_slots[snd]]
                if fin.size:
                    self.sending[fin] = False
                    self._count("tx_completed", values=fin.size)
                    self.csma.arm(fin[self.q_count[fin] > 0], draws.backoff[:, s])  # fresh access delay (fairness)
            if ev["check"].size:
                d = self._check_points(ev["check"])
                if d is not None:
                    deliveries.append(d)
            self.slot += 1
        return deliveries

    def _start_tx(self, go: np.ndarray) -> None:
        h = self.q_head[go]
        F = self.q_bits.shape[2]
        self.cur_bits[go, :F] = self.q_bits[go, h, :]
        self.cur_slots[go] = self.q_slots[go, h]
        self.cur_pos[go] = 0
        self.cur_id[go] = self.frame_counter + np.arange(go.size)
        self.frame_counter += go.size
        self.sending[go] = True
        self.q_head[go] = (h + 1) % self.Q
        self.q_count[go] -= 1
        # a robot that was receiving drops its frame (half duplex); CSMA normally prevents this
        recv = go[self.det.state[go] == RECV]
        if recv.size:
            self.det.finish(recv)
        self._count("tx_started", go)

    def _foreign_light(self, on: np.ndarray, tx_ptr, rx, tx, lit_bits) -> np.ndarray:
        """(N,) per robot receiving a frame: bitmask of its detectors lit in this slot by robots ``on``
        (emitting) other than the frame's transmitter (``gt_tx``)."""
        out = np.zeros(self.n, dtype=np.int64)
        if on.size:
            li = _ranges(tx_ptr[on], tx_ptr[on + 1])
            r = rx[li]
            f = (self.det.state[r] == RECV) & (tx[li] != self.gt_tx[r])
            np.bitwise_or.at(out, r[f], lit_bits[li[f]])
        return out

    def _interference(self, got: np.ndarray, foreign: np.ndarray) -> None:
        """Deliveries.interference: foreign light of this slot counts at robots ``got`` (that stored a bit)
        whose frame's transmitter is dark in this slot."""
        t = self.gt_tx[got]
        ts = np.maximum(t, 0)
        on = (t >= 0) & self.sending[ts] & self.cur_bits[ts, np.minimum(self.cur_pos[ts], self.cur_bits.shape[1] - 1)]
        dark = got[~on]
        self.rx_foreign[dark] |= foreign[dark]

    def _truth_on_start(self, started, on, tx_ptr, tx, rx, G) -> None:
        """Ground truth: the strongest transmitter emitting s1 at each robot that just detected a start."""
        self.rx_foreign[started] = 0
        self.gt_tx[started] = -1
        self.gt_id[started] = -1
        self.collided[started] = False
        if on.size:
            li = _ranges(tx_ptr[on], tx_ptr[on + 1])
            is_started = np.zeros(self.n, dtype=bool)
            is_started[started] = True
            li = li[is_started[rx[li]]]
            r, t, st = rx[li], tx[li], G[li].max(axis=1)
            o = np.lexsort((-st, r))
            r, t, st = r[o], t[o], st[o]
            firsts = np.r_[True, r[1:] != r[:-1]] if r.size else np.zeros(0, dtype=bool)
            r, t, st = r[firsts], t[firsts], st[firsts]
            sig = st * (self.ambient[r] - self.adc_model.m_min) > 0.5  # at least half a count of light
            best = np.full(self.n, -1, dtype=np.int64)
            best[r[sig]] = t[sig]
            self.gt_tx[started] = best[started]
            ok = self.gt_tx[started] >= 0
            srt = started[ok]
            tt = self.gt_tx[srt]
            # aligned only if the transmitter is emitting its own start symbol right now
            aligned = self.cur_pos[tt] == 0
            self.gt_id[srt[aligned]] = self.cur_id[tt[aligned]]
        nfalse = int((self.gt_tx[started] < 0).sum())
        if nfalse:
            self._count("rx_false_starts", values=nfalse)

    def _truth_bits(self, got: np.ndarray) -> None:
        k = self.det.nbits[got] - 1
        t = self.gt_tx[got]
        valid = t >= 0
        tb = np.zeros(got.size, dtype=bool)
        if valid.any():
            tv = t[valid]
            same = self.sending[tv] & (self.cur_id[tv] == self.gt_id[got[valid]])
            bits = self.cur_bits[tv, np.minimum(self.cur_pos[tv], self.cur_bits.shape[1] - 1)]
            tb[valid] = same & bits
        self.gt_buf[got, k] = tb

    # ------------------------------------------------------------------ frame check points
    def _check_points(self, robots: np.ndarray) -> dict[str, np.ndarray] | None:
        out = None
        det, fmt, c = self.det, self.fmt, self.code
        valid_types = self.kinds.valid_codes()
        todo = robots
        while todo.size:
            nxt = []
            ph = det.phase[todo]
            # phase 0: marker/type check
            p0 = todo[ph == 0]
            if p0.size:
                if c.k == c.n:
                    info = det.buf[p0, :4]
                else:
                    info, _ = c.decode(det.buf[p0, : c.n])
                good = info[:, 0].copy()
                if info.shape[1] >= 4:
                    good &= valid_types[bits_to_uint(info[:, 1:4])]
                self._abort(p0[~good])
                g = p0[good]
                det.phase[g] = 1
                det.expect[g] = fmt.header_blocks * c.n
                nxt.append(g[det.expect[g] == det.nbits[g]])
            # phase 1: header decode -> frame length
            p1 = todo[ph == 1]
            if p1.size:
                hb = fmt.header_blocks
                info, ok = c.decode_stream(det.buf[p1, : hb * c.n])
                h = fmt.parse_header(info)
                good = ok & (h["marker"] == 1) & valid_types[h["type"]] & (h["origin"] < self.copy_size) & (h["sender"] < self.copy_size)
                self._abort(p1[~good])
                g = p1[good]
                total = fmt.n_blocks(h["length"][good]) * c.n
                det.ensure_capacity(int(total.max()) if total.size else 0)
                self._ensure_frame_capacity(int(total.max()) + 1 if total.size else 0)
                det.phase[g] = 2
                det.expect[g] = total
                nxt.append(g[det.expect[g] == det.nbits[g]])
            # phase 2: frame complete -> decode and deliver
            p2 = todo[ph == 2]
            if p2.size:
                d = self._complete(p2)
                if d is not None:
                    out = d if out is None else {k: np.concatenate([out[k], d[k]]) if k != "payload" else _cat_pad(out[k], d[k]) for k in out}
            todo = np.concatenate(nxt) if nxt else np.zeros(0, dtype=np.int64)
        return out

    def _score_bits(self, robots: np.ndarray) -> None:
        """Ground-truth scoring of aligned frames at their end (delivered or aborted): raw bit errors over
        the bits received, and errors of every complete 15-bit block after BCH decoding."""
        al = robots[self.gt_id[robots] >= 0]
        if not al.size:
            return
        nb = self.det.nbits[al]
        W = int(nb.max())
        rxb, tb = self.det.buf[al, :W], self.gt_buf[al, :W]
        mask = np.arange(W)[None, :] < nb[:, None]
        err = ((rxb != tb) & mask).sum(axis=1)
        self._count("bits_checked", al, nb)
        self._count("bit_errors", al, err)
        if self.collided[al].any():
            self._count("collisions", al[self.collided[al]])
        c = self.code
        B = W // c.n
        if B:
            nblk = nb // c.n
            shape = (al.size, B, c.n)
            info, _ = c.decode(rxb[:, : B * c.n].reshape(shape))
            tinfo, _ = c.decode(tb[:, : B * c.n].reshape(shape))
            bad = (info != tinfo).any(axis=2) & (np.arange(B)[None, :] < nblk[:, None])
            self._count("blocks_checked", al, nblk)
            self._count("block_errors", al, bad.sum(axis=1))

    def _abort(self, robots: np.ndarray) -> None:
        if not robots.size:
            return
        self._score_bits(robots)
        lost = robots[self.gt_id[robots] >= 0]
        if lost.size:
            self._count("rx_lost", lost)
        self._count("rx_aborted", values=robots.size)
        self.det.finish(robots)

    def _complete(self, robots: np.ndarray) -> dict[str, np.ndarray] | None:
        det, fmt, c = self.det, self.fmt, self.code
        self._score_bits(robots)
        nbits = det.nbits[robots]
        out: dict[str, list] = {k: [] for k in ("receiver", "origin", "sender", "seq", "type", "length", "payload", "detector", "slot", "corrupt", "done_slot", "transmitter", "interference")}
        for nb in np.unique(nbits):
            R = robots[nbits == nb]
            info, ok = c.decode_stream(det.buf[R, :nb])
            h = fmt.parse_header(info)
            # ground truth comparison (aligned frames only)
            al = self.gt_id[R] >= 0
            corrupt = np.zeros(R.size, dtype=bool)
            if al.any():
                tinfo, _ = c.decode_stream(self.gt_buf[R[al], :nb])
                used = fmt.header_bits + h["length"][al]
                mask = np.arange(info.shape[1])[None, :] < used[:, None]
                corrupt[al] = ((info[al] != tinfo) & mask).any(axis=1)
            crc = fmt.crc_ok(info, h["length"]) | ~ok
            if not crc.all():
                self._count("rx_crc_failed", values=int((~crc).sum()))
                ok = ok & crc
            bad = ~ok
            if bad.any():
                self._count("rx_decode_failed", values=int(bad.sum()))
                lost = R[bad & al]
                if lost.size:
                    self._count("rx_lost", lost)
            g = ok
            if not g.any():
                continue
            H = fmt.header_bits
            L = h["length"][g]
            Lmax = int(L.max()) if L.size else 0
            pay = info[g, H : H + Lmax] & (np.arange(Lmax)[None, :] < L[:, None])
            out["receiver"].append(R[g])
            out["origin"].append(h["origin"][g])
            out["sender"].append(h["sender"][g])
            out["seq"].append(h["seq"][g])
            out["type"].append(h["type"][g])
            out["length"].append(L)
            out["payload"].append(pay)
            out["detector"].append(det.best_det[R[g]])
            out["slot"].append(det.start_slot[R[g]])
            out["corrupt"].append(corrupt[g])
            out["done_slot"].append(np.full(int(g.sum()), self.slot, dtype=np.int64))
            out["transmitter"].append(self.gt_tx[R[g]])
            out["interference"].append(self.rx_foreign[R[g]])
        det.finish(robots)
        if not out["receiver"]:
            return None
        res = {k: (np.concatenate(v) if k != "payload" else _cat_pad_list(v)) for k, v in out.items()}
        self._count("rx_decoded", values=res["receiver"].size)
        return res

    # ------------------------------------------------------------------ end of step
    def _finish_step(self, parts: list[dict[str, np.ndarray]]) -> Deliveries:
        if parts:
            d = {k: (np.concatenate([p[k] for p in parts]) if k != "payload" else _cat_pad_list([p[k] for p in parts])) for k in parts[0]}
        else:
            d = {k: np.zeros(0, dtype=np.int64) for k in ("receiver", "origin", "sender", "seq", "type", "length", "detector", "slot", "done_slot", "transmitter", "interference")}
            d["corrupt"] = np.zeros(0, dtype=bool)
            d["payload"] = np.zeros((0, 0), dtype=bool)
        # canonical order: by the slot the frame was completed in, then by receiver (one per robot and slot)
        o = np.lexsort((d["receiver"], d["done_slot"]))
        d = {k: v[o] for k, v in d.items()}
        # header ids are the receiver's copy's own numbers: to robot rows; slots counted from the copy's reset
        base = self.offset[d["receiver"]]
        d["origin"], d["sender"] = d["origin"] + base, d["sender"] + base
        d["slot"] = d["slot"] - self.slot0[self.copy_of[d["receiver"]]]
        # a frame whose header names the receiver itself as origin or last hop is not delivered (a robot never
        # receives its own frames, half duplex: such a header is corrupt or a flooded echo of its own message)
        keep = (d["origin"] != d["receiver"]) & (d["sender"] != d["receiver"])
        if not keep.all():
            self._count("rx_self_named", values=int((~keep).sum()))
        if self.comm_mode == "flooding" and keep.size:
            flood = keep & (d["type"] == self.kinds.code("app"))
            key = (d["receiver"] * self.n + d["origin"]) * (1 << SEQ_BITS) + d["seq"]
            # forget old entries
            fresh = self.seen_slot > self.slot - self.dedupe_slots
            self.seen_keys, self.seen_slot = self.seen_keys[fresh], self.seen_slot[fresh]
            seen_before = np.isin(key, self.seen_keys)
            first = np.zeros(keep.size, dtype=bool)
            rows = np.flatnonzero(flood)
            _, idx = np.unique(key[rows], return_index=True)
            first[rows[idx]] = True
            new = flood & ~seen_before & first
            dup = flood & ~new
            keep &= ~dup
            if dup.any():
                self._count("rx_duplicates", values=int(dup.sum()))
            if new.any():
                self.seen_keys = np.concatenate([self.seen_keys, key[new]])
                self.seen_slot = np.concatenate([self.seen_slot, np.full(int(new.sum()), self.slot)])
                self._relay(d, np.flatnonzero(new))
        out = Deliveries(
            receiver=d["receiver"][keep],
            origin=d["origin"][keep],
            sender=d["sender"][keep],
            seq=d["seq"][keep],
            detector=d["detector"][keep],
            kind=self._kind_names(d["type"][keep]),
            length=d["length"][keep],
            payload=d["payload"][keep],
            slot=d["slot"][keep],
            corrupt=d["corrupt"][keep],
            transmitter=d["transmitter"][keep],
            interference=d["interference"][keep],
        )
        if len(out):
            self._count("rx_delivered", out.receiver)
            self._count("rx_corrupt_delivered", values=int(out.corrupt.sum()))
        out.stats = self._step_stats
        return out

    def _relay(self, d: dict[str, np.ndarray], idx: np.ndarray) -> None:
        """Flooding: queue one re-send of each new message (same origin/seq/payload, sender = relay)."""
        robots = d["receiver"][idx]
        base = self.offset[robots]
        bits, slots = self._build(d["type"][idx], d["seq"][idx], d["origin"][idx] - base, robots - base, d["payload"][idx], d["length"][idx])
        order = np.argsort(robots, kind="stable")
        rs = robots[order]
        firsts = np.r_[True, rs[1:] != rs[:-1]]
        grp = np.maximum.accumulate(np.where(firsts, np.arange(rs.size), 0))
        rank = np.empty(rs.size, dtype=np.int64)
        rank[order] = np.arange(rs.size) - grp
        self._enqueue(robots, bits, slots, rank)
        self._count("tx_relays", values=idx.size)

    # ------------------------------------------------------------------ helpers
    @property
    def busy(self) -> np.ndarray:
        """(N,) robots currently sending or receiving a frame."""
        return self.sending | (self.det.state == RECV)

    def summary(self) -> dict[str, float]:
        """Derived rates over everything since :meth:`reset`."""
        s = self.stats
        return {
            "bit_error_rate": s["bit_errors"] / max(1, s["bits_checked"]),
            "block_error_rate": s["block_errors"] / max(1, s["blocks_checked"]),
            "delivered_per_started": s["rx_delivered"] / max(1, s["tx_started"]),
        }


def _cat_pad(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return _cat_pad_list([a, b])


def _cat_pad_list(arrs: list[np.ndarray]) -> np.ndarray:
    if len(arrs) == 1:  # the compiled backend's single part: nothing to pad
        return arrs[0]
    W = max((x.shape[1] for x in arrs), default=0)
    return np.concatenate([np.pad(x, ((0, 0), (0, W - x.shape[1]))) if x.shape[1] < W else x for x in arrs], axis=0) if arrs else np.zeros((0, 0), bool)
