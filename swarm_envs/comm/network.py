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
(:func:`swarm_envs.comm.kernels.slot_loop`); ``backend="numpy"`` runs the vectorised loop of :mod:`swarm_envs.comm.reference_slots`, the
tested reference. Every random number of a step (ADC and intensity noise, CSMA access delays and backoffs)
is drawn before the slot loop by :func:`swarm_envs.comm.draws.draw_copies` in arrays indexed by robot, so
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

from typing import Any

import numpy as np

from swarm_envs._compile._worker import run_chunks
from swarm_envs.comm.bch import BCHCode, code as bch_code
from swarm_envs.comm.channel import ADCModel, adc_model_for
from swarm_envs.comm.deliveries import Deliveries, PreparedStep
from swarm_envs.comm.kernels import COUNTERS, DELIVERY_FIELDS, PER_ROBOT, build_frames, link_tables, slot_loop
from swarm_envs.comm.draws import GeneratorList, StepDraws, draw_copies
from swarm_envs.comm.protocol import (
    CSMA,
    MAX_PAYLOAD,
    RECV,
    SEQ_BITS,
    TYPE_BITS,
    DetectorBank,
    FrameFormat,
    KindRegistry,
    concat_padded,
    crc_table,
)
from swarm_envs.sim.copies import CopyRandom
from swarm_envs.sim.platforms import Platform, get_platform

__all__ = ["Network", "BITRATES", "COMM_MODES", "BACKENDS"]

BITRATES = (310, 650, 1080, 1160, 1670, 1800)  # bps offered by the e-puck hardware [T20 Sec. 5]
COMM_MODES = ("broadcast", "flooding")
BACKENDS = ("numpy", "numba")


class Network:
    """Bit-level SwarmCom simulation of ``n_robots`` robots (module docstring).

    Args:
        platform: robot platform (its IR model gives the gains, :func:`adc_model_for` the ADC).
        n_robots: swarm size N.
        rng: random generator (start-up ambient samples at reset, then :func:`~swarm_envs.comm.draws.draw_copies`
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
            pre-drawn random numbers (:func:`swarm_envs.comm.draws.draw_copies`) and give the same results.
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

    def step(self, links: Any, prepared: PreparedStep | None = None, threads: int = 1) -> Deliveries:
        """Simulate one control step of ``bitrate * dt`` bit slots over the given IR links
        (:class:`swarm_envs.ir.links.IRLinks` of the current poses) and return what was delivered.
        ``prepared``: this step's draws from :meth:`prepare_step` (default: drawn now; same numbers).
        ``threads``: the compiled slot loop runs the env copies in that many contiguous groups, on this thread
        and helper threads (:func:`swarm_envs._compile._worker.run_chunks`); the result is the same bit for
        bit for any number."""
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
        else:  # the numpy reference (tests compare the kernels with it)
            from swarm_envs.comm.reference_slots import link_tables_numpy

            tx_ptr, rx, tx, G, flat, sig_ptr, sig_rx = link_tables_numpy(self, rx, tx, gains)

        if prepared is None:
            prepared = self.prepare_step()
        elif prepared.first_slot != self.slot or prepared.carry_before != self.carry:
            raise ValueError("prepared was made for another step of this network (prepare_step, then step, once each)")
        S, draws = prepared.slots, prepared.draws
        self.carry = prepared.carry_after
        self.csma.draw_requested(draws.access)
        if self.backend == "numba":
            deliveries = self._slots_kernel(S, draws, tx_ptr, rx, G, sig_ptr, sig_rx, threads)
        else:
            from swarm_envs.comm.reference_slots import slots_numpy

            deliveries = slots_numpy(self, S, draws, tx_ptr, rx, tx, G, flat, sig_ptr, sig_rx)
        self._count("slots", values=S)
        return self._finish_step(deliveries)

    def draw_step(self, S: int) -> StepDraws:
        """Every random number of a step of S slots, drawn before the slot loop (same for both backends): all
        copies in one call, copy b from its own generator (:func:`swarm_envs.comm.draws.draw_copies`)."""
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

    def _slots_kernel(self, S, draws, tx_ptr, rx, G, sig_ptr, sig_rx, threads: int = 1) -> list[dict[str, np.ndarray]]:
        """The compiled slot loop (:func:`swarm_envs.comm.kernels.slot_loop`) over ``threads`` contiguous groups
        of env copies (each with its own counters and delivery records), on threads."""
        a, det, fmt, c = self.adc_model, self.det, self.fmt, self.code
        wmax = int(fmt.n_blocks(MAX_PAYLOAD)) * c.n + 1  # longest frame any header can announce
        det.ensure_capacity(wmax)
        if self.gt_buf.shape[1] < det.buf.shape[1]:
            self.gt_buf = np.concatenate([self.gt_buf, np.zeros((self.n, det.buf.shape[1] - self.gt_buf.shape[1]), bool)], axis=1)
        per_robot = np.zeros((len(PER_ROBOT), self.n), dtype=np.int64)
        state = det.state.view(np.int8)
        n_groups = max(1, min(int(threads), self.n_copies))
        edges = [self.copy_size * ((self.n_copies * k) // n_groups) for k in range(n_groups + 1)]  # robot rows
        counts = np.zeros((n_groups, len(COUNTERS)), dtype=np.int64)
        records: list[tuple[np.ndarray, np.ndarray]] = []
        for k in range(n_groups):
            dcap = (edges[k + 1] - edges[k]) * (1 + S // (fmt.header_blocks * c.n + 1))  # completions per robot and step are bounded
            records.append((np.zeros((dcap, len(DELIVERY_FIELDS)), dtype=np.int64), np.zeros((dcap, MAX_PAYLOAD), dtype=bool)))

        def group(k: int) -> int:
            d_int, d_pay = records[k]
            return slot_loop(
                S, self.slot, self.n_det, float(a.m_min), int(a.m_sup), self.m_tr, det.alpha, fmt.first_check_slots,
                tx_ptr, rx, G, sig_ptr, sig_rx, self.ambient, self.rx_level, self.response_kt, float(a.response_bias),
                draws.noise, draws.intensity_noise, draws.backoff,
                self.q_bits, self.q_slots, self.q_head, self.q_count, self.cur_bits, self.cur_slots, self.cur_pos, self.cur_id,
                self.sending, self.csma.backoff,
                state, det.m_max_est, det.thr, det.nbits, det.expect, det.phase, det.buf, det.best_m, det.best_det,
                det.last_s1, det.start_slot,
                self.gt_tx, self.gt_id, self.gt_buf, self.collided,
                c.n, c.k, c._table_msg, c._table_ok, fmt.header_blocks, fmt.header_bits, fmt.id_bits, fmt.with_sender,
                fmt.crc_bits, self._crc_table(), self.kinds.valid_codes(),
                self.copy_size, counts[k], per_robot, d_int, d_pay, self.rx_foreign, edges[k], edges[k + 1],
            )  # fmt: skip

        written = run_chunks(group, n_groups)
        self.slot += S
        for i, name in enumerate(COUNTERS):
            total = int(counts[:, i].sum())
            if total:
                self._count(name, values=total)
        for i, name in enumerate(PER_ROBOT):
            self.stats[name + "_per_robot"] += per_robot[i]
            self._step_stats[name + "_per_robot"] += per_robot[i]
        parts = []
        for (d_int, d_pay), D in zip(records, written):  # _finish_step puts the groups' records in the canonical order
            if D == 0:
                continue
            cols = {f: d_int[:D, i] for i, f in enumerate(DELIVERY_FIELDS)}
            out = {k: cols[k] for k in ("receiver", "origin", "sender", "seq", "type", "length", "detector", "slot", "done_slot", "transmitter", "interference")}
            out["corrupt"] = cols["corrupt"].astype(bool)
            out["payload"] = d_pay[:D, : int(cols["length"].max())].copy()
            parts.append(out)
        return parts

    def _finish_step(self, parts: list[dict[str, np.ndarray]]) -> Deliveries:
        if parts:
            d = {k: (np.concatenate([p[k] for p in parts]) if k != "payload" else concat_padded([p[k] for p in parts])) for k in parts[0]}
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
