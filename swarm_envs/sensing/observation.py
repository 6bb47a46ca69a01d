"""Observation layout (``docs/observations.md``) and the vectorised packing of per-link readings into fixed slots.

Every robot observes a ``Dict``:

- ``range_bearing`` (K, 7): ``[valid, range (m), cos bearing, sin bearing, cos heading, sin heading, age (steps)]``
  for the K neighbours nearest by *estimated* range; on a platform without a range sensor (``rone``) the K
  most recently decoded (:func:`ranked_slots`);
- ``messages`` (M, 2 + b): ``[valid, sender bearing / pi, payload bit 0 .. b-1]`` for messages decoded since
  the last step (``sensing="ideal"``: nearest senders first; ``sensing="full"``: in the order the channel
  delivered them, the first M kept, when more than M arrived);
- ``scale_free`` (K, 3): ``[valid, x, y]`` neighbour positions in the robot's frame, scaled so the mean
  neighbour distance is 1 (clipped to +-``SCALE_FREE_CLIP``), nearest first by these coordinates (on ``rone``,
  equal distances in a random order, :func:`ranked_slots`);
- ``rigid`` (1,): 1 when the robot's scale-free coordinates are determined (rigid neighbourhood);
- ``proprio`` (8 + 2 + b): ``[bump sector 0..7, last action]``.

With ``observe_ids=True`` four more parts give the robot its own id and, per row, the id its sensing
*decoded* (:data:`ID_FIELDS`): ``own_id`` (2,) ``[own id / (n_world - 1), own id parity]``, and
``range_bearing_ids`` (K, 4), ``message_ids`` (M, 4), ``scale_free_ids`` (K, 4), one row per row of
``range_bearing``, ``messages`` and ``scale_free``: ``[an id was decoded, id / (n_world - 1), id < own
id, same parity as own id]`` (all zero where the row is empty). The ids are a copy's own robot numbers
(agents and static robots, 0 .. n_world - 1) as the stack decoded them: the R&B request frame [F14], the
SwarmCom header origin [T20] or the r-one message that carried the bearing [L]; a corrupted or colliding
frame gives the wrong id here exactly as the receiver decoded it. ``sensing="ideal"`` gives the true ids.

``flatten=True`` concatenates them (``gymnasium.spaces.flatten``, keys in sorted order) into one ``Box``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from gymnasium import spaces

from swarm_envs._compile._numba import njit
from swarm_envs.sim.geometry import wrap_angle
from swarm_envs.sensing.base import SensorFrame
from swarm_envs.sim.world import N_BUMP_SECTORS

__all__ = [
    "ObservationLayout",
    "nearest_slots",
    "ranked_slots",
    "pack_nearest",
    "id_rows",
    "own_id_rows",
    "RB_FIELDS",
    "ID_FIELDS",
    "ID_PARTS",
    "SCALE_FREE_CLIP",
    "wrapped_difference",
    "assemble_observation",
]

RB_FIELDS = ("valid", "range", "cos_bearing", "sin_bearing", "cos_heading", "sin_heading", "age")
#: columns of the id parts (``observe_ids=True``), one row per observation row
ID_FIELDS = ("decoded", "id", "lower_than_own", "same_parity")
#: the parts ``observe_ids=True`` adds: id part -> the part whose rows it names (``own_id``: the robot)
ID_PARTS = {"own_id": None, "range_bearing_ids": "range_bearing", "message_ids": "messages", "scale_free_ids": "scale_free"}
SCALE_FREE_CLIP = 10.0


def _id_scale(n_world: int) -> float:
    return float(max(int(n_world) - 1, 1))


def own_id_rows(own: np.ndarray, n_world: int) -> np.ndarray:
    """(n, 2) float32 ``own_id`` rows ``[own id / (n_world - 1), own id parity]`` of ids ``own`` (n,)."""
    own = np.asarray(own, dtype=np.int64)
    return np.stack([own / _id_scale(n_world), own % 2], axis=-1).astype(np.float32)


def id_rows(ids: np.ndarray, own: np.ndarray, n_world: int) -> np.ndarray:
    """(n, r, 4) float32 id rows (:data:`ID_FIELDS`) of decoded ids ``ids`` (n, r) (a copy's own robot
    numbers, -1 where a row has none) seen by robots with ids ``own`` (n,): ``[decoded, id / (n_world -
    1), id < own, same parity]``, all zero where no id was decoded."""
    ids = np.asarray(ids, dtype=np.int64)
    own = np.asarray(own, dtype=np.int64)[:, None]
    decoded = ids >= 0
    out = np.zeros(ids.shape + (4,), np.float32)
    out[..., 0] = decoded
    out[..., 1] = np.where(decoded, ids / _id_scale(n_world), 0.0)
    out[..., 2] = decoded & (ids < own)
    out[..., 3] = decoded & (ids % 2 == own % 2)
    return out


def wrapped_difference(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``wrap_angle(a - b)`` (rad, in (-pi, pi]) elementwise; compiled for two 1-D arrays of one shape
    (other shapes: :func:`swarm_envs.sim.geometry.wrap_angle`).

    The kernel does the same IEEE operations as :func:`swarm_envs.sim.geometry.wrap_angle` (``np.mod`` is
    ``fmod``, exact, plus one addition of 2 pi for negative remainders), so the results are the same bits,
    several times faster than ``np.mod``.
    """
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    if a.ndim == 1 and a.shape == b.shape:
        return _wrapped_difference_kernel(a, b)
    return wrap_angle(a - b)


def range_bearing_rows(
    order: np.ndarray,
    distance: np.ndarray,
    bearing: np.ndarray,
    heading: np.ndarray,
    age: np.ndarray,
    bearing_cos_sin: np.ndarray | None = None,
) -> np.ndarray:
    """(n, k, 7) float32 ``range_bearing`` rows (:data:`RB_FIELDS`, not clipped) of the links in ``order``
    (n, k) (from :func:`nearest_slots`; -1: an all-zero row), from per-link range (m), bearing and
    heading (rad) and age (steps); ``bearing_cos_sin`` (n, k, 2): cos and sin of the slots' bearings if
    already known. cos and sin are taken by numpy on the kept links only; a compiled pass writes the rows
    (the same float32 values as stacking in float64 and casting)."""
    if len(distance) == 0:
        return np.zeros(order.shape + (7,), np.float32)
    kept = np.where(order >= 0, order, 0)  # empty slots read link 0 and are zeroed
    if bearing_cos_sin is None:
        b = bearing[kept]
        bearing_cos_sin = np.stack([np.cos(b), np.sin(b)], axis=-1)
    h = heading[kept]
    heading_cos_sin = np.stack([np.cos(h), np.sin(h)], axis=-1)
    return _range_bearing_kernel(
        np.ascontiguousarray(order, dtype=np.int64),
        np.ascontiguousarray(distance, dtype=np.float64),
        np.ascontiguousarray(bearing_cos_sin, dtype=np.float64),
        heading_cos_sin,
        np.ascontiguousarray(age, dtype=np.float64),
    )


def nearest_slots(n_rows: int, row: np.ndarray, key: np.ndarray, k: int) -> np.ndarray:
    """(n_rows, k) link index of the ``k`` smallest ``key`` per row (-1 where a row has fewer links), the
    ``order`` of :func:`pack_nearest` without packing any values."""
    if len(row) == 0 or k == 0:
        return np.full((n_rows, k), -1, dtype=np.int64)
    row = _checked_rows(n_rows, row)
    return _nearest_slots_kernel(int(n_rows), row, np.ascontiguousarray(key, dtype=np.float64).reshape(-1), int(k))


def ranked_slots(n_rows: int, row: np.ndarray, key: np.ndarray, tie: np.ndarray, k: int) -> np.ndarray:
    """(n_rows, k) link index of each row's ``k`` first links ranked by ascending ``key`` (NaN last), equal
    keys by ascending ``tie``, equal ties by link index (-1 where a row has fewer links).

    The observation-row ranking of the platforms without a range sensor (``rone``, ``sensing="full"``), whose
    readings would otherwise all tie: ``range_bearing`` rows with ``key`` = the reading's age (steps since the
    frame that carried it was decoded, so the most recently heard neighbours come first and are the ones
    kept when more than ``k`` are heard), ``scale_free`` rows with ``key`` = the distance of the scale-free
    coordinates; ``tie`` = one uniform [0, 1) draw per link and step from the env copy's own ranking stream.
    Neither key nor tie depends on the decoded id, so a row's position tells nothing about it.
    """
    if len(row) == 0 or k == 0:
        return np.full((n_rows, k), -1, dtype=np.int64)
    perm = np.argsort(np.asarray(tie, dtype=np.float64).reshape(-1), kind="stable")
    slots = nearest_slots(n_rows, np.asarray(row)[perm], np.asarray(key, dtype=np.float64).reshape(-1)[perm], k)
    return np.where(slots >= 0, perm[np.maximum(slots, 0)], -1)


def _checked_rows(n_rows: int, row: np.ndarray) -> np.ndarray:
    """``row`` as a contiguous int64 vector; raises ValueError for a row outside [0, n_rows)."""
    row = np.ascontiguousarray(row, dtype=np.int64).reshape(-1)
    if row.min() < 0 or row.max() >= n_rows:
        raise ValueError(f"pack_nearest: rows must lie in [0, {n_rows}), got [{row.min()}, {row.max()}]")
    return row


def pack_nearest(
    n_rows: int, row: np.ndarray, key: np.ndarray, values: np.ndarray, k: int
) -> tuple[np.ndarray, np.ndarray]:
    """Scatter per-link ``values`` (P, F) into ``(n_rows, k, F)`` slots, the ``k`` smallest ``key`` per row.

    Returns ``(packed, order)``: ``packed`` zero-filled where a row has fewer than k entries, and
    ``order`` (n_rows, k) with the link index in each slot (-1 where empty). Slots are in increasing
    ``key`` order (NaN last), equal keys in link order. A compiled one-pass selection; its plain numpy
    reference is :func:`swarm_envs._compile.reference.pack_nearest`.
    """
    values = np.asarray(values, dtype=np.float64)
    if values.ndim == 1:
        values = values[:, None]
    if len(row) == 0 or k == 0:
        return np.zeros((n_rows, k, values.shape[1])), np.full((n_rows, k), -1, dtype=np.int64)
    row = _checked_rows(n_rows, row)
    return _pack_nearest_kernel(
        int(n_rows), row, np.ascontiguousarray(key, dtype=np.float64).reshape(-1), np.ascontiguousarray(values), int(k)
    )


@njit(cache=True, inline="always")
def _before(key_a: float, idx_a: int, key_b: float, idx_b: int) -> bool:
    """Whether link a comes before link b: smaller key first, NaN keys last, then link order."""
    nan_a, nan_b = key_a != key_a, key_b != key_b
    if nan_a != nan_b:
        return nan_b
    if not nan_a and key_a != key_b:
        return key_a < key_b
    return idx_a < idx_b


@njit(cache=True)
def _pack_nearest_kernel(n_rows: int, row: np.ndarray, key: np.ndarray, values: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """:func:`pack_nearest`: the slots of :func:`_nearest_slots_kernel`, then the values copied in."""
    F = values.shape[1]
    order = _nearest_slots_kernel(n_rows, row, key, k)
    packed = np.empty((n_rows, k, F), np.float64)
    packed[:] = 0.0
    for r in range(n_rows):
        for c in range(k):
            if order[r, c] < 0:
                break
            for f in range(F):
                packed[r, c, f] = values[order[r, c], f]
    return packed, order


@njit(cache=True)
def _nearest_slots_kernel(n_rows: int, row: np.ndarray, key: np.ndarray, k: int) -> np.ndarray:
    """:func:`nearest_slots` in one pass over the links: each row keeps its k first links in
    :func:`_before` order by insertion (links arrive in index order, so ties keep link order)."""
    P = len(row)
    order = np.empty((n_rows, k), np.int64)
    order[:] = -1
    best = np.empty((n_rows, k), np.float64)
    count = np.empty(n_rows, np.int64)
    count[:] = 0
    for p in range(P):
        r, kp = row[p], key[p]
        c = count[r]
        if c == k:
            if not _before(kp, p, best[r, k - 1], order[r, k - 1]):
                continue
            c = k - 1
        else:
            count[r] = c + 1
        while c > 0 and _before(kp, p, best[r, c - 1], order[r, c - 1]):
            best[r, c] = best[r, c - 1]
            order[r, c] = order[r, c - 1]
            c -= 1
        best[r, c] = kp
        order[r, c] = p
    return order


@njit(cache=True)
def _range_bearing_kernel(order: np.ndarray, distance: np.ndarray, bcs: np.ndarray, hcs: np.ndarray, age: np.ndarray) -> np.ndarray:
    """Rows [1, range, cos, sin bearing, cos, sin heading, age] of the kept links as float32; zero rows
    for empty slots."""
    n, k = order.shape
    out = np.empty((n, k, 7), np.float32)
    out[:] = 0.0
    for r in range(n):
        for c in range(k):
            o = order[r, c]
            if o < 0:
                continue
            out[r, c, 0] = 1.0
            out[r, c, 1] = np.float32(distance[o])
            out[r, c, 2] = np.float32(bcs[r, c, 0])
            out[r, c, 3] = np.float32(bcs[r, c, 1])
            out[r, c, 4] = np.float32(hcs[r, c, 0])
            out[r, c, 5] = np.float32(hcs[r, c, 1])
            out[r, c, 6] = np.float32(age[o])
    return out


@njit(cache=True, inline="always")
def wrap_difference_scalar(a: float, b: float) -> float:
    """``pi - np.mod(pi - (a - b), 2 pi)`` with numpy's remainder rule: ``fmod`` (exact), plus 2 pi
    when it is negative, +0 when it is zero (NaN stays NaN). For compiled callers."""
    two_pi = 2.0 * np.pi
    y = np.pi - (a - b)
    # fmod without the library call where its result is known exactly: y itself in [0, 2 pi),
    # y - 2 pi in [2 pi, 4 pi) (exact by Sterbenz's lemma)
    if 0.0 <= y < two_pi:
        m = y
    elif two_pi <= y < 2.0 * two_pi:
        m = y - two_pi
    else:
        m = np.fmod(y, two_pi)
    if m != 0.0:
        if m < 0.0:
            m += two_pi
    else:
        m = 0.0
    return np.pi - m


@njit(cache=True)
def _wrapped_difference_kernel(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """:func:`wrap_difference_scalar` elementwise."""
    out = np.empty(len(a), np.float64)
    for i in range(len(a)):
        out[i] = wrap_difference_scalar(a[i], b[i])
    return out


@njit(cache=True)
def _clip_float32_kernel(values: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """``np.clip(values.astype(float32), low, high)`` for (n, S) float64 or float32 values and (S,) float32
    bounds (NaN stays NaN, as with ``np.clip``)."""
    n, S = values.shape
    out = np.empty((n, S), np.float32)
    for i in range(n):
        for s in range(S):
            v = np.float32(values[i, s])
            if v == v:  # numpy's clip: max then min, each keeping a NaN and taking the bound on ties
                if not v > low[s]:
                    v = low[s]
                if not v < high[s]:
                    v = high[s]
            out[i, s] = v
    return out


@dataclass
class ObservationLayout:
    """Sizes and bounds of one robot's observation; builds the gymnasium spaces."""

    n_neighbours: int = 8
    n_messages: int = 8
    message_bits: int = 0
    max_range: float = 1.0
    max_age: int = 10
    flatten: bool = False
    observe_ids: bool = False
    #: robots per copy (agents and static robots): ids are scaled by ``n_world - 1``
    n_world: int = 1
    _dict_space: spaces.Dict | None = field(default=None, init=False, repr=False)

    @property
    def action_size(self) -> int:
        return 2 + self.message_bits

    @property
    def proprio_size(self) -> int:
        return N_BUMP_SECTORS + self.action_size

    def dict_space(self) -> spaces.Dict:
        if self._dict_space is None:
            k, m, b = self.n_neighbours, self.n_messages, self.message_bits
            rb_low = np.tile(np.array([0, 0, -1, -1, -1, -1, 0], np.float32), (k, 1))
            rb_high = np.tile(np.array([1, self.max_range, 1, 1, 1, 1, self.max_age], np.float32), (k, 1))
            msg_low = np.tile(np.array([0, -1] + [0] * b, np.float32), (m, 1))
            msg_high = np.ones((m, 2 + b), np.float32)
            sf_low = np.tile(np.array([0, -SCALE_FREE_CLIP, -SCALE_FREE_CLIP], np.float32), (k, 1))
            sf_high = np.tile(np.array([1, SCALE_FREE_CLIP, SCALE_FREE_CLIP], np.float32), (k, 1))
            pro_low = np.concatenate([np.zeros(N_BUMP_SECTORS), -np.ones(self.action_size)]).astype(np.float32)
            pro_high = np.ones(self.proprio_size, np.float32)
            parts = {
                "range_bearing": spaces.Box(rb_low, rb_high, dtype=np.float32),
                "messages": spaces.Box(msg_low, msg_high, dtype=np.float32),
                "scale_free": spaces.Box(sf_low, sf_high, dtype=np.float32),
                "rigid": spaces.Box(0.0, 1.0, (1,), dtype=np.float32),
                "proprio": spaces.Box(pro_low, pro_high, dtype=np.float32),
            }
            if self.observe_ids:
                parts["own_id"] = spaces.Box(0.0, 1.0, (2,), dtype=np.float32)
                for name, rows_of in ID_PARTS.items():
                    if rows_of is not None:
                        parts[name] = spaces.Box(0.0, 1.0, (parts[rows_of].shape[0], len(ID_FIELDS)), dtype=np.float32)
            self._dict_space = spaces.Dict(parts)  # gymnasium sorts the keys
        return self._dict_space

    def space(self) -> spaces.Space:
        """The per-agent observation space (Dict, or its flattened Box)."""
        return spaces.flatten_space(self.dict_space()) if self.flatten else self.dict_space()

    def action_space(self) -> spaces.Box:
        return spaces.Box(-1.0, 1.0, (self.action_size,), dtype=np.float32)

    def build(
        self,
        range_bearing: np.ndarray,
        messages: np.ndarray,
        scale_free: np.ndarray,
        rigid: np.ndarray,
        proprio: np.ndarray,
        ids: dict[str, np.ndarray] | None = None,
    ) -> dict[str, np.ndarray]:
        """Clip batched parts (leading robot axis; float64, or float32 cast from float64) into the space
        bounds, as float32 arrays; ``ids``: the id parts (:data:`ID_PARTS`) when ``observe_ids``."""
        parts = {
            "range_bearing": range_bearing,
            "messages": messages,
            "scale_free": scale_free,
            "rigid": rigid.reshape(-1, 1),
            "proprio": proprio,
            **(ids or {}),
        }
        out = {}
        for name, box in self.dict_space().spaces.items():
            out[name] = _clip_to_box(parts[name], box.low, box.high)
        return out

    def per_robot(self, batched: dict[str, np.ndarray], i: int) -> np.ndarray | dict[str, np.ndarray]:
        """One robot's observation from the batched dict (flattened if ``flatten``)."""
        obs = {name: batched[name][i] for name in batched}
        if self.flatten:
            return spaces.flatten(self.dict_space(), obs).astype(np.float32)
        return obs

    def unflatten(self, flat: np.ndarray) -> dict[str, np.ndarray]:
        """Inverse of the flattening: a (..., D) array back to named parts (leading axes kept)."""
        flat = np.asarray(flat)
        lead = flat.shape[:-1]
        out, start = {}, 0
        for name, box in self.dict_space().spaces.items():
            size = int(np.prod(box.shape))
            out[name] = flat[..., start : start + size].reshape(*lead, *box.shape)
            start += size
        return out


def _clip_to_box(values: np.ndarray, low: np.ndarray, high: np.ndarray) -> np.ndarray:
    """``np.clip(values as float32, low, high)`` for float64 or float32 values (n, *box shape) and float32
    bounds of the box shape, in one compiled pass (same float32 results; other dtypes or shapes: ``np.clip``)."""
    values = np.asarray(values)
    if values.dtype in (np.float64, np.float32) and values.ndim >= 1 and values.shape[1:] == low.shape and low.dtype == np.float32:
        n = values.shape[0]
        flat = _clip_float32_kernel(
            np.ascontiguousarray(values).reshape(n, -1), np.ascontiguousarray(low).reshape(-1), np.ascontiguousarray(high).reshape(-1)
        )
        return flat.reshape(values.shape)
    return np.clip(np.asarray(values, np.float32), low, high)


def assemble_observation(
    frame: SensorFrame, layout: ObservationLayout, bumps: np.ndarray, last_actions: np.ndarray, n_world: int, with_ids: bool
) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """Every robot's observation from one sensing frame: (the layout's parts, the id parts (empty unless
    ``with_ids``)), leading axis = robot of all copies (``n_world`` robots per copy).

    The K nearest readings per robot become ``range_bearing`` rows (a stack that already chose its slots and
    built the rows, as the full stack does, hands them over in ``NeighbourReadings.slots`` / ``rows``);
    messages are kept in the frame's order (``MessageReadings.distance_hint`` when the stack gives one);
    ``proprio`` is the bump flags ``bumps`` (n, 8) and ``last_actions`` (n, action_size). Parts are built in
    float32 and clipped to the layout's box by :meth:`ObservationLayout.build`.
    """
    nb = frame.neighbours
    n, k, m, b = len(bumps), layout.n_neighbours, layout.n_messages, layout.message_bits
    slots, cos_sin = nb.slots, nb.slot_cos_sin
    if slots is not None and slots.shape == (n, k) and nb.rows is not None and nb.rows.shape[:2] == (n, k):
        range_bearing = nb.rows
    else:
        if slots is None or slots.shape != (n, k):
            slots, cos_sin = nearest_slots(n, nb.rx, nb.range, k), None
        range_bearing = range_bearing_rows(slots, nb.range, nb.bearing, nb.heading, nb.age, cos_sin)
    msg = frame.messages
    if len(msg.receiver):
        key = msg.distance_hint if msg.distance_hint is not None else np.arange(len(msg.receiver), dtype=float)
        msg_values = np.concatenate(
            [np.ones((len(msg.receiver), 1)), msg.bearing[:, None] / np.pi, msg.payload.reshape(len(msg.receiver), b)], axis=1
        )
        messages, message_slots = pack_nearest(n, msg.receiver, key, msg_values, m)
    else:
        messages, message_slots = np.zeros((n, m, 2 + b), np.float32), np.full((n, m), -1)
    sf = frame.scale_free
    scale_free = np.empty(sf.xy.shape[:-1] + (3,), np.float32)
    scale_free[..., 0] = sf.valid
    scale_free[..., 1:] = np.where(sf.valid[..., None], sf.xy, 0.0)
    proprio = np.empty((n, N_BUMP_SECTORS + last_actions.shape[1]), np.float32)
    proprio[:, :N_BUMP_SECTORS] = bumps
    proprio[:, N_BUMP_SECTORS:] = last_actions
    ids = _decoded_id_parts(slots, nb.tx, message_slots, msg.sender, sf.ids, n_world, k) if with_ids else {}
    parts = layout.build(range_bearing, messages, scale_free, sf.rigid.astype(np.float32), proprio, ids)
    return parts, ids


def _decoded_id_parts(
    slots: np.ndarray, tx: np.ndarray, message_slots: np.ndarray, sender: np.ndarray, scale_free_ids: np.ndarray | None, n_world: int, k: int
) -> dict[str, np.ndarray]:
    """The id parts (``observe_ids``) of every robot: its own id and, per observation row, the id the
    sensing stack decoded (``NeighbourReadings.tx`` of the row's reading, ``MessageReadings.sender`` of the
    row's message, ``ScaleFreeReadings.ids``), as a copy's own robot numbers."""
    n = len(slots)
    own = np.arange(n) % n_world

    def decoded(index: np.ndarray, rows: np.ndarray) -> np.ndarray:  # robot rows of the slots -> ids, -1 empty
        return np.where(index >= 0, rows[np.maximum(index, 0)] % n_world if len(rows) else -1, -1)

    sf_ids = np.full((n, k), -1) if scale_free_ids is None else np.where(scale_free_ids >= 0, scale_free_ids % n_world, -1)
    return {
        "own_id": own_id_rows(own, n_world),
        "range_bearing_ids": id_rows(decoded(slots, tx), own, n_world),
        "message_ids": id_rows(decoded(message_slots, sender), own, n_world),
        "scale_free_ids": id_rows(sf_ids, own, n_world),
    }
