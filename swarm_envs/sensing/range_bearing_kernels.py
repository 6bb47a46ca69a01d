"""Compiled kernels of the range & bearing sensor [F14]: the contention schedule
(:func:`priority_independent_set`, :func:`priority_independent_set_sorted`; reference: the Luby rounds of
:func:`swarm_envs._compile.reference.independent_set`), the id and CRC words read from colliding request frames
(:func:`frame_words`; reference :func:`swarm_envs.sensing.range_bearing_frames.frame_words_numpy`), the per-step
brightness sums and ADC reads (:func:`firing_sums`, :func:`adc_bits`, :func:`adc_pass`, :func:`group_brightest`),
the decode rule (:func:`pick_ids`) and the reading table (:func:`merge_readings`). Each is compared bit for bit
with its numpy reference in ``tests/sensing/test_sensing_glue_kernels.py`` (or the files named)."""

from __future__ import annotations

import numpy as np

from swarm_envs._compile._numba import njit  # numba.njit whose cache recovers from corrupted files
from swarm_envs._compile._sort import argsort_quick  # np.argsort as numba compiles it, quicker to compile
from swarm_envs.sensing.numpy_sums import PAIRWISE_INIT, pairwise_block


__all__ = ["priority_independent_set", "priority_independent_set_sorted", "frame_words", "firing_sums", "adc_bits", "adc_pass", "pick_ids", "merge_readings"]


@njit(cache=True, nogil=True)
def priority_independent_set(prio, u, v):  # pragma: no cover - compiled
    """Greedy maximal independent set in decreasing ``prio`` of the graph with edges (u[e], v[e]) (either
    direction): a node is in the set iff no neighbour of higher priority is. Equals the Luby rounds of
    the numpy reference for distinct priorities (each round admits the nodes that beat every undecided
    neighbour, which is exactly the greedy order's choice). Returns (N,) bool."""
    n = prio.size
    m = u.size
    deg = np.empty(n + 1, np.int64)
    deg[:] = 0
    for e in range(m):
        deg[u[e] + 1] += 1
        deg[v[e] + 1] += 1
    for i in range(n):
        deg[i + 1] += deg[i]
    fill = deg[:-1].copy()
    adj = np.empty(2 * m, np.int64)
    for e in range(m):
        adj[fill[u[e]]] = v[e]
        fill[u[e]] += 1
        adj[fill[v[e]]] = u[e]
        fill[v[e]] += 1
    order = argsort_quick(-prio)
    fired = np.empty(n, np.bool_)
    fired[:] = False
    blocked = np.empty(n, np.bool_)
    blocked[:] = False
    for k in range(n):
        x = order[k]
        if blocked[x]:
            continue
        fired[x] = True
        for e in range(deg[x], deg[x + 1]):
            blocked[adj[e]] = True
    return fired


#: largest group (colliding links at one receiver) :func:`frame_words` sums; larger groups need numpy's
#: recursive pairwise sum (not called from here: a cached kernel calling a recursive one crashes when
#: numba loads it back from its disk cache)
FRAME_WORDS_MAX_GROUP = 129


def frame_words(light, frames, starts, heard, noise, scale, top, floor, id_bits):
    """Compiled :func:`swarm_envs.sensing.range_bearing_frames.frame_words_numpy` (same arguments, same bits:
    the level of a bit slot is summed over the group's links in numpy's reduceat order) for groups of at
    most :data:`FRAME_WORDS_MAX_GROUP` links."""
    return _frame_words(
        np.ascontiguousarray(light, dtype=np.float64), np.ascontiguousarray(frames, dtype=np.bool_),
        np.ascontiguousarray(starts, dtype=np.int64), np.ascontiguousarray(heard, dtype=np.bool_),
        np.ascontiguousarray(noise, dtype=np.float64), float(scale), float(top), float(floor), int(id_bits),
        PAIRWISE_INIT,
    )


@njit(cache=True, nogil=True)
def _frame_words(light, frames, starts, heard, noise, scale, top, floor, id_bits, init):  # pragma: no cover - compiled
    G, n_d = heard.shape
    L = light.shape[0]
    nb = frames.shape[1] - 1
    H = noise.shape[0]
    ident = np.empty(H, np.int64)
    ident[:] = 0
    crc = np.empty(H, np.int64)
    crc[:] = 0
    buf = np.empty(max(L, 1), np.float64)  # scratch for the pairwise sums of large groups
    fr = np.empty((L, nb), np.float64)  # frame bits as 0.0 / 1.0: the products below without branches
    for l in range(L):
        for k in range(nb):
            fr[l, k] = 1.0 if frames[l, k + 1] else 0.0
    h = 0
    for g in range(G):
        s = starts[g]
        e = starts[g + 1] if g + 1 < G else L
        m = e - s
        for i in range(n_d):
            if not heard[g, i]:
                continue
            word_id = np.int64(0)
            word_crc = np.int64(0)
            for k in range(nb):
                first = light[s, i] * fr[s, k]
                if m <= 1:
                    lev = first
                elif m - 1 < 8:  # reduceat: first + sequential sum of the rest from init
                    res = init
                    for l in range(s + 1, e):
                        res += light[l, i] * fr[l, k]
                    lev = first + res
                else:  # 9 to 129 links (the caller checks): numpy's unrolled pairwise block
                    for l in range(s + 1, e):
                        buf[l - s - 1] = light[l, i] * fr[l, k]
                    lev = first + pairwise_block(buf, m - 1)
                c = np.rint(lev * scale + noise[h, k])
                c = 0.0 if c < 0.0 else c  # numpy's clip (a bound replaces only values beyond it)
                c = top if c > top else c
                bit = np.int64(c / scale >= floor)  # arithmetic, not a branch: the bits are random
                if k < id_bits:
                    word_id |= bit << k
                else:
                    word_crc |= bit << (k - id_bits)
            ident[h] = word_id
            crc[h] = word_crc
            h += 1
    return ident, crc


# -- range & bearing sensor glue (references in swarm_envs.sensing.range_bearing / exchange) ------------------


@njit(cache=True, nogil=True)
def adc_pass(lam, rows, noise, p, scale, top):  # pragma: no cover - compiled
    """One power-ladder pass of :func:`swarm_envs.sensing.range_bearing_model.measure` on matrices ``lam[rows]``
    (flattened to (P, m)): ``clip(round(p * lam * scale + noise), 0, top)`` with numpy's operation order
    and its clip (a rounded -0.0 stays -0.0). ``noise`` (R, m), or (0, m) for
    none. Returns counts (R, m) and saturated (R,) (max count >= top)."""
    R = rows.size
    m = lam.shape[1]
    counts = np.empty((R, m), np.float64)
    sat = np.empty(R, np.bool_)
    sat[:] = False
    has_noise = noise.shape[0] > 0
    for r in range(R):
        src = rows[r]
        big = -np.inf
        for j in range(m):
            c = p * lam[src, j]
            c = c * scale
            if has_noise:
                c = c + noise[r, j]
            c = np.rint(c)
            if c < 0.0:  # numpy's clip: a bound replaces only a value strictly beyond it (-0.0 and NaN stay)
                c = 0.0
            if c > top:
                c = top
            counts[r, j] = c
            if c > big:
                big = c
        sat[r] = big >= top
    return counts, sat


@njit(cache=True, nogil=True)
def group_brightest(gains, starts, labels):  # pragma: no cover - compiled
    """Per contiguous group of rows (``starts``), the label of the row holding the group's largest entry
    (first such row on ties); ``gains`` (L, m) without NaN. Reference:
    :func:`swarm_envs._compile.reference.group_argmax` of the row maxima."""
    G = starts.size
    L, m = gains.shape
    out = np.empty(G, labels.dtype)
    for g in range(G):
        s = starts[g]
        e = starts[g + 1] if g + 1 < G else L
        best = -np.inf
        arg = s
        for l in range(s, e):
            v = gains[l, 0]
            for j in range(1, m):
                if gains[l, j] > v:
                    v = gains[l, j]
            if v > best:
                best = v
                arg = l
        out[g] = labels[arg]
    return out


@njit(cache=True, nogil=True)
def pick_ids(heard, ident_h, crc_h, crc16, id_check, not_heard, conflict):  # pragma: no cover - compiled
    """Decode rule of :func:`swarm_envs.sensing.range_bearing_frames.decode_ids` (reference
    :func:`swarm_envs._compile.reference.pick_ids`): per group, the id every checking channel
    names, ``not_heard`` if none checks, ``conflict`` if they disagree. ``ident_h``/``crc_h`` are the words
    of the heard channels in ``np.nonzero(heard)`` order."""
    G, n_d = heard.shape
    out = np.empty(G, np.int64)
    h = 0
    for g in range(G):
        lo = np.int64(-1)
        hi = np.int64(-1)
        for i in range(n_d):
            if not heard[g, i]:
                continue
            w = ident_h[h]
            good = (not id_check) or crc16[w] == crc_h[h]
            h += 1
            if good:
                if lo < 0 or w < lo:
                    lo = w
                if w > hi:
                    hi = w
        if lo < 0:
            out[g] = not_heard
        elif lo == hi:
            out[g] = lo
        else:
            out[g] = conflict
    return out


@njit(cache=True, nogil=True)
def merge_readings(old_key, old_f, old_i, max_age, new_key, new_f, new_i):  # pragma: no cover - compiled
    """Reading table update of :meth:`swarm_envs.sensing.range_bearing.RangeBearingSensor.step` for sorted
    unique ``old_key`` and non-decreasing ``new_key``: old rows age by one, rows older than ``max_age``
    or refreshed by a new key are dropped, new rows enter with age 0, and the result is sorted by key
    (old before new on equal keys, as a stable sort of the concatenation). ``old_f`` (3, K) float
    columns (range, bearing, heading), ``old_i`` (3, K) int columns (age, true tx, overlap); ``new_f`` /
    ``new_i`` the same for the new rows (their age column is ignored). Returns key, floats, ints."""
    K = old_key.size
    M = new_key.size
    keep = np.empty(K, np.bool_)
    keep[:] = False
    n = M
    b = 0
    for a in range(K):
        while b < M and new_key[b] < old_key[a]:
            b += 1
        if old_i[0, a] + 1 <= max_age and not (b < M and new_key[b] == old_key[a]):
            keep[a] = True
            n += 1
    key = np.empty(n, np.int64)
    fl = np.empty((3, n), np.float64)
    it = np.empty((3, n), np.int64)
    a = 0
    b = 0
    o = 0
    while o < n:
        while a < K and not keep[a]:
            a += 1
        if a < K and (b >= M or old_key[a] <= new_key[b]):
            key[o] = old_key[a]
            for c in range(3):
                fl[c, o] = old_f[c, a]
            it[0, o] = old_i[0, a] + 1
            it[1, o] = old_i[1, a]
            it[2, o] = old_i[2, a]
            a += 1
        else:
            key[o] = new_key[b]
            for c in range(3):
                fl[c, o] = new_f[c, b]
            it[0, o] = 0
            it[1, o] = new_i[1, b]
            it[2, o] = new_i[2, b]
            b += 1
        o += 1
    return key, fl, it


@njit(cache=True, nogil=True)
def firing_sums(gains, starts, n_d, init):  # pragma: no cover - compiled
    """Sums of the firing links' gains per receiving group, in one pass.

    ``gains`` (S, n_d * n_e) the firing links' matrices (``links.gains[sel]``), grouped by ``starts`` (G,)
    (groups of at most :data:`FRAME_WORDS_MAX_GROUP` links). Returns, bit for bit as the numpy path of
    :meth:`swarm_envs.sensing.range_bearing.RangeBearingSensor.step`: ``lam`` (G, n_d * n_e) =
    ``segment_sum(gains, starts)``, ``light`` (S, n_d) = ``sum_last`` per detector, ``start`` (G, n_d) =
    ``segment_sum(light, starts)`` and ``best`` (G,) each group's row with the largest entry (first on
    ties).
    """
    G = starts.size
    S = gains.shape[0]
    m = gains.shape[1]
    n_e = m // n_d
    lam = np.empty((G, m), np.float64)
    light = np.empty((S, n_d), np.float64)
    start = np.empty((G, n_d), np.float64)
    best = np.empty(G, np.int64)
    buf = np.empty(max(S, 1), np.float64)
    for g in range(G):
        s = starts[g]
        e = starts[g + 1] if g + 1 < G else S
        n = e - s
        top = -np.inf
        for l in range(s, e):
            row = l
            v = gains[row, 0]
            for c in range(1, m):
                if gains[row, c] > v:
                    v = gains[row, c]
            if v > top:
                top = v
                best[g] = l
            for i in range(n_d):  # sum_last: left to right
                r = gains[row, i * n_e]
                for j in range(1, n_e):
                    r += gains[row, i * n_e + j]
                light[l, i] = r
        # reduceat order: first row + (short: sequential from init; else numpy's unrolled pairwise block)
        if n == 1:
            for c in range(m):
                lam[g, c] = gains[s, c]
        elif n - 1 < 8:  # row by row (contiguous), each column still summed in link order
            for c in range(m):
                lam[g, c] = init
            for l in range(s + 1, e):
                row = l
                for c in range(m):
                    lam[g, c] += gains[row, c]
            row = s
            for c in range(m):
                lam[g, c] = gains[row, c] + lam[g, c]
        else:
            for c in range(m):
                for l in range(s + 1, e):
                    buf[l - s - 1] = gains[l, c]
                lam[g, c] = gains[s, c] + pairwise_block(buf, n - 1)
        for i in range(n_d):
            first = light[s, i]
            if n == 1:
                start[g, i] = first
            elif n - 1 < 8:
                res = init
                for l in range(s + 1, e):
                    res += light[l, i]
                start[g, i] = first + res
            else:
                for l in range(s + 1, e):
                    buf[l - s - 1] = light[l, i]
                start[g, i] = first + pairwise_block(buf, n - 1)
    return lam, light, start, best


@njit(cache=True, nogil=True)
def adc_bits(level, noise, scale, top, floor):  # pragma: no cover - compiled
    """(R, m) bool ``clip(round(level * scale + noise), 0, top) / scale >= floor`` (the ADC and the
    no-reading floor of :func:`swarm_envs.sensing.range_bearing_frames.decode_ids`' start bits); ``noise``
    (R, m), or (0, m) for none."""
    R, m = level.shape
    out = np.empty((R, m), np.bool_)
    has_noise = noise.shape[0] > 0
    for r in range(R):
        for j in range(m):
            c = level[r, j] * scale
            if has_noise:
                c = c + noise[r, j]
            c = np.rint(c)
            if c < 0.0:
                c = 0.0
            if c > top:
                c = top
            out[r, j] = c / scale >= floor
    return out


@njit(cache=True, nogil=True)
def priority_independent_set_sorted(prio, u, v):  # pragma: no cover - compiled
    """:func:`priority_independent_set` for edges sorted by ``u`` (the IR links, sorted by receiver),
    without building an adjacency list: in decreasing priority a node fires unless a fired node listed
    it (its ``u`` range, marked when that node fired) or it lists a fired node (its own ``u`` range,
    checked now; a listed node that fired has the higher priority). Returns (fired (N,) bool, ok); ok
    is False (and fired meaningless) when ``u`` is not sorted."""
    n = prio.size
    m = u.size
    start = np.empty(n + 1, np.int64)
    start[:] = 0
    for e in range(m):
        if e > 0 and u[e] < u[e - 1]:
            none = np.empty(n, np.bool_)
            none[:] = False
            return none, False
        start[u[e] + 1] += 1
    for i in range(n):
        start[i + 1] += start[i]
    order = argsort_quick(-prio)
    fired = np.empty(n, np.bool_)
    fired[:] = False
    blocked = np.empty(n, np.bool_)
    blocked[:] = False
    for k in range(n):
        x = order[k]
        if blocked[x]:
            continue
        free = True
        for e in range(start[x], start[x + 1]):
            if fired[v[e]]:
                free = False
                break
        if not free:
            continue
        fired[x] = True
        for e in range(start[x], start[x + 1]):
            blocked[v[e]] = True
    return fired, True


