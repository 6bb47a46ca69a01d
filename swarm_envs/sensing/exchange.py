"""Round-based bearing exchange for scale-free coordinates [L Sec. 5.2.2, Sec. 3.2.1; docs/design.md#bearing-exchange].

[L Sec. 5.2.2]: in communication step 1 every robot broadcasts its id and receivers record the bearing of
the sender; in step 2 every robot broadcasts its id plus the ids and bearings of its neighbours. After the
round robot u knows ``theta_u(v)`` for each neighbour v and ``theta_v(w)`` for every ``w in N(v)``: exactly
the input of the 2-hop algorithm (:func:`swarm_envs.sensing.scale_free.coordinates_all`). On the r-one
both steps are the same periodic broadcast (every message's reception yields the sender's bearing, and
every message carries the sender's current neighbour list), which is what we model.

Modes
-----
``mode="ideal"``: every step, each robot's own row is its current bearing readings and it receives every
neighbour's current row instantly and losslessly (ages 0). For ablations.

``mode="network"``: the rows travel as SwarmCom *system* traffic, in rounds [L Sec. 3.2.2]. Every
``period`` steps (each robot with its own random phase, drawn from the generator passed in, like the
thesis's random start delay) a robot's round starts and it queues one message; all due robots at once with
``network.queue_system(robots, bits, kind, lengths=...)``; the env advances the network
(``network.step(links) -> Deliveries``) and hands the deliveries back to :meth:`BearingExchange.receive`.
"When a new round begins, each robot clears all prior neighbor information and updates the network
information again" [L Sec. 3.2.2]: during its round a robot fills a fresh table; when its following round
starts that table becomes its published one (what :meth:`BearingExchange.knowledge` returns and what it
broadcasts) and the filling starts empty again. A robot therefore knows, and reports, exactly the
neighbours it heard during its last complete round; a neighbour it did not hear for a whole round is
gone at the following round start. This holds on every platform: the exchange is the thesis's round protocol
wherever it runs.

A robot's table holds the robots it *received a message from*, with the receiver's own bearing of the
robot the frame *says* sent it: the header's decoded ``origin`` looked up in the receiver's readings
(``readings.rx``/``readings.tx`` are what the receiver believes: on the sector source the bearings
:class:`swarm_envs.sensing.bearing_sensor.MessageBearings` measured on this step's frames, keyed by decoded
ids, so this very frame's bearing). No lookup uses the true sender: a frame whose origin decodes to another
robot's id is matched to the receiver's bearing of that other robot (if it has one). A lost message means a
missing own bearing and a missing row for that round. Losses therefore remove information (fewer
triangles, fewer rigid robots) but never mix up whose bearing is whose. A decoded frame is rejected when
its content is inconsistent (announced count vs payload length, an id or an origin outside the receiver's
swarm, or a list naming the sender itself); an uncoded ([15,15]) frame whose bearing bits flipped can still
slip through: that is the channel's corruption and it reaches the coordinates as a bearing error.

Bit encoding of a message (payload, most significant bit first)::

    count (c_bits) | count x [ neighbour id (id_bits) | bearing sector (bearing_bits) ]

- The sender's own id is not repeated: the SwarmCom frame header already carries the origin id
  (:mod:`swarm_envs.comm.protocol`) and ``Deliveries.origin`` reports it.
- ``id_bits = max(1, ceil(log2 n_robots))``; ``bearing_bits = 4`` by default: the bearing is sent as the
  index ``round(theta / (2 pi / 16)) mod 16`` of the r-one's 16 sectors of 22.5 degrees [L Sec. 3.2.1]
  (lossless for r-one sector bearings, a quantisation for continuous R&B bearings).
- ``count`` is capped at ``max_entries`` so that the payload fits the protocol's 8-bit length field
  (255 bits): ``max_entries = min(k_max, (255 - c_bits) // (id_bits + bearing_bits))``; with 1000 robots,
  id 10 bits + 4 = 14 bits per neighbour, i.e. at most 17 neighbours per message.
- A robot reports the neighbours of its last complete round, most recently heard first.

Thesis timing for comparison: ``T_round = 2 (1 + N)^2 t_msg`` with t_msg = 32.8 ms for a 3-byte message at
1250 bps [L Sec. 3.2.1] (2.5 s for 5 neighbours); :func:`thesis_round_time` gives it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from swarm_envs.sim.copies import CopyRandom
from swarm_envs.sensing.exchange_kernels import decode_bits, encode_tables, roll_tables, store_deliveries

__all__ = ["BearingExchange", "NeighbourKnowledge", "encode_rows", "decode_rows", "thesis_round_time", "readings_table", "dequantise"]

MAX_PAYLOAD_BITS = 255  # the SwarmCom frame's 8-bit length field (swarm_envs.comm.protocol)
NEVER = -(10**9)  # the time of an empty slot

# a robot's tables: own entries (ids, own bearing, time heard) and the rows its neighbours reported (ids,
# bearings, time received); filled during its round (_FILL) and, from the following round start, published (_PUB)
_FILL = ("tab_ids", "tab_bear", "tab_time", "row_ids", "row_bear", "row_time")
_PUB = ("pub_ids", "pub_bear", "pub_time", "pub_row_ids", "pub_row_bear", "pub_row_time")
_DTYPES = (np.int64, float, np.int64, np.int64, float, np.int64)
_EMPTY = (-1, np.nan, NEVER, -1, np.nan, NEVER)


@dataclass
class NeighbourKnowledge:
    """What each robot knows after an exchange round [L Sec. 5.2.2] (slot layout, K slots per robot).

    The output of :class:`BearingExchange` and the input of the 2-hop algorithm
    (:func:`swarm_envs.sensing.scale_free.coordinates_all`, which re-exports this class).

    Attributes:
        ids: (N, K) int, neighbour ids of each robot (-1 = empty slot).
        bearings: (N, K) float, own bearing ``theta_u(ids[u, i])`` (rad).
        row_ids: (N, K, K2) int, the neighbour list reported by neighbour ``ids[u, i]`` (-1 = empty, and all
            -1 if nothing was received from that neighbour).
        row_bearings: (N, K, K2) float, the bearings ``theta_z(row_ids[u, i, j])`` it reported (rad).
        row_age: (N, K) int, steps since the row was received (0 = fresh, -1 = never received).
        robot_ids: (N,) int, the id of each row's robot (default ``arange(N)``); lets a single robot be
            evaluated with N = 1.
    """

    ids: np.ndarray
    bearings: np.ndarray
    row_ids: np.ndarray
    row_bearings: np.ndarray
    row_age: np.ndarray | None = None
    robot_ids: np.ndarray | None = None

    @property
    def n_robots(self) -> int:
        return int(self.ids.shape[0])


def thesis_round_time(n_neighbours: int, t_msg: float = 0.0328) -> float:
    """Network round time (s) ``2 (1 + N)^2 t_msg`` [L Sec. 3.2.1]; t_msg for a 3-byte message."""
    return 2.0 * (1 + n_neighbours) ** 2 * t_msg


def _uint_bits(v: np.ndarray, width: int) -> np.ndarray:
    """(...,) uint -> (..., width) bits, MSB first."""
    v = np.asarray(v, dtype=np.int64)
    return ((v[..., None] >> np.arange(width - 1, -1, -1)) & 1).astype(np.uint8)


def _quantise(theta: np.ndarray, bearing_bits: int) -> np.ndarray:
    n = 1 << bearing_bits
    return np.mod(np.rint(np.asarray(theta) / (2 * np.pi / n)).astype(np.int64), n)


def dequantise(q: np.ndarray, bearing_bits: int) -> np.ndarray:
    """Bearings (rad, in (-pi, pi]) of the ``bearing_bits``-bit codes ``q`` of :func:`encode_rows`."""
    n = 1 << bearing_bits
    a = np.asarray(q, dtype=float) * (2 * np.pi / n)
    return np.pi - np.mod(np.pi - a, 2 * np.pi)


def encode_rows(ids: np.ndarray, bearings: np.ndarray, id_bits: int, count_bits: int, bearing_bits: int = 4) -> np.ndarray:
    """Encode R neighbour lists at once. ids (R, L) (-1 = none), bearings (R, L) rad -> (R, n_bits) uint8,
    zero padded after each row's ``count_bits + count * (id_bits + bearing_bits)`` bits."""
    ids = np.asarray(ids, dtype=np.int64)
    R, L = ids.shape
    present = ids >= 0
    count = present.sum(1)
    # compact present entries to the front, keeping their order
    order = np.argsort(~present, axis=1, kind="stable")
    cid = np.take_along_axis(ids, order, 1)
    cb = np.take_along_axis(np.asarray(bearings, float), order, 1)
    ent = np.concatenate([_uint_bits(np.maximum(cid, 0), id_bits), _uint_bits(_quantise(np.nan_to_num(cb), bearing_bits), bearing_bits)], -1)
    ent = np.where((np.arange(L)[None, :] < count[:, None])[:, :, None], ent, 0).reshape(R, -1)
    return np.concatenate([_uint_bits(count, count_bits), ent], 1)


def decode_rows(bits: np.ndarray, id_bits: int, count_bits: int, max_entries: int, bearing_bits: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """Inverse of :func:`encode_rows`: bits (R, >= needed) -> ids (R, max_entries) (-1 pad), bearings (rad).
    The integers are read by a kernel (:func:`swarm_envs.sensing.exchange_kernels.decode_bits`; numpy reference:
    :func:`swarm_envs._compile.reference.decode_rows`), the bearings by the formula here."""
    bits = np.ascontiguousarray(bits, dtype=np.uint8)
    if bits.ndim != 2:
        raise ValueError(f"decode_rows: bits must be (rows, bits), got shape {bits.shape}")
    ids, q = decode_bits(bits, int(id_bits), int(count_bits), int(max_entries), int(bearing_bits))
    return ids, np.where(ids >= 0, dequantise(q, bearing_bits), np.nan)


def readings_table(rx: np.ndarray, tx: np.ndarray, bearing: np.ndarray, n_robots: int, k_max: int) -> tuple[np.ndarray, np.ndarray]:
    """(N, k_max) neighbour ids (ascending, -1 pad) and bearings from per-link readings (vectorised).

    Links with a NaN bearing are dropped; beyond k_max neighbours the lowest ids are kept.
    """
    rx = np.asarray(rx, dtype=np.int64)
    tx = np.asarray(tx, dtype=np.int64)
    b = np.asarray(bearing, dtype=float)
    ok = np.isfinite(b) & (rx != tx)
    rx, tx, b = rx[ok], tx[ok], b[ok]
    o = np.lexsort((tx, rx))
    rx, tx, b = rx[o], tx[o], b[o]
    ids = -np.ones((n_robots, k_max), dtype=np.int64)
    th = np.full((n_robots, k_max), np.nan)
    if rx.size:
        start = np.searchsorted(rx, rx, side="left")
        slot = np.arange(rx.size) - start
        keep = slot < k_max
        ids[rx[keep], slot[keep]] = tx[keep]
        th[rx[keep], slot[keep]] = b[keep]
    return ids, th


class BearingExchange:
    """Periodic bearing-list exchange [L Sec. 5.2.2]; output in the form
    :func:`swarm_envs.sensing.scale_free.coordinates_all` consumes.

    Args:
        n_robots: swarm size N.
        mode: ``"ideal"`` (instant, lossless) or ``"network"`` (SwarmCom system traffic).
        k_max: slots per robot (neighbour table size K) and longest reported list.
        network: a :class:`swarm_envs.comm.network.Network` (network mode); may also be passed to
            :meth:`send`.
        period: steps between two broadcasts of one robot, the length of its round (network mode).
        bearing_bits: bits per transmitted bearing (4 = 16 sectors of 22.5 degrees).
        kind: SwarmCom system message kind.
        rng: generator for the broadcast phases (network mode), or per-copy streams
            (:class:`swarm_envs.sim.copies.CopyRandom`) when the exchange runs several env copies.
        n_copies: env copies of ``n_robots`` robots each (rows copy-major; ids in messages are a copy's own
            0..n_robots-1, so messages and their widths are those of a single env).
    """

    def __init__(
        self,
        n_robots: int,
        mode: str = "ideal",
        k_max: int = 16,
        network: Any = None,
        period: int = 10,
        bearing_bits: int = 4,
        kind: str = "bearing_exchange",
        rng: np.random.Generator | CopyRandom | None = None,
        n_copies: int = 1,
    ) -> None:
        if mode not in ("ideal", "network"):
            raise ValueError(f"unknown exchange mode {mode!r}; allowed: 'ideal', 'network'")
        self.copy_size = int(n_robots)
        self.n_copies = int(n_copies)
        self.n = self.copy_size * self.n_copies
        self.copy_of = np.repeat(np.arange(self.n_copies), self.copy_size)
        self.offset = self.copy_of * self.copy_size  # first robot of each robot's copy
        self.mode = mode
        self.k_max = int(k_max)
        self.network = network
        self.period = max(1, int(period))
        self.bearing_bits = int(bearing_bits)
        self.kind = kind
        self.id_bits = max(1, int(np.ceil(np.log2(max(self.copy_size, 2)))))
        e = self.id_bits + self.bearing_bits
        self.count_bits = max(1, int(np.ceil(np.log2(self.k_max + 1))))
        self.max_entries = int(min(self.k_max, (MAX_PAYLOAD_BITS - self.count_bits) // e))
        rng = rng if rng is not None else np.random.default_rng()
        self.rng = rng if isinstance(rng, CopyRandom) else CopyRandom([rng] * self.n_copies)
        self.reset()

    # ------------------------------------------------------------------ state
    def reset(self, rng: np.random.Generator | None = None, copies: np.ndarray | None = None, rngs: list | None = None) -> None:
        """Clear all tables and draw new broadcast phases (of ``copies`` only if given, with their new
        generators ``rngs``; ``rng`` replaces a single env's generator)."""
        if rng is not None:
            self.rng = CopyRandom([rng] * self.n_copies)
        if copies is None:
            n, k = self.n, self.k_max
            self.t = np.zeros(self.n_copies, np.int64)
            self.phase = self.rng.integers(0, self.period, self.copy_of)
            w = self.k_max if self.mode == "ideal" else self.max_entries  # ideal rows are not truncated
            shapes = ((n, k), (n, k), (n, k), (n, k, w), (n, k, w), (n, k))
            for names in (_FILL, _PUB):  # the tables filled in the current round and the last complete round's
                for name, shape, dtype, value in zip(names, shapes, _DTYPES, _EMPTY):
                    setattr(self, name, np.full(shape, value, dtype))
            self.stats = {"sent": 0, "received": 0, "bits_sent": 0, "rejected": 0}
            return
        copies = np.asarray(copies, dtype=np.int64).reshape(-1)
        if rngs is not None:
            for b, g in zip(copies, rngs):
                self.rng.generators[b] = g
        rows = np.flatnonzero(np.isin(self.copy_of, copies))
        self.t[copies] = 0
        self.phase[rows] = self.rng.integers(0, self.period, self.copy_of[rows])
        for names in (_FILL, _PUB):
            for name, value in zip(names, _EMPTY):
                getattr(self, name)[rows] = value

    @property
    def _now(self) -> np.ndarray:
        """(N,) each robot's copy clock (steps since its reset)."""
        return self.t[self.copy_of]

    def bits_per_message(self, count: int) -> int:
        """Payload length (bits) of a message listing ``count`` neighbours."""
        return self.count_bits + min(count, self.max_entries) * (self.id_bits + self.bearing_bits)

    # ------------------------------------------------------------------ ideal
    def _ideal(self, readings: Any) -> NeighbourKnowledge:
        ids, th = readings_table(readings.rx, readings.tx, readings.bearing, self.n, self.k_max)
        self.pub_ids, self.pub_bear = ids, th
        self.pub_time = np.where(ids >= 0, self._now[:, None], NEVER)
        safe = np.maximum(ids, 0)
        has = (ids >= 0)[:, :, None]
        self.pub_row_ids = np.where(has, ids[safe], -1)
        self.pub_row_bear = np.where(has, th[safe], np.nan)
        self.pub_row_time = self.pub_time.copy()
        return self.knowledge()

    # ------------------------------------------------------------------ network
    def due(self, t: int | None = None) -> np.ndarray:
        """Robots whose broadcast is due at step t (default: the current step): the robots whose round
        starts then."""
        t = self._now if t is None else t
        return np.nonzero((t - self.phase) % self.period == 0)[0]

    def send(self, network: Any = None) -> int:
        """Queue this step's messages (network mode): each due robot starts a new round (:meth:`start_rounds`)
        and broadcasts the table of the round that just ended.

        Returns the number of messages queued.
        """
        net = network if network is not None else self.network
        if self.mode != "network":
            return 0
        if net is None:
            raise ValueError("network mode needs a Network (constructor or send(network))")
        robots = self.due()
        if robots.size == 0:
            return 0
        self.start_rounds(robots)
        bits, lens = self.encode(robots)
        net.queue_system(robots, bits[:, : int(lens.max())].astype(bool), self.kind, lengths=lens)  # all lengths at once
        self.stats["sent"] += int(robots.size)
        self.stats["bits_sent"] += int(lens.sum())
        return int(robots.size)

    def encode(self, robots: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Message bits (R, n_bits) uint8 (zero padded) and payload lengths (R,) of ``robots``' published
        tables (their last complete round): most recently heard first, at most ``max_entries``, ids in a
        copy's own numbering, in the format of :func:`encode_rows` (compiled:
        :func:`swarm_envs.sensing.exchange_kernels.encode_tables`; numpy reference:
        :func:`swarm_envs._compile.reference.encode_tables`)."""
        robots = np.asarray(robots, dtype=np.int64)
        return encode_tables(
            self.pub_ids, self.pub_bear, self.pub_time, robots, self.offset.astype(np.int64), self.max_entries,
            self.id_bits, self.count_bits, self.bearing_bits,
        )

    def receive(self, deliveries: Any, readings: Any) -> None:
        """Decode this step's deliveries (network mode) and update tables.

        Args:
            deliveries: ``Deliveries`` with ``receiver``, ``origin``, ``payload``, ``kind`` arrays (payload
                either an (D, L) bit array or a sequence of 1-D bit arrays). Only ``kind == self.kind`` is
                used.
            readings: the receiver's current readings (``rx``, ``tx``, ``bearing``, ``valid``), keyed by the ids
                the receiver believes (decoded); the own bearing of a sender is the reading
                ``(receiver, decoded origin)`` (none if the receiver has no such reading).
        """
        if deliveries is None:
            return
        recv = np.asarray(deliveries.receiver, dtype=np.int64).reshape(-1)
        if recv.size == 0:
            return
        origin = np.asarray(deliveries.origin, dtype=np.int64).reshape(-1)
        kinds = np.asarray(deliveries.kind).reshape(-1)
        sel = np.nonzero(kinds == self.kind)[0]
        if sel.size == 0:
            return
        payload = deliveries.payload
        if isinstance(payload, np.ndarray) and payload.ndim == 2:
            bits = payload[sel]
        else:
            rows = [np.asarray(payload[i], dtype=np.uint8).reshape(-1) for i in sel]
            width = max((r.size for r in rows), default=0)
            bits = np.zeros((len(rows), max(width, 1)), np.uint8)
            for j, r in enumerate(rows):
                bits[j, : r.size] = r
        ids, th = decode_rows(bits, self.id_bits, self.count_bits, self.max_entries, self.bearing_bits)
        # sanity checks on what the frame decoded to (uncoded frames can arrive corrupted): the announced
        # count must match the payload length, ids must exist and not name the sender itself
        count = (ids >= 0).sum(1)
        recv, origin = recv[sel], origin[sel]
        ids = np.where(ids >= 0, ids + self.offset[recv][:, None], -1)  # a copy's own numbering -> robot rows
        sane = ~((ids >= self.offset[recv][:, None] + self.copy_size) | (ids == origin[:, None])).any(1)
        sane &= (origin >= self.offset[recv]) & (origin < self.offset[recv] + self.copy_size)  # a robot of its swarm
        length = getattr(deliveries, "length", None)
        if length is not None:
            length = np.asarray(length, dtype=np.int64).reshape(-1)[sel]
            sane &= length == self.count_bits + count * (self.id_bits + self.bearing_bits)
        self.stats["rejected"] = self.stats.get("rejected", 0) + int((~sane).sum())
        ids, th, recv, origin = ids[sane], th[sane], recv[sane], origin[sane]
        if recv.size == 0:
            return
        # the receiver's own bearing of the robot the frame says sent it: its reading (recv, decoded origin)
        key_l = np.asarray(readings.rx, np.int64) * self.n + np.asarray(readings.tx, np.int64)
        okl = np.asarray(readings.valid, bool)
        key_l, bear_l = key_l[okl], np.asarray(readings.bearing, float)[okl]
        o = np.argsort(key_l)
        key_l, bear_l = key_l[o], bear_l[o]
        key = recv * self.n + origin
        pos = np.clip(np.searchsorted(key_l, key), 0, max(key_l.size - 1, 0))
        found = key_l.size > 0
        hit = (key_l[pos] == key) if found else np.zeros(key.size, bool)
        own_b = np.where(hit, bear_l[pos] if found else np.nan, np.nan)
        self.stats["received"] += int(recv.size)
        if ids.shape[1] != self.row_ids.shape[2]:  # an ideal-mode exchange keeps rows of k_max entries
            raise ValueError(f"decoded rows of {ids.shape[1]} entries do not fit the tables' rows of {self.row_ids.shape[2]}")
        # one delivery after the other (numpy reference: swarm_envs._compile.reference.store_deliveries)
        store_deliveries(
            recv, origin, own_b.astype(float), hit, ids, np.asarray(th, float), self._now, self.tab_ids, self.tab_bear,
            self.tab_time, self.row_ids, self.row_bear, self.row_time,
        )

    def start_rounds(self, robots: np.ndarray) -> None:
        """Start a new round of ``robots`` [L Sec. 3.2.2]: the tables they filled during the round that ends
        become their published ones (what :meth:`knowledge` and their broadcasts read), and the tables they
        fill next start empty: "each robot clears all prior neighbor information" (compiled:
        :func:`swarm_envs.sensing.exchange_kernels.roll_tables`; numpy reference: :func:`swarm_envs._compile.reference.roll_tables`)."""
        robots = np.asarray(robots, dtype=np.int64).reshape(-1)
        roll_tables(robots, *(getattr(self, name) for name in _FILL + _PUB), NEVER)

    # ------------------------------------------------------------------ common
    def knowledge(self, copy: bool = True) -> NeighbourKnowledge:
        """What each robot knows now: the published tables of its last complete round (own entries and the
        received rows, with the rows' ages in steps). ``copy=False`` returns views of the live tables (valid
        until the next :meth:`send` / :meth:`step`; saves copying the (N, K, K2) rows when the caller
        consumes them at once)."""
        age = np.where(self.pub_row_time > NEVER, self._now[:, None] - self.pub_row_time, -1)
        c = np.copy if copy else (lambda a: a)
        return NeighbourKnowledge(
            ids=c(self.pub_ids),
            bearings=c(self.pub_bear),
            row_ids=c(self.pub_row_ids),
            row_bearings=c(self.pub_row_bear),
            row_age=age,
        )

    def step(self, readings: Any, deliveries: Any = None, copy: bool = True) -> NeighbourKnowledge:
        """Advance one control step.

        ideal: ``step(readings)`` returns the full, fresh knowledge. network: call :meth:`send` before the
        network step (it starts the due robots' rounds), then ``step(readings, deliveries)`` after it (it
        decodes into the current rounds' tables and returns the knowledge); ``readings``: the receivers'
        bearings to pair the senders with (on the sector source, those measured on this step's frames).
        ``copy``: as in :meth:`knowledge` (network mode; ideal knowledge is always fresh arrays).
        """
        if self.mode == "ideal":
            k = self._ideal(readings)
        else:
            self.receive(deliveries, readings)
            k = self.knowledge(copy)
        self.t += 1
        return k
