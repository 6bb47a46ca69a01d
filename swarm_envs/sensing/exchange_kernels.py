"""Compiled kernels of the bearing exchange [L Sec. 5]: each robot's table of the bearings it measured, rolled
and encoded into its messages, and the tables decoded from the messages it received (references in
:mod:`swarm_envs._compile.reference`, compared bit for bit in ``tests/sensing/test_sensing_glue_kernels.py``)."""

from __future__ import annotations
import numpy as np
from swarm_envs._compile._numba import njit  # numba.njit whose cache recovers from corrupted files

__all__ = ["roll_tables", "encode_tables", "decode_bits", "store_deliveries"]


@njit(cache=True, nogil=True)
def roll_tables(robots, tab_ids, tab_bear, tab_time, row_ids, row_bear, row_time,
                pub_ids, pub_bear, pub_time, pub_row_ids, pub_row_bear, pub_row_time, never):  # pragma: no cover - compiled  # fmt: skip
    """In place :meth:`swarm_envs.sensing.exchange.BearingExchange.start_rounds` (reference:
    :func:`swarm_envs._compile.reference.roll_tables`): for each of ``robots`` the tables filled during its round (``tab_*``, ``row_*``) are
    copied to the published ones (``pub_*``) and emptied (ids -1, bearings NaN, times ``never``)."""
    k = tab_ids.shape[1]
    w = row_ids.shape[2]
    for u in robots:
        for s in range(k):
            pub_ids[u, s] = tab_ids[u, s]
            pub_bear[u, s] = tab_bear[u, s]
            pub_time[u, s] = tab_time[u, s]
            pub_row_time[u, s] = row_time[u, s]
            for j in range(w):
                pub_row_ids[u, s, j] = row_ids[u, s, j]
                pub_row_bear[u, s, j] = row_bear[u, s, j]
                row_ids[u, s, j] = -1
                row_bear[u, s, j] = np.nan
            tab_ids[u, s] = -1
            tab_bear[u, s] = np.nan
            tab_time[u, s] = never
            row_time[u, s] = never


@njit(cache=True, nogil=True)
def encode_tables(tab_ids, tab_bear, tab_time, robots, offset, max_entries, id_bits, count_bits, bearing_bits):  # pragma: no cover - compiled
    """Bit rows of the bearing-exchange messages of ``robots`` (:meth:`swarm_envs.sensing.exchange.BearingExchange.encode`;
    reference: :func:`swarm_envs._compile.reference.encode_tables` with :func:`~swarm_envs.sensing.exchange.encode_rows`):
    each robot's table slots, most recently heard first (stable in slot order), the first
    ``max_entries`` of them, present ones (id >= 0) compacted to the front; count then, per entry, the id
    minus the robot's ``offset`` and the bearing sector ``rint(theta / (2 pi / 2**bearing_bits)) mod
    2**bearing_bits`` (NaN: sector 0), MSB first, zero padded. Returns bits (R, count_bits + max_entries
    * (id_bits + bearing_bits)) uint8 and the payload lengths (R,)."""
    R = robots.size
    k = tab_ids.shape[1]
    e = id_bits + bearing_bits
    nq = np.int64(1) << bearing_bits
    width = 2.0 * np.pi / nq
    bits = np.empty((R, count_bits + max_entries * e), np.uint8)
    bits[:] = 0
    lens = np.empty(R, np.int64)
    order = np.empty(k, np.int64)
    for r in range(R):
        u = robots[r]
        for s in range(k):  # stable insertion sort by descending time
            order[s] = s
        for a in range(1, k):
            x = order[a]
            b = a - 1
            while b >= 0 and tab_time[u, x] > tab_time[u, order[b]]:
                order[b + 1] = order[b]
                b -= 1
            order[b + 1] = x
        c = 0
        for s in range(min(k, max_entries)):
            slot = order[s]
            v = tab_ids[u, slot]
            if v < 0:
                continue
            th = tab_bear[u, slot]
            if np.isnan(th):
                th = 0.0
            q = np.int64(np.rint(th / width)) % nq
            o = count_bits + c * e
            lid = v - offset[u]
            for j in range(id_bits):
                bits[r, o + j] = (lid >> (id_bits - 1 - j)) & 1
            for j in range(bearing_bits):
                bits[r, o + id_bits + j] = (q >> (bearing_bits - 1 - j)) & 1
            c += 1
        for j in range(count_bits):
            bits[r, j] = (c >> (count_bits - 1 - j)) & 1
        lens[r] = count_bits + c * e
    return bits, lens


@njit(cache=True, nogil=True)
def decode_bits(bits, id_bits, count_bits, max_entries, bearing_bits):  # pragma: no cover - compiled
    """Integer part of :func:`swarm_envs.sensing.exchange.decode_rows`: count (capped at ``max_entries``),
    ids and bearing sectors of each row's first ``count`` entries (-1 beyond; bits beyond a row's
    width read as 0; reference: :func:`swarm_envs._compile.reference.decode_rows`). Returns ids, sectors (R,
    max_entries) int64."""
    R, W = bits.shape
    e = id_bits + bearing_bits
    ids = np.empty((R, max_entries), np.int64)
    ids[:] = -1
    qs = np.empty((R, max_entries), np.int64)
    qs[:] = -1
    for r in range(R):
        c = np.int64(0)
        for j in range(count_bits):
            c = (c << 1) | (np.int64(bits[r, j]) if j < W else 0)
        c = min(c, max_entries)
        for m in range(c):
            o = count_bits + m * e
            v = np.int64(0)
            for j in range(id_bits):
                v = (v << 1) | (np.int64(bits[r, o + j]) if o + j < W else 0)
            q = np.int64(0)
            for j in range(bearing_bits):
                q = (q << 1) | (np.int64(bits[r, o + id_bits + j]) if o + id_bits + j < W else 0)
            ids[r, m] = v
            qs[r, m] = q
    return ids, qs


@njit(cache=True, nogil=True)
def store_deliveries(r, o, own_b, hit, ids, th, now, tab_ids, tab_bear, tab_time, row_ids, row_bear, row_time):  # pragma: no cover - compiled
    """In place table update of :meth:`swarm_envs.sensing.exchange.BearingExchange.receive`, one delivery
    after the other (reference: :func:`swarm_envs._compile.reference.store_deliveries`, numpy waves of one delivery
    per receiver, which is the same order per receiver): the entry of sender ``o[d]`` in receiver ``r[d]``'s table (else
    the oldest slot; empty slots are the oldest) gets its row ``ids[d]``, ``th[d]`` and, when the
    receiver has a bearing of the sender (``hit[d]``), that bearing and a fresh time; a delivery
    without a bearing only refreshes an existing entry."""
    k = tab_ids.shape[1]
    w = row_ids.shape[2]
    for d in range(r.size):
        u = r[d]
        slot = -1
        for s in range(k):
            if tab_ids[u, s] == o[d]:
                slot = s
                break
        if slot < 0:
            if not hit[d]:
                continue
            slot = 0
            for s in range(1, k):
                if tab_time[u, s] < tab_time[u, slot]:
                    slot = s
        tab_ids[u, slot] = o[d]
        if hit[d]:
            tab_bear[u, slot] = own_b[d]
            tab_time[u, slot] = now[u]
        for j in range(w):
            row_ids[u, slot, j] = ids[d, j]
            row_bear[u, slot, j] = th[d, j]
        row_time[u, slot] = now[u]
