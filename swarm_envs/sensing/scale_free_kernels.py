"""Compiled kernels of the batched 2-hop scale-free algorithm [L Algs. 1-4]: the triangles of each robot's
2-hop neighbourhood, the length propagation, the mean-length normalisation and the bearing slot keys.

:func:`swarm_envs._compile.reference.coordinates_all` is the reference of the 2-hop path: vectorised numpy over
robots, built from many (N, K, K) temporaries. These kernels do the integer and graph work robot by robot with
K-sized local arrays; the transcendental and rounded formulas are computed by numpy in
:func:`swarm_envs.sensing.scale_free.coordinates_all`; the kernels only do correctly rounded IEEE operations in
numpy's order, so the compiled path gives the reference's results bit for bit (``tests/sensing/test_scale_free_kernels.py``)."""

from __future__ import annotations
import numpy as np
from swarm_envs._compile._numba import njit  # numba.njit whose cache recovers from corrupted files
from swarm_envs.sensing.numpy_sums import pairwise_block

__all__ = ["two_hop_triangles", "two_hop_propagate", "unit_mean_positions", "slot_keys"]


_INT64_MAX = int(np.iinfo(np.int64).max)  # a constant in the kernels (np.iinfo compiles its own helpers)


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
            tot = pairwise_block(w, k)
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
