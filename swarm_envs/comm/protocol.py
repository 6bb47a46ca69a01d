"""SwarmCom link protocol [T20 Sec. 4]: frame layout, the dynamic-threshold detector and CSMA.

Everything is vectorised over robots: the detector and the MAC hold one array entry per robot and are
advanced one bit slot at a time by :class:`swarm_envs.comm.network.Network`.

Frame on air [T20 Sec. 4.1]
---------------------------
On-off keying, one ADC sample per bit slot. A frame is one start symbol s1 followed by B blocks of 15
bits, each block a codeword of the configured BCH code [15, k] (:mod:`swarm_envs.comm.bch`). The
information bits (``B * k``, zero padded) are, most significant bit first::

    marker(1) = 1 | type(3) | length(8) | seq(7) | origin(id_bits) | [sender(id_bits)] | payload(length) | [crc(crc_bits)]

- ``marker``: always 1. A noise-triggered false start (the receiver sees s1 in noise, then mostly s0)
  produces marker = 0 and is aborted early (see :class:`DetectorBank`).
- ``type``: 1..7, 0 is invalid. 1 = application message (``"app"``); 2..7 are assigned on first use to
  system kinds (e.g. the scale-free bearing exchange) by :class:`KindRegistry`.
- ``length``: payload length in bits, 0..255.
- ``seq``: per-origin sequence number mod 128 (the reference firmware's 7-bit packet id).
- ``origin``: id of the robot that created the message, ``id_bits = max(6, ceil(log2 n_robots))`` bits:
  the firmware's 6-bit source field for swarms of up to 64 robots, wider for bigger swarms.
- ``sender``: id of the last hop; only present in flooding mode (where it may differ from origin).
- ``payload``: the message.
- ``crc``: optional CRC over all the bits before it (:func:`crc`), most significant bit first; a frame whose
  CRC does not match is dropped. Per platform (:attr:`swarm_envs.sim.platforms.Platform.frame_crc_bits`): the
  r-one's messages carry a 16-bit CRC [L Sec. 3.2.1, Table 3.3], so do the Droplet firmware's; [T20]
  gives the e-puck none (its frames are protected only by the BCH code of every block, the header
  included), and flooding adds our CRC-8 there.

Compared with the reference firmware (5 codewords [15,11] = 55 bits: id 7, source 6, destination 6,
type 4, data 32) we drop the destination (all traffic is broadcast or flooded), add the marker and an
explicit length (the data size is configurable), and widen the ids with the swarm.

Detector [T20 Sec. 4.2, 5.3, 4.5]
--------------------------------
``m = min`` over the robot's detectors. Idle: s1 (frame start) if ``m < m_t = m_max_est - m_tr``
[Eqs. (30)-(33)]; the start symbol's value is the amplitude A and the dynamic threshold
``m_t_dyn = floor(|m_t + A| / 2)`` [Eq. (36)] decides every following bit until the frame ends (or is
aborted), then the threshold resets to m_t. ``m_max_est`` is the receiver's own estimate of the ambient
value: the mean of ``startup_samples`` samples at reset (start-up), then an exponential moving average of
idle s0 samples (run-time adaptation; the per-sample mean over the detectors) [Sec. 4.5].

Abort rules (ours; the paper does not say how its firmware ends a frame): the frame is aborted when the
marker/type check fails (after the first 4 bits for the uncoded [15,15] code, after the first block for
coded frames), when the header blocks fail to decode or name an impossible origin/length, and it ends
after the number of blocks announced by the header.

CSMA [T20 Sec. 4.4]
-------------------
A robot with a queued frame first waits a random access delay (0..W-1 slots, so robots given messages at
the same step boundary do not all start together; drawn at the start of the next step); then it senses the channel: busy if its detector is
inside a frame or its last sample was s1. If free it starts sending in this slot; if busy it defers for
a random 1..W slots and senses again (non-persistent CSMA). Two robots that start in the same slot (or
hidden terminals that cannot sense each other) collide physically at receivers that hear both.
Half duplex: a transmitting robot does not receive.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from swarm_envs.comm.bch import BCHCode, code as bch_code
from swarm_envs.sim.platforms import CRC_WIDTHS  # the allowed ``crc_bits`` of a frame (0: no CRC)

__all__ = [
    "concat_padded",
    "FrameFormat",
    "KindRegistry",
    "DetectorBank",
    "CSMA",
    "IDLE",
    "RECV",
    "bits_to_uint",
    "uint_to_bits",
    "crc",
    "crc_table",
    "CRC_POLYS",
]

IDLE = 0
RECV = 1
MARKER_BITS = 1
TYPE_BITS = 3
LENGTH_BITS = 8
SEQ_BITS = 7
MAX_PAYLOAD = (1 << LENGTH_BITS) - 1


def concat_padded(arrs: list[np.ndarray]) -> np.ndarray:
    """Payload bit rows (k_i, W_i) of several deliveries stacked into one (sum k_i, max W_i) array, shorter
    rows padded with False."""
    if len(arrs) == 1:  # a single part: nothing to pad
        return arrs[0]
    W = max((x.shape[1] for x in arrs), default=0)
    return np.concatenate([np.pad(x, ((0, 0), (0, W - x.shape[1]))) if x.shape[1] < W else x for x in arrs], axis=0) if arrs else np.zeros((0, 0), bool)


def uint_to_bits(values: np.ndarray, width: int) -> np.ndarray:
    """Unsigned ints ``(...)`` -> bits ``(..., width)`` (bool, MSB first)."""
    shifts = np.arange(width - 1, -1, -1, dtype=np.int64)
    return ((np.asarray(values, dtype=np.int64)[..., None] >> shifts) & 1).astype(bool)


def bits_to_uint(bits: np.ndarray) -> np.ndarray:
    """Bits ``(..., width)`` (MSB first) -> int64 ``(...)``."""
    bits = np.asarray(bits)
    w = bits.shape[-1]
    if w == 0:
        return np.zeros(bits.shape[:-1], dtype=np.int64)
    return bits.astype(np.int64) @ (np.int64(1) << np.arange(w - 1, -1, -1, dtype=np.int64))


#: CRC generator polynomials by width: CRC-8 x^8 + x^2 + x + 1 (CRC-8/ATM; ours, for flooding) and CRC-16
#: x^16 + x^15 + x^2 + 1, the polynomial of the r-one's and the Droplet's message CRCs (module docstring)
CRC_POLYS = {8: 0x107, 16: 0x18005}
_CRC_TABLES: dict[int, np.ndarray] = {}


def crc_table(width: int = 8, size: int = 512) -> np.ndarray:
    """(>= size,) int64: entry j is x^(j+width) mod g, the CRC of a set bit followed by j bits (cached per
    width; ``g`` = :data:`CRC_POLYS` [width])."""
    if width not in CRC_POLYS:
        raise ValueError(f"CRC width must be one of {sorted(CRC_POLYS)}, got {width}")
    t = _CRC_TABLES.get(width)
    if t is None or t.size < size:
        poly, top = CRC_POLYS[width], 1 << width
        n = max(size, 512)
        t = np.zeros(n, dtype=np.int64)
        r = top ^ poly  # x^width mod g
        for j in range(n):  # t[j] = x^(j+width) mod g
            t[j] = r
            r <<= 1
            if r & top:
                r ^= poly
        _CRC_TABLES[width] = t
    return t


def crc(bits: np.ndarray, length: np.ndarray, width: int = 8) -> np.ndarray:
    """CRC (:data:`CRC_POLYS` [width], zero init, bits taken in order, no final XOR) of the first ``length[i]``
    bits of each row of ``bits (M, W)``, vectorised: the CRC is linear, so it is the XOR of the CRCs of
    the set bits, and a set bit followed by j bits contributes ``x^(j+width) mod g``.

    ``width=16``: the CRC-16 of the r-one [L Sec. 3.2.1, Table 3.3] and the Droplet firmware (the reflected
    table CRC with 0xA001 over bytes sent least significant bit first gives the same register, bit-reversed;
    docs/design.md#swarmcom-messaging). ``width=8``: ours, optional error detection for flooding on the
    e-puck, so that corrupted frames are dropped instead of re-flooded as new messages."""
    bits = np.asarray(bits, dtype=bool)
    M, W = bits.shape
    table = crc_table(width, W + 1)
    length = np.asarray(length, dtype=np.int64).reshape(M)
    j = length[:, None] - 1 - np.arange(W)[None, :]
    use = bits & (j >= 0)
    vals = np.where(use, table[np.clip(j, 0, None)], 0)
    return np.bitwise_xor.reduce(vals, axis=1) if W else np.zeros(M, dtype=np.int64)


class KindRegistry:
    """Message kinds <-> 3-bit type codes. ``"app"`` = 1; system kinds get 2..7 on first use."""

    def __init__(self) -> None:
        self._code: dict[str, int] = {"app": 1}
        self._name: dict[int, str] = {1: "app"}

    def code(self, kind: str) -> int:
        c = self._code.get(kind)
        if c is None:
            c = len(self._code) + 1
            if c >= (1 << TYPE_BITS):
                raise ValueError(f"too many message kinds (max {(1 << TYPE_BITS) - 1}): {list(self._code)}")
            self._code[kind] = c
            self._name[c] = kind
        return c

    def name(self, type_code: int) -> str:
        return self._name.get(int(type_code), "?")

    def valid_codes(self) -> np.ndarray:
        """(8,) bool: which type codes are registered."""
        v = np.zeros(1 << TYPE_BITS, dtype=bool)
        v[list(self._name)] = True
        return v


@dataclass
class FrameFormat:
    """Frame layout for one network (module docstring).

    Attributes:
        code: BCH code of every block.
        id_bits: width of the origin / sender fields.
        with_sender: True in flooding mode (header carries the last-hop id).
        crc_bits: width of the CRC over header + payload appended to the information bits (:func:`crc`):
            0 (none, as [T20]), 8 (CRC-8, ours) or 16 (the CRC-16 of the r-one [L Table 3.3] and the Droplet).
    """

    code: BCHCode
    id_bits: int
    with_sender: bool = False
    crc_bits: int = 0
    header_bits: int = field(init=False)

    def __post_init__(self) -> None:
        self.header_bits = MARKER_BITS + TYPE_BITS + LENGTH_BITS + SEQ_BITS + self.id_bits * (2 if self.with_sender else 1)

    @classmethod
    def for_swarm(
        cls, n_robots: int, code: tuple[int, int] | BCHCode = (15, 15), with_sender: bool = False, crc_bits: int = 0
    ) -> "FrameFormat":
        c = code if isinstance(code, BCHCode) else bch_code(*code)
        id_bits = max(6, int(np.ceil(np.log2(max(2, n_robots)))))
        if crc_bits not in CRC_WIDTHS:
            raise ValueError(f"crc_bits must be one of {CRC_WIDTHS}, got {crc_bits}")
        return cls(c, id_bits, with_sender, int(crc_bits))

    @property
    def header_blocks(self) -> int:
        return self.code.blocks_for(self.header_bits)

    @property
    def first_check_slots(self) -> int:
        """Bits after the start symbol at which marker/type are checked (module docstring)."""
        return MARKER_BITS + TYPE_BITS if self.code.k == self.code.n else self.code.n

    def n_blocks(self, payload_len: np.ndarray | int) -> np.ndarray:
        return -(-(self.header_bits + np.asarray(payload_len) + self.crc_bits) // self.code.k)

    def frame_slots(self, payload_len: np.ndarray | int) -> np.ndarray:
        """Bit slots of a whole frame on air (start symbol + blocks)."""
        return 1 + self.n_blocks(payload_len) * self.code.n

    def build(
        self,
        type_code: np.ndarray,
        seq: np.ndarray,
        origin: np.ndarray,
        sender: np.ndarray,
        payload: np.ndarray,
        length: np.ndarray,
    ) -> tuple[np.ndarray, np.ndarray]:
        """Build M frames.

        Args:
            type_code, seq, origin, sender, length: (M,) ints.
            payload: (M, Lmax) bool, row i valid up to ``length[i]``.

        Returns:
            bits (M, S) bool, whole frames on air including the start symbol; slots (M,) frame lengths.
        """
        M = int(np.asarray(type_code).shape[0])
        payload = np.asarray(payload, dtype=bool).reshape(M, -1)
        length = np.asarray(length, dtype=np.int64)
        if (length > MAX_PAYLOAD).any() or (length > payload.shape[1]).any() or (length < 0).any():
            raise ValueError(f"payload length negative, longer than {MAX_PAYLOAD} bits or than the given array")
        fields = [
            np.ones((M, 1), dtype=bool),
            uint_to_bits(type_code, TYPE_BITS),
            uint_to_bits(length, LENGTH_BITS),
            uint_to_bits(np.asarray(seq) % (1 << SEQ_BITS), SEQ_BITS),
            uint_to_bits(origin, self.id_bits),
        ]
        if self.with_sender:
            fields.append(uint_to_bits(sender, self.id_bits))
        header = np.concatenate(fields, axis=1)
        Lmax = int(length.max()) if M else 0
        pay = payload[:, :Lmax] & (np.arange(Lmax)[None, :] < length[:, None])
        info = np.concatenate([header, pay], axis=1)
        w = self.crc_bits
        if w:
            check = uint_to_bits(crc(info, self.header_bits + length, w), w)
            info = np.concatenate([info, np.zeros((M, w), dtype=bool)], axis=1)
            pos = (self.header_bits + length)[:, None] + np.arange(w)[None, :]
            info[np.arange(M)[:, None], pos] = check
        coded = self.code.encode_stream(info)  # (M, Bmax*n), blocks beyond a frame's own length unused
        slots = self.frame_slots(length)
        bits = np.concatenate([np.ones((M, 1), dtype=bool), coded], axis=1)
        bits &= np.arange(bits.shape[1])[None, :] < slots[:, None]
        return bits, slots

    def crc_ok(self, info: np.ndarray, length: np.ndarray) -> np.ndarray:
        """(M,) True where the CRC field after the payload matches (always True without CRC)."""
        info = np.asarray(info, dtype=bool)
        M = info.shape[0]
        w = self.crc_bits
        if not w:
            return np.ones(M, dtype=bool)
        end = self.header_bits + np.asarray(length, dtype=np.int64)
        pos = np.minimum(end[:, None] + np.arange(w)[None, :], info.shape[1] - 1)
        got = bits_to_uint(info[np.arange(M)[:, None], pos])
        return got == crc(info, end, w)

    def parse_header(self, info: np.ndarray) -> dict[str, np.ndarray]:
        """Header fields of decoded information bits ``(M, >= header_bits)``."""
        info = np.asarray(info, dtype=bool)
        o = 0
        out = {}
        for name, w in (("marker", MARKER_BITS), ("type", TYPE_BITS), ("length", LENGTH_BITS), ("seq", SEQ_BITS), ("origin", self.id_bits)):
            out[name] = bits_to_uint(info[:, o : o + w])
            o += w
        if self.with_sender:
            out["sender"] = bits_to_uint(info[:, o : o + self.id_bits])
            o += self.id_bits
        else:
            out["sender"] = out["origin"].copy()
        return out


class DetectorBank:
    """The SwarmCom receivers of N robots: per-robot state arrays [T20 Sec. 4.2, Eq. (36), Sec. 4.5].

    Args:
        n: number of robots.
        n_detectors: detectors per robot.
        relative_threshold: m_tr (counts) [Eq. (33)].
        max_bits: initial raw-bit buffer length per robot (grows on demand).
        ambient_alpha: EMA weight of one idle sample in the run-time m_max adaptation.
    """

    def __init__(self, n: int, relative_threshold: float = 5.0, max_bits: int = 64, ambient_alpha: float = 1.0 / 256) -> None:
        self.n = int(n)
        self.m_tr = float(relative_threshold)
        self.alpha = float(ambient_alpha)
        self.state = np.zeros(n, dtype=np.int8)
        self.m_max_est = np.zeros(n)
        self.thr = np.zeros(n)  # dynamic threshold while RECV
        self.nbits = np.zeros(n, dtype=np.int64)  # bits received after the start symbol
        self.expect = np.zeros(n, dtype=np.int64)  # next check point / frame end (bits)
        self.phase = np.zeros(n, dtype=np.int8)  # 0 = before first check, 1 = before header, 2 = payload
        self.buf = np.zeros((n, max_bits), dtype=bool)
        self.best_m = np.zeros(n, dtype=np.int64)
        self.best_det = np.zeros(n, dtype=np.int64)
        self.last_s1 = np.zeros(n, dtype=bool)
        self.start_slot = np.zeros(n, dtype=np.int64)

    def reset(self, m_max_startup: np.ndarray) -> None:
        """Idle all receivers; ``m_max_startup`` (N,) is each robot's start-up ambient estimate."""
        self.state[:] = IDLE
        self.m_max_est[:] = m_max_startup
        self.nbits[:] = 0
        self.last_s1[:] = False
        self.buf[:] = False

    @property
    def m_t(self) -> np.ndarray:
        """Static decision threshold m_t = m_max_est - m_tr (counts) [Eq. (33)]."""
        return self.m_max_est - self.m_tr

    def ensure_capacity(self, nbits: int) -> None:
        if nbits > self.buf.shape[1]:
            new = np.zeros((self.n, max(nbits, 2 * self.buf.shape[1])), dtype=bool)
            new[:, : self.buf.shape[1]] = self.buf
            self.buf = new

    def sample(self, m: np.ndarray, listen: np.ndarray, first_check: int, slot: int) -> dict[str, np.ndarray]:
        """Advance every receiver by one bit slot.

        Args:
            m: (N, n_detectors) ADC counts of this slot.
            listen: (N,) bool, robots that receive this slot (not transmitting).
            first_check: bits after the start symbol at which the first check point falls.
            slot: global slot counter (recorded as a frame's start time).

        Returns:
            dict of index arrays: ``started`` (robots that detected a start symbol this slot), ``got_bit``
            (robots that stored a bit), ``check`` (robots that reached their check point and must be
            examined by the caller, see :meth:`finish` / :meth:`set_expect`).
        """
        mv = m.min(axis=1)
        md = m.argmin(axis=1)
        m_t = self.m_max_est - self.m_tr
        in_frame = self.state == RECV
        thr = np.where(in_frame, self.thr, m_t)
        s1 = mv < thr
        self.last_s1 = s1 & listen
        idle = listen & ~in_frame
        started = np.flatnonzero(idle & s1)
        quiet = np.flatnonzero(idle & ~s1)
        if quiet.size:  # run-time ambient adaptation on idle s0 samples [Sec. 4.5]
            self.m_max_est[quiet] += self.alpha * (m[quiet].mean(axis=1) - self.m_max_est[quiet])
        if started.size:
            A = mv[started]
            self.state[started] = RECV
            self.thr[started] = np.floor(np.abs(m_t[started] + A) / 2.0)  # Eq. (36)
            self.nbits[started] = 0
            self.expect[started] = first_check
            self.phase[started] = 0
            self.best_m[started] = A
            self.best_det[started] = md[started]
            self.start_slot[started] = slot
        got = np.flatnonzero(listen & in_frame)
        if got.size:
            k = self.nbits[got]
            self.ensure_capacity(int(k.max()) + 1)
            self.buf[got, k] = s1[got]
            self.nbits[got] = k + 1
            better = mv[got] < self.best_m[got]
            bg = got[better]
            self.best_m[bg] = mv[bg]
            self.best_det[bg] = md[bg]
        check = got[self.nbits[got] == self.expect[got]] if got.size else got
        # a transmitting robot drops whatever it was receiving (half duplex)
        deaf = np.flatnonzero(~listen & in_frame)
        return {"started": started, "got_bit": got, "check": check, "deaf": deaf}

    def finish(self, robots: np.ndarray) -> None:
        """End (deliver or abort) the frames of ``robots``: back to idle, threshold resets to m_t."""
        self.state[robots] = IDLE
        self.nbits[robots] = 0


class CSMA:
    """Carrier-sense multiple access state of N robots [T20 Sec. 4.4] (module docstring).

    Args:
        n: number of robots.
        window: contention window W (slots): access delay 0..W-1, deferral 1..W.
    """

    def __init__(self, n: int, window: int = 32) -> None:
        self.n = int(n)
        self.window = int(window)
        if not 1 <= self.window < 2**31:  # the compiled drawer's bounded integers (comm.kernels._copy_integers)
            raise ValueError(f"backoff window must be an integer in [1, 2**31) slots, got {window!r}")
        self.backoff = np.zeros(n, dtype=np.int64)

    def reset(self) -> None:
        self.backoff[:] = 0

    def request(self, robots: np.ndarray) -> None:
        """Mark robots whose queue just became non-empty: their access delay is drawn at the start of the
        next step (:meth:`draw_requested`), so every draw of a step comes from pre-drawn per-robot arrays."""
        if len(robots):
            self.backoff[robots] = -1

    def draw_requested(self, delays: np.ndarray) -> None:
        """Give every requested robot its access delay ``delays[robot]`` (``delays`` (N,) ints in [0, W))."""
        req = self.backoff < 0
        self.backoff[req] = delays[req]

    def arm(self, robots: np.ndarray, draws: np.ndarray) -> None:
        """Fresh random access delay ``draws[robot]`` (``draws`` (N,) ints in [0, W)) before the next
        carrier sense of ``robots``."""
        if len(robots):
            self.backoff[robots] = draws[robots]

    def decide(self, pending: np.ndarray, busy: np.ndarray, draws: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """One slot of CSMA. ``pending`` (N,) bool: has a frame waiting and is not sending; ``busy`` (N,) bool:
        carrier sensed; ``draws`` (N,) ints in [0, W) of this slot (a deferring robot waits ``1 + draw``).
        Returns (robots that start sending now, robots that deferred)."""
        waiting = pending & (self.backoff > 0)
        self.backoff[waiting] -= 1
        ready = pending & ~waiting
        go = np.flatnonzero(ready & ~busy)
        defer = np.flatnonzero(ready & busy)
        if defer.size:
            self.backoff[defer] = 1 + draws[defer]
        return go, defer
