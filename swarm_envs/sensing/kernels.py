"""Compiled (numba) kernels for the batched 2-hop scale-free algorithm [L Algs. 1-4], and the sensing glue.

:func:`swarm_envs._compile.reference.coordinates_all` is the reference of the 2-hop path: vectorised numpy over robots,
but built from many (N, K, K) temporaries (slot sort, id matching, reachability by matrix squaring,
lock-step BFS / Prim). These kernels do the integer and graph work robot by robot with K-sized local
arrays; the transcendental and rounded formulas (inner angles, rounding, ANGLEBALANCE, law-of-sines logs,
sensitivities, exp, sin/cos) are still computed by numpy in
:func:`swarm_envs.sensing.scale_free.coordinates_all`; the kernels only do correctly rounded IEEE
operations (+, -, *, /, fmod, comparisons) in numpy's order (the length propagation, the mean-length
normalisation of :func:`unit_mean_positions` with numpy's pairwise row sum, the bearing keys of
:func:`slot_keys`), so the compiled path gives the reference's results bit for bit
(``tests/test_scale_free_kernels.py``).

Also the range & bearing sensor's and the bearing exchange's compiled glue, each with its numpy reference
compared bit for bit in ``tests/test_sensing_glue_kernels.py`` (or the files named): :func:`segment_sum`
(``np.add.reduceat`` over rows), :func:`priority_independent_set` and
:func:`priority_independent_set_sorted` (the contention schedule; reference: the Luby rounds of
:func:`swarm_envs._compile.reference.independent_set`), :func:`frame_words` (id and CRC words read
from colliding request frames; reference :func:`swarm_envs.sensing.range_bearing.frame_words_numpy`),
:func:`firing_sums`, :func:`adc_bits`, :func:`adc_pass`, :func:`pick_ids`, :func:`merge_readings`
(the sensor's per-step sums, ADC reads, decode rule and reading table), :func:`encode_tables`,
:func:`decode_bits`, :func:`roll_tables`, :func:`store_deliveries` (the exchange's messages and
tables). The references that only the tests use are in :mod:`swarm_envs._compile.reference`.
"""

from __future__ import annotations

import numpy as np

from swarm_envs._compile._numba import njit  # numba.njit whose cache recovers from corrupted files
from swarm_envs._compile._sort import argsort_quick  # np.argsort as numba compiles it, quicker to compile

_INT64_MAX = int(np.iinfo(np.int64).max)  # a constant in the kernels (np.iinfo compiles its own helpers)

__all__ = [
    "two_hop_triangles", "two_hop_propagate", "segment_sum", "sum_last", "priority_independent_set",
    "priority_independent_set_sorted", "frame_words", "firing_sums", "adc_bits", "adc_pass", "pick_ids",
    "merge_readings", "encode_tables", "decode_bits", "roll_tables", "store_deliveries", "slot_keys",
    "unit_mean_positions", "PAIRWISE_INIT",
]


@njit(cache=True, nogil=True)
def two_hop_triangles(key_b, key_id, ids_in, th_in, ok_in, rid_in, rth_in, self_ids, cap):  # pragma: no cover - compiled
    """Slot order and usable triangles of every robot (the reference's first half).

    Slots are ordered by (key_b, key_id), stable (``np.lexsort``). For sorted slots i, j of robot u the
    triangle (u, i, j) is usable when both are valid, i reported u, and each reported the other
    (a row listing an id twice: last entry wins; a row id held by two slots: the lower slot).

    Returns ``order`` (N, K), ``inv`` (N, K) (its inverse permutation), sorted ``ok`` (N, K) and ``th``
    (N, K), the per-robot triangle start offsets (N + 1,), and for each triangle in (u, i, j)
    lexicographic order (at most ``cap``: pass ``sum(deg * (deg - 1))`` over robots, deg = valid slots):
    u, i, j and the raw bearings ``theta_i(u), theta_i(j), theta_j(u),
    theta_j(i), theta_u(i), theta_u(j)`` (rad).
    """
    n, k = ids_in.shape
    k2 = rid_in.shape[2]
    order = np.empty((n, k), np.int64)
    inv = np.empty((n, k), np.int64)
    ok = np.empty((n, k), np.bool_)
    ok[:] = False
    th = np.empty((n, k), np.float64)
    tu = np.empty(cap, np.int64)
    ti = np.empty(cap, np.int64)
    tj = np.empty(cap, np.int64)
    vals = np.empty((cap, 6), np.float64)
    starts = np.empty(n + 1, np.int64)
    starts[:] = 0
    ids = np.empty(k, np.int64)
    has_zu = np.empty(k, np.bool_)
    has_zu[:] = False
    tzu = np.empty(k, np.float64)
    tzu[:] = 0.0
    has_zw = np.empty((k, k), np.bool_)
    has_zw[:] = False
    tzw = np.empty((k, k), np.float64)
    tzw[:] = 0.0
    t = 0
    for u in range(n):
        # stable insertion sort of the slots by (key_b, key_id)
        for s in range(k):
            order[u, s] = s
        for a in range(1, k):
            x = order[u, a]
            b = a - 1
            while b >= 0:
                y = order[u, b]
                if key_b[u, x] < key_b[u, y] or (key_b[u, x] == key_b[u, y] and key_id[u, x] < key_id[u, y]):
                    order[u, b + 1] = y
                    b -= 1
                else:
                    break
            order[u, b + 1] = x
        for s in range(k):
            o = order[u, s]
            inv[u, o] = s
            ok[u, s] = ok_in[u, o]
            th[u, s] = th_in[u, o]
            ids[s] = ids_in[u, o]
        # theta_z(u) and theta_z(w) on sorted slots
        for s in range(k):
            has_zu[s] = False
            tzu[s] = 0.0
            for j in range(k):
                has_zw[s, j] = False
                tzw[s, j] = 0.0
            if not ok[u, s]:
                continue
            o = order[u, s]
            for m in range(k2):
                r = rid_in[u, o, m]
                rt = rth_in[u, o, m]
                if r < 0 or not np.isfinite(rt):
                    continue
                if r == self_ids[u] and not has_zu[s]:
                    has_zu[s] = True
                    tzu[s] = rt
                for j in range(k):
                    if ok[u, j] and ids[j] == r:
                        has_zw[s, j] = True
                        tzw[s, j] = rt  # a row listing an id twice: the last entry wins
                        break
        for i in range(k):
            if not (ok[u, i] and has_zu[i]):
                continue
            for j in range(k):
                if i != j and ok[u, j] and has_zu[j] and has_zw[i, j] and has_zw[j, i]:
                    tu[t] = u
                    ti[t] = i
                    tj[t] = j
                    vals[t, 0] = tzu[i]
                    vals[t, 1] = tzw[i, j]
                    vals[t, 2] = tzu[j]
                    vals[t, 3] = tzw[j, i]
                    vals[t, 4] = th[u, i]
                    vals[t, 5] = th[u, j]
                    t += 1
        starts[u + 1] = t
    return order, inv, ok, th, starts, tu[:t], ti[:t], tj[:t], vals[:t]


@njit(cache=True, nogil=True)
def two_hop_propagate(ok, starts, ti, tj, logratio, weight, noise_sensitivity):  # pragma: no cover - compiled
    """Components, root, rigidity and length propagation of every robot (the reference's second half).

    ``starts``/``ti``/``tj`` list each robot's usable (non-degenerate) directed neighbour-graph edges,
    ``logratio`` their ``log(f_j / f_i)`` and ``weight`` their sensitivity [L Alg. 3]. Root: first slot
    (bearing order) of the largest component. Propagation: Prim's MST from the root [L Alg. 4] when
    ``noise_sensitivity``, else the BFS queue of [L Alg. 1], with the reference's tie rules.

    Returns ``logf`` (N, K) (0 at the root), ``known`` (N, K) bool and ``rigid`` (N,) bool.
    """
    n, k = ok.shape
    logf = np.empty((n, k), np.float64)
    logf[:] = 0.0
    known = np.empty((n, k), np.bool_)
    known[:] = False
    rigid = np.empty(n, np.bool_)
    rigid[:] = False
    E = np.empty((k, k), np.bool_)
    E[:] = False
    LR = np.empty((k, k), np.float64)
    LR[:] = 0.0
    W = np.empty((k, k), np.float64)
    comp = np.empty(k, np.int64)
    size = np.empty(k, np.int64)
    size[:] = 0
    stack = np.empty(k, np.int64)
    best = np.empty(k, np.float64)
    par = np.empty(k, np.int64)
    disc = np.empty(k, np.int64)
    new = np.empty(k, np.bool_)
    new[:] = False
    parent = np.empty(k, np.int64)
    parent[:] = 0
    BIG = _INT64_MAX
    for u in range(n):
        for a in range(k):
            for b in range(k):
                E[a, b] = False
                LR[a, b] = 0.0
                W[a, b] = np.inf
        for e in range(starts[u], starts[u + 1]):
            E[ti[e], tj[e]] = True
            LR[ti[e], tj[e]] = logratio[e]
            W[ti[e], tj[e]] = weight[e]
        # connected components of the neighbour graph over valid slots
        for a in range(k):
            comp[a] = -1
            size[a] = 0
        for a in range(k):
            if not ok[u, a] or comp[a] >= 0:
                continue
            comp[a] = a
            top = 0
            stack[0] = a
            cnt = 1
            while top >= 0:
                x = stack[top]
                top -= 1
                for b in range(k):
                    if E[x, b] and ok[u, b] and comp[b] < 0:
                        comp[b] = a
                        cnt += 1
                        top += 1
                        stack[top] = b
            size[a] = cnt
        big = 0
        deg = 0
        for a in range(k):
            if ok[u, a]:
                deg += 1
                if size[comp[a]] > big:
                    big = size[comp[a]]
        root = 0
        for a in range(k):
            sa = size[comp[a]] if ok[u, a] else 0
            if sa == big:
                root = a
                break
        rigid[u] = deg >= 1 and big == deg
        has_root = deg > 0
        known[u, root] = has_root
        if noise_sensitivity:
            for a in range(k):
                best[a] = W[root, a] if has_root else np.inf
                par[a] = root
            for _ in range(k - 1):
                jj = 0
                cmin = np.inf if known[u, 0] else best[0]
                if not np.isnan(cmin):
                    for a in range(1, k):
                        c = np.inf if known[u, a] else best[a]
                        if np.isnan(c):  # np.argmin: the first NaN wins
                            jj = a
                            cmin = c
                            break
                        if c < cmin:
                            jj = a
                            cmin = c
                if not np.isfinite(cmin):
                    break
                p = par[jj]
                logf[u, jj] = logf[u, p] + LR[p, jj]
                known[u, jj] = True
                for a in range(k):
                    w = W[jj, a]
                    if w < best[a] or (w == best[a] and jj < par[a] and np.isfinite(w)):
                        best[a] = w
                        par[a] = jj
        else:
            cnt = 1 if has_root else 0
            for a in range(k):
                disc[a] = 0 if known[u, a] else BIG
            for _ in range(k - 1):
                nnew = 0
                for b in range(k):
                    new[b] = False
                    parent[b] = 0
                    if known[u, b]:
                        continue
                    dmin = BIG
                    for a in range(k):
                        if E[a, b] and known[u, a] and disc[a] < dmin:
                            dmin = disc[a]
                            parent[b] = a
                            new[b] = True
                    if new[b]:
                        nnew += 1
                if nnew == 0:
                    break
                # discovery rank: new nodes ordered by (parent's discovery rank, slot)
                for b in range(k):
                    if not new[b]:
                        continue
                    kb = disc[parent[b]] * k + b
                    rank = 0
                    for c in range(k):
                        if new[c] and disc[parent[c]] * k + c < kb:
                            rank += 1
                    stack[b] = cnt + rank
                for b in range(k):
                    if new[b]:
                        logf[u, b] = logf[u, parent[b]] + LR[parent[b], b]
                for b in range(k):
                    if new[b]:
                        disc[b] = stack[b]
                        known[u, b] = True
                cnt += nnew
    return logf, known, rigid


def segment_sum(a: np.ndarray, starts: np.ndarray) -> np.ndarray:
    """``np.add.reduceat(a, starts, axis=0)`` bit for bit, compiled for float64 rows and valid ``starts``
    (reduceat loops over segments slowly when most segments hold one or two rows); otherwise reduceat itself.

    numpy reduces each segment ``s:e`` column by column as ``a[s] + pairwise_sum(a[s+1:e])``, with its
    pairwise summation (sequential from -0.0 (numpy >= 2) below 8 terms, 8 interleaved partial sums up to 128, halving
    above); the kernel repeats exactly that order, so float results are identical, not just close.
    """
    a = np.asarray(a)
    starts = np.asarray(starts, dtype=np.int64)
    if a.dtype != np.float64 or starts.size == 0 or starts.min() < 0 or starts.max() >= a.shape[0]:
        return np.add.reduceat(a, starts, axis=0)
    flat = np.ascontiguousarray(a).reshape(a.shape[0], -1)
    return _segment_sum(flat, starts, PAIRWISE_INIT).reshape((starts.size, *a.shape[1:]))


#: the start value of numpy's short pairwise sums: -0.0 under numpy >= 2 (the additive identity: a sum of
#: -0.0 stays -0.0), 0.0 before; asked of the installed numpy. Kernels that repeat numpy's summation take it
#: as an argument, not a global (numba's cache would freeze it).
PAIRWISE_INIT = -0.0 if np.signbit(np.add.reduceat(np.full((3, 1), -0.0), [0], axis=0)[0, 0]) else 0.0


@njit(cache=True, nogil=True)
def _pairwise_sum(a, lo, n, c, init):  # pragma: no cover - compiled
    """numpy's ``DOUBLE_pairwise_sum`` of ``a[lo:lo+n, c]`` (numpy/_core/src/umath/loops_utils.h.src)."""
    if n < 8:
        res = init
        for i in range(n):
            res += a[lo + i, c]
        return res
    if n <= 128:
        r0, r1, r2, r3 = a[lo, c], a[lo + 1, c], a[lo + 2, c], a[lo + 3, c]
        r4, r5, r6, r7 = a[lo + 4, c], a[lo + 5, c], a[lo + 6, c], a[lo + 7, c]
        m = n - n % 8
        i = 8
        while i < m:
            r0 += a[lo + i, c]
            r1 += a[lo + i + 1, c]
            r2 += a[lo + i + 2, c]
            r3 += a[lo + i + 3, c]
            r4 += a[lo + i + 4, c]
            r5 += a[lo + i + 5, c]
            r6 += a[lo + i + 6, c]
            r7 += a[lo + i + 7, c]
            i += 8
        res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
        while i < n:
            res += a[lo + i, c]
            i += 1
        return res
    n2 = n // 2
    n2 -= n2 % 8
    return _pairwise_sum(a, lo, n2, c, init) + _pairwise_sum(a, lo + n2, n - n2, c, init)


@njit(cache=True, nogil=True)
def _segment_sum(a, starts, init):  # pragma: no cover - compiled
    G = starts.size
    L, m = a.shape
    out = np.empty((G, m), np.float64)
    for g in range(G):
        s = starts[g]
        e = starts[g + 1] if g + 1 < G else L
        if e <= s + 1:  # one row (reduceat also returns a[s] when the next start is not larger)
            for c in range(m):
                out[g, c] = a[s, c]
        elif e - s - 1 < 8:  # short segment: _pairwise_sum's sequential branch, inline (it is recursive,
            for c in range(m):  # so numba calls it as a function: slow for the typical 2-3 rows)
                res = init
                for i in range(s + 1, e):
                    res += a[i, c]
                out[g, c] = a[s, c] + res
        else:
            for c in range(m):
                out[g, c] = a[s, c] + _pairwise_sum(a, s + 1, e - s - 1, c, init)
    return out


def sum_last(a: np.ndarray) -> np.ndarray:
    """Sum over the last axis, added left to right (``((a0 + a1) + a2) + ...``), compiled (reference:
    :func:`swarm_envs._compile.reference.sum_last`, numpy column additions in the same order, the same bits).
    (``a.sum(-1)`` reduces a short last axis slowly: ~4x slower for the (L, 8, 8) gain matrices.)"""
    a = np.asarray(a, dtype=float)
    if a.shape[-1] == 0:
        return np.zeros(a.shape[:-1])
    flat = np.ascontiguousarray(a.reshape(-1, a.shape[-1]))  # one compiled layout (a single row can come as a column view)
    return _sum_last(flat).reshape(a.shape[:-1])


@njit(cache=True, nogil=True)
def _sum_last(a):  # pragma: no cover - compiled
    m, k = a.shape
    out = np.empty(m, np.float64)
    for i in range(m):
        r = a[i, 0]
        for j in range(1, k):
            r += a[i, j]
        out[i] = r
    return out


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
    """Compiled :func:`swarm_envs.sensing.range_bearing.frame_words_numpy` (same arguments, same bits:
    the level of a bit slot is summed over the group's links in numpy's reduceat order) for groups of at
    most :data:`FRAME_WORDS_MAX_GROUP` links."""
    return _frame_words(
        np.ascontiguousarray(light, dtype=np.float64), np.ascontiguousarray(frames, dtype=np.bool_),
        np.ascontiguousarray(starts, dtype=np.int64), np.ascontiguousarray(heard, dtype=np.bool_),
        np.ascontiguousarray(noise, dtype=np.float64), float(scale), float(top), float(floor), int(id_bits),
        PAIRWISE_INIT,
    )


@njit(cache=True, nogil=True)
def _pairwise_block(a, n):  # pragma: no cover - compiled
    """numpy's pairwise sum of ``a[:n]`` for 8 <= n <= 128 (the unrolled, non-recursive branch)."""
    r0, r1, r2, r3 = a[0], a[1], a[2], a[3]
    r4, r5, r6, r7 = a[4], a[5], a[6], a[7]
    m = n - n % 8
    i = 8
    while i < m:
        r0 += a[i]
        r1 += a[i + 1]
        r2 += a[i + 2]
        r3 += a[i + 3]
        r4 += a[i + 4]
        r5 += a[i + 5]
        r6 += a[i + 6]
        r7 += a[i + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += a[i]
        i += 1
    return res


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
                    lev = first + _pairwise_block(buf, m - 1)
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
    """One power-ladder pass of :func:`swarm_envs.sensing.range_bearing.measure` on matrices ``lam[rows]``
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
    """Decode rule of :func:`swarm_envs.sensing.range_bearing.decode_ids` (reference
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
                lam[g, c] = gains[s, c] + _pairwise_block(buf, n - 1)
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
                start[g, i] = first + _pairwise_block(buf, n - 1)
    return lam, light, start, best


@njit(cache=True, nogil=True)
def adc_bits(level, noise, scale, top, floor):  # pragma: no cover - compiled
    """(R, m) bool ``clip(round(level * scale + noise), 0, top) / scale >= floor`` (the ADC and the
    no-reading floor of :func:`swarm_envs.sensing.range_bearing.decode_ids`' start bits); ``noise``
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
def unit_mean_positions(e, valid, inv, cos_t, sin_t, init):  # pragma: no cover - compiled
    """End of :func:`swarm_envs.sensing.scale_free.coordinates_all` after the (numpy) ``exp``: lengths
    ``e`` (N, K) where ``valid`` (sorted slots), NaN elsewhere, divided by each robot's mean valid length
    (summed as numpy's ``nansum`` over the row: its pairwise sum of all K entries), put back in
    the input slot order ``f[u, s] = f_sorted[u, inv[u, s]]``, and positions ``f cos(theta), f sin(theta)``
    from the given ``cos_t``/``sin_t`` (N, K). Rows of at most 128 slots. Returns f, valid (input slot
    order) and xy (N, K, 2)."""
    n, k = e.shape
    f = np.empty((n, k), np.float64)
    vout = np.empty((n, k), np.bool_)
    xy = np.empty((n, k, 2), np.float64)
    w = np.empty(k, np.float64)
    fs = np.empty(k, np.float64)
    for u in range(n):
        nv = 0
        for j in range(k):
            if valid[u, j]:
                nv += 1
                w[j] = 0.0 if np.isnan(e[u, j]) else e[u, j]
            else:
                w[j] = 0.0
        if k < 8:  # np.sum over a row: numpy's pairwise sum of all k entries (sequential from init below 8)
            tot = init
            for j in range(k):
                tot += w[j]
        else:
            tot = _pairwise_block(w, k)
        denom = tot / max(nv, 1) if nv > 0 else 1.0
        for j in range(k):
            fs[j] = (e[u, j] if valid[u, j] else np.nan) / denom
        for s in range(k):
            src = inv[u, s]
            f[u, s] = fs[src]
            vout[u, s] = valid[u, src]
            xy[u, s, 0] = fs[src] * cos_t[u, s]
            xy[u, s, 1] = fs[src] * sin_t[u, s]
    return f, vout, xy


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


@njit(cache=True, nogil=True)
def slot_keys(ids, th, two_pi, id_max):  # pragma: no cover - compiled
    """Slot validity and sort keys of :func:`swarm_envs.sensing.scale_free.coordinates_all` in one pass:
    ``ok = (ids >= 0) & isfinite(th)``, ``key_b = mod(th, two_pi)`` where ok else inf (numpy's float mod:
    ``fmod`` (exact), plus ``two_pi`` when the signs differ, +0.0 for a zero remainder), ``key_id = ids``
    where ok else ``id_max``, and ``sum(deg * (deg - 1))`` over robots (deg = ok slots)."""
    n, k = ids.shape
    ok = np.empty((n, k), np.bool_)
    key_b = np.empty((n, k), np.float64)
    key_id = np.empty((n, k), np.int64)
    cap = 0
    for u in range(n):
        deg = 0
        for s in range(k):
            t = th[u, s]
            good = ids[u, s] >= 0 and np.isfinite(t)
            ok[u, s] = good
            if good:
                r = np.fmod(t, two_pi)
                if r != 0.0:
                    if (two_pi < 0.0) != (r < 0.0):
                        r += two_pi
                else:
                    r = np.copysign(0.0, two_pi)
                key_b[u, s] = r
                key_id[u, s] = ids[u, s]
                deg += 1
            else:
                key_b[u, s] = np.inf
                key_id[u, s] = id_max
        cap += deg * (deg - 1)
    return ok, key_b, key_id, cap


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
