"""Plain numpy references of the compiled kernels, for the tests that compare the two.

The simulator runs the numba kernels only; each function here computes what one kernel (or the function
that calls it) computes, in straightforward vectorised numpy (scipy where a graph or a KD-tree is the
plain tool), and its docstring names that kernel. The tests check the kernels against these functions,
most of them bit for bit. Nothing in the package calls this module.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from swarm_envs.sim.geometry import wrap_angle

if TYPE_CHECKING:
    from swarm_envs.sensing.exchange import NeighbourKnowledge
    from swarm_envs.sensing.scale_free import ScaleFreeResult

__all__ = [
    "motor_forces",
    "pack_nearest",
    "directed_links",
    "largest_component_fraction",
    "ir_directed_pairs",
    "occluder_lists",
    "occluder_frames",
    "coordinates_all",
    "sum_last",
    "independent_set",
    "group_argmax",
    "pick_ids",
    "decode_rows",
    "encode_tables",
    "roll_tables",
    "store_deliveries",
]


# -- physics (swarm_envs.sim.world, kernels in swarm_envs.sim.substep_kernel) ---------------------------------------
def motor_forces(control: np.ndarray, motion: np.ndarray, mass: float, moment: float, h: float, force: float, torque: float) -> np.ndarray:
    """:func:`swarm_envs.sim.substep_kernel.motor_forces`: each robot's (fx, fy, torque) rows (n, 3) that change
    its velocity ``motion`` (n, 3: vx, vy, omega) towards ``control`` (n, 3) within one sub-step of ``h`` s, the
    linear change clipped to ``force`` h / ``mass`` in norm and the angular to ``torque`` h / ``moment``."""
    dv = control[:, :2] - motion[:, :2]
    cap = force * h / mass
    norm = np.sqrt((dv * dv).sum(axis=1))
    dv = np.where((norm > cap)[:, None], dv * (cap / np.maximum(norm, 1e-300))[:, None], dv)
    cap_w = torque * h / moment
    dw = np.clip(control[:, 2] - motion[:, 2], -cap_w, cap_w)
    return np.column_stack([dv * mass / h, dw * moment / h])


# -- observations (swarm_envs.sensing.observation) -------------------------------------------------------------------
def pack_nearest(n_rows: int, row: np.ndarray, key: np.ndarray, values: np.ndarray, k: int) -> tuple[np.ndarray, np.ndarray]:
    """Reference of :func:`swarm_envs.sensing.observation.pack_nearest` (kernels ``_pack_nearest_kernel`` and
    ``_nearest_slots_kernel`` of :mod:`swarm_envs.sensing.observation`, whose ``order`` is
    :func:`~swarm_envs.sensing.observation.nearest_slots`): a stable sort of the links by row, then key (NaN last),
    and the first ``k`` of each row. Returns ``(packed (n_rows, k, F), order (n_rows, k))``."""
    values = np.asarray(values, dtype=np.float64)
    if values.ndim == 1:
        values = values[:, None]
    packed = np.zeros((n_rows, k, values.shape[1]))
    order = np.full((n_rows, k), -1, dtype=np.int64)
    if len(row) == 0 or k == 0:
        return packed, order
    idx = np.lexsort((key, row))
    sorted_rows = row[idx]
    starts = np.searchsorted(sorted_rows, sorted_rows, side="left")
    rank = np.arange(len(idx)) - starts
    keep = rank < k
    packed[sorted_rows[keep], rank[keep]] = values[idx[keep]]
    order[sorted_rows[keep], rank[keep]] = idx[keep]
    return packed, order


# -- ideal sensing and metrics (swarm_envs.sensing.ideal, swarm_envs.tasks.metrics) ----------------------------------
def directed_links(pairs: np.ndarray, n_rows: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Reference of :func:`swarm_envs.sensing.ideal.directed_links` (kernel ``_directed_links_kernel``):
    both directions of sorted (P, 2) pairs i < j, sorted by (rx, tx) with one argsort of a unique key, and
    the index of each link's pair. Returns (rx, tx, pair index)."""
    pairs = np.ascontiguousarray(pairs, dtype=np.int64).reshape(-1, 2)
    if len(pairs) == 0:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty, empty
    rx = np.concatenate([pairs[:, 0], pairs[:, 1]])
    tx = np.concatenate([pairs[:, 1], pairs[:, 0]])
    order = np.argsort(rx * int(n_rows) + tx)
    return rx[order], tx[order], np.concatenate([np.arange(len(pairs))] * 2)[order]


def largest_component_fraction(positions: np.ndarray, link_distance: float, pairs: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Reference of :func:`swarm_envs.tasks.metrics.largest_component_fraction` (kernel
    ``_component_stats_kernel``, a union-find): for (B, N, 2) positions, scipy's connected components of
    one graph over all copies (the KD-tree's pairs, :func:`swarm_envs.sensing.ideal.candidate_pairs`, unless
    ``pairs`` are given). Returns (largest-component fraction (B,), number of components (B,))."""
    from swarm_envs.sensing.ideal import candidate_pairs

    B, N = positions.shape[:2]
    copy = np.repeat(np.arange(B), N)
    if pairs is None:
        pairs = candidate_pairs(positions.reshape(B * N, 2), link_distance, copy)
    n = B * N
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    labels = connected_components(graph, directed=False)[1]
    sizes = np.bincount(labels, minlength=n)
    # components never span copies: each label belongs to the copy of its robots
    label_copy = np.full(sizes.size, -1)
    label_copy[labels] = copy
    present = sizes > 0
    largest = np.zeros(B)
    np.maximum.at(largest, label_copy[present], sizes[present])
    count = np.bincount(label_copy[present], minlength=B)
    return largest / N, count


# -- IR layer (swarm_envs.ir.layer, kernels in swarm_envs.ir.*_kernels) -------------------------------------
def ir_directed_pairs(
    pairs: np.ndarray, positions: np.ndarray, headings: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Reference of :func:`swarm_envs.ir.pair_kernels.directed_pairs_kernel` (``swarm_envs.ir.layer._directed_pairs``):
    both directions of the unordered ``pairs`` (U, 2) sorted by (rx, tx) with one argsort, and their frames.
    Returns (rx, tx, row of ``pairs``, tx centre in rx's frame (P, 2) (m), (cos, sin) of tx's heading in
    rx's frame (P, 2) from the robots' own cosines and sines, that heading (P,) (rad, :func:`wrap_angle`),
    centre distance (P,) (m))."""
    c, s = np.cos(headings), np.sin(headings)
    U, N = pairs.shape[0], positions.shape[0]
    rx = np.concatenate([pairs[:, 0], pairs[:, 1]]).astype(np.intp)
    tx = np.concatenate([pairs[:, 1], pairs[:, 0]]).astype(np.intp)
    order = np.argsort(rx.astype(np.int64) * N + tx)  # by (rx, tx); the keys are unique, so any sort agrees
    rx, tx = rx[order], tx[order]
    d = positions[tx] - positions[rx]
    c, s = c[rx], s[rx]
    rel = np.stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]], axis=-1)
    ct, st = np.cos(headings)[tx], np.sin(headings)[tx]
    rel_cs = np.stack([ct * c + st * s, st * c - ct * s], axis=-1)
    return rx, tx, order % U, rel, rel_cs, wrap_angle(headings[tx] - headings[rx]), np.sqrt(d[:, 0] * d[:, 0] + d[:, 1] * d[:, 1])


def occluder_lists(
    positions: np.ndarray, a: np.ndarray, b: np.ndarray, width: float, tree: cKDTree | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """Reference of the occluder search (:func:`swarm_envs.ir.occluder_kernels.occluders_kernel` on the neighbour
    lists of ``swarm_envs.ir.layer._occluder_lists``; the robots :func:`swarm_envs.ir.occlusion.pair_occluders`
    and :func:`swarm_envs.ir.occlusion.line_of_sight` find): the third robots closer than ``width`` (m) to
    segment a[p]-b[p], as CSR (offsets (P + 1,), robots (K,) sorted per pair). The candidates are the
    KD-tree neighbours of both ends within ``sqrt(longest^2 / 4 + width^2)``, tested as flat (pair,
    candidate) arrays."""
    from swarm_envs.ir.occlusion import neighbour_csr

    positions = np.ascontiguousarray(positions, dtype=float).reshape(-1, 2)
    a = np.ascontiguousarray(a, dtype=np.int64).reshape(-1)
    b = np.ascontiguousarray(b, dtype=np.int64).reshape(-1)
    P, N = a.shape[0], positions.shape[0]
    if P == 0 or N < 3:
        return np.zeros(P + 1, dtype=np.int64), np.zeros(0, dtype=np.int64)
    if tree is None:
        tree = cKDTree(positions)
    seg = positions[b] - positions[a]
    length = np.hypot(seg[:, 0], seg[:, 1])
    reach = float(np.sqrt(0.25 * float(length.max()) ** 2 + float(width) ** 2 + 2e-9))
    starts, counts, nbrs = neighbour_csr(positions, reach, tree)
    pairs, cands = [], []
    L2 = np.where(length > 0, length * length, 1.0)
    for end in (a, b):  # two vectorised passes: neighbours of a, then of b
        c = counts[end]
        pair = np.repeat(np.arange(P), c)
        offset = np.arange(int(c.sum())) - np.repeat(np.cumsum(c) - c, c)
        cand = nbrs[np.repeat(starts[end], c) + offset]
        keep = (cand != a[pair]) & (cand != b[pair])
        cand, pair = cand[keep], pair[keep]
        ap = positions[cand] - positions[a[pair]]
        sp = seg[pair]
        t = np.clip((ap[:, 0] * sp[:, 0] + ap[:, 1] * sp[:, 1]) / L2[pair], 0.0, 1.0)
        qx, qy = ap[:, 0] - t * sp[:, 0], ap[:, 1] - t * sp[:, 1]
        near = qx * qx + qy * qy < width * width
        pairs.append(pair[near])
        cands.append(cand[near])
    key = np.unique(np.concatenate(pairs).astype(np.int64) * N + np.concatenate(cands))
    offsets = np.concatenate([[0], np.cumsum(np.bincount(key // N, minlength=P))]).astype(np.int64)
    return offsets, (key % N).astype(np.int64)


def occluder_frames(
    positions: np.ndarray, headings: np.ndarray, rx: np.ndarray, pair_of: np.ndarray, offsets: np.ndarray, idx: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """Reference of :func:`swarm_envs.ir.occluder_kernels.occluder_frames_kernel`: the occluders of pair
    ``pair_of[p]`` (CSR ``offsets``, ``idx``) as centres in receiver ``rx[p]``'s frame. Returns (offsets
    (P + 1,), centres (K, 2))."""
    rx = np.ascontiguousarray(rx, dtype=np.int64)
    pair_of = np.ascontiguousarray(pair_of, dtype=np.int64)
    counts = np.diff(offsets)[pair_of]
    out = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    row = np.repeat(np.arange(rx.shape[0]), counts)
    k = idx[np.repeat(offsets[pair_of], counts) + np.arange(int(out[-1])) - np.repeat(out[:-1], counts)]
    d = positions[k] - positions[rx[row]]
    c, s = np.cos(headings[rx[row]]), np.sin(headings[rx[row]])
    return out, np.stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]], axis=-1).reshape(-1, 2)


# -- scale-free coordinates (swarm_envs.sensing.scale_free, kernels in swarm_envs.sensing.scale_free_kernels) --------------
def coordinates_all(knowledge: NeighbourKnowledge, noise_sensitivity: bool = True, angle_balance: bool = True) -> ScaleFreeResult:
    """Reference of :func:`swarm_envs.sensing.scale_free.coordinates_all` (kernels ``slot_keys``,
    ``two_hop_triangles``, ``two_hop_propagate`` and ``unit_mean_positions`` of
    :mod:`swarm_envs.sensing.range_bearing_kernels`): 2-hop scale-free coordinates for every robot at once [L Algs. 1-4],
    the same float formulas, bit for bit.

    Vectorised numpy over robots, no Python loop over robots: reported ids are matched to slots with one
    sorted search (O(N K K2 log NK)); triangle angles are computed only on usable triangles; connectivity
    is log2(K) batched (K x K) float32 matrix products; the BFS queue order [L Alg. 1] runs as at most K
    lock-step iterations of (N, K, K) operations and Prim's MST [L Alg. 4] as K - 1 iterations of (N, K)
    operations. Arguments and result as in :func:`swarm_envs.sensing.scale_free.coordinates_all`.
    """
    from swarm_envs.sensing.scale_free import ScaleFreeResult, triangle_angles, unit_mean_lengths, triangle_sensitivity

    ids_in = np.asarray(knowledge.ids, dtype=np.int64)
    th_in = np.asarray(knowledge.bearings, dtype=float)
    rid_in = np.asarray(knowledge.row_ids, dtype=np.int64)
    rth_in = np.asarray(knowledge.row_bearings, dtype=float)
    n, k = ids_in.shape
    self_ids = (
        np.arange(n, dtype=np.int64) if knowledge.robot_ids is None else np.asarray(knowledge.robot_ids, np.int64)
    )
    slot_ok_in = (ids_in >= 0) & np.isfinite(th_in)

    # Order slots counter-clockwise by bearing in [0, 2pi) then id; empty slots last [L Fig. 4.3].
    key_b = np.where(slot_ok_in, np.mod(th_in, 2.0 * np.pi), np.inf)
    key_id = np.where(slot_ok_in, ids_in, np.iinfo(np.int64).max)
    order = np.lexsort((key_id, key_b), axis=-1) if n else np.zeros((0, k), np.int64)
    rows = np.arange(n)[:, None]
    ids = ids_in[rows, order]
    th = th_in[rows, order]
    ok = slot_ok_in[rows, order]
    rid = rid_in[rows, order]
    rth = rth_in[rows, order]
    rok = (rid >= 0) & np.isfinite(rth)

    # theta_z(u) for each neighbour slot z, and theta_z(w) for each pair of slots (z, w).
    m_zu = rok & (rid == self_ids[:, None, None])  # (N, K, K2)
    has_zu = m_zu.any(-1) & ok
    tzu = np.where(has_zu, rth[rows, np.arange(k)[None, :], np.argmax(m_zu, -1)], 0.0)
    # Map every reported id to u's slot holding that id with one sorted search over (u, id) keys
    # (O(N K K2 log NK) instead of an (N, K, K, K2) comparison).
    space = int(max(ids.max(initial=0), rid.max(initial=0), self_ids.max(initial=0))) + 1
    own_key = np.where(ok, rows * space + ids, -1).reshape(-1)
    o_sort = np.argsort(own_key, kind="stable")
    sorted_key = own_key[o_sort]
    ru, ri, rm = np.nonzero(rok & ok[:, :, None])  # reported entries of received rows
    q = ru * space + rid[ru, ri, rm]
    if sorted_key.size:
        pos = np.minimum(np.searchsorted(sorted_key, q), sorted_key.size - 1)
        hit = sorted_key[pos] == q
        slot_j = o_sort[pos[hit]] % k
    else:
        hit, slot_j = np.zeros(q.size, bool), np.zeros(0, np.int64)
    has_zw = np.zeros((n, k, k), dtype=bool)
    tzw = np.zeros((n, k, k))
    hu, hi, hm = ru[hit], ri[hit], rm[hit]
    # if a row lists the same id twice, the last entry wins (explicitly: numpy leaves the winner of a
    # repeated fancy-index assignment unspecified; this is what its in-memory-order loop has always given)
    flat = (hu * k + hi) * k + slot_j
    last = flat.size - 1 - np.unique(flat[::-1], return_index=True)[1]
    tzw[hu[last], hi[last], slot_j[last]] = rth[hu[last], hi[last], hm[last]]
    has_zw[hu, hi, slot_j] = True
    eye = np.eye(k, dtype=bool)[None]
    tri = has_zw & np.swapaxes(has_zw, 1, 2) & has_zu[:, :, None] & has_zu[:, None, :] & ~eye
    tri &= ok[:, :, None] & ok[:, None, :]

    # Inner angles, computed only on the usable (u, i, j) triangles (sparse): Pij = angle at neighbour i
    # in triangle (u, i, j), Pji = angle at j, pu = angle at u.
    # Angles are rounded to 1e-ANGLE_DECIMALS rad: quantised (sector) bearings make many triangles exactly
    # equal, and float noise (e.g. 67.5 deg from atan2 vs from a decoded 4-bit sector) must not decide
    # ties in the MST; ties then fall to slot (bearing) order.
    tu, ti, tj = np.nonzero(tri)
    Pij, Pji, good = triangle_angles(
        tzu[tu, ti], tzw[tu, ti, tj], tzu[tu, tj], tzw[tu, tj, ti], th[tu, ti], th[tu, tj], angle_balance
    )  # good is symmetric in (i, j) by construction
    tu, ti, tj, Pij, Pji = tu[good], ti[good], tj[good], Pij[good], Pji[good]
    E = np.zeros((n, k, k), dtype=bool)
    E[tu, ti, tj] = True
    logratio = np.zeros((n, k, k))  # log(f_j / f_i) along i -> j (law of sines)
    logratio[tu, ti, tj] = np.log(np.sin(Pij)) - np.log(np.sin(Pji))

    # Connected components of the neighbour graph by repeated squaring of the reachability matrix
    # (float32 batched matmul: exact for 0/1 entries with K < 2**24).
    R = ((E | eye) & ok[:, :, None] & ok[:, None, :]).astype(np.float32)
    for _ in range(max(1, int(np.ceil(np.log2(max(k, 2)))))):
        R = (np.matmul(R, R) > 0).astype(np.float32)
    R = R > 0
    comp_size = R.sum(-1)  # (N, K) size of the component of each slot (0 for empty)
    big = comp_size.max(-1) if k else np.zeros(n, np.int64)
    # root: first slot (in bearing order) whose component is largest
    root = np.argmax(comp_size == big[:, None], axis=-1)
    deg = ok.sum(-1)
    rigid = (deg >= 1) & (big == deg)

    known = np.zeros((n, k), dtype=bool)
    has_root = deg > 0
    known[np.arange(n), root] = has_root
    logf = np.zeros((n, k))
    if noise_sensitivity:
        W = np.full((n, k, k), np.inf)
        with np.errstate(divide="ignore", invalid="ignore"):
            W[tu, ti, tj] = triangle_sensitivity(Pij, Pji)
        # Prim's algorithm in lock-step over robots, O(K) work per robot and iteration: best[u, j] is the
        # cheapest edge from the tree to j, par[u, j] its tree end (ties: the lower slot).
        ar = np.arange(n)
        r0 = root
        best = np.where(has_root[:, None], W[ar, r0], np.inf)
        par = np.broadcast_to(r0[:, None], (n, k)).copy()
        for _ in range(k - 1):
            cand = np.where(known, np.inf, best)
            j = np.argmin(cand, axis=-1)
            go = np.isfinite(cand[ar, j])
            if not go.any():
                break
            r, jj = ar[go], j[go]
            logf[r, jj] = logf[r, par[r, jj]] + logratio[r, par[r, jj], jj]
            known[r, jj] = True
            w_new = W[r, jj]  # (R, K) edges from the new tree node
            better = (w_new < best[r]) | ((w_new == best[r]) & (jj[:, None] < par[r]) & np.isfinite(w_new))
            best[r] = np.where(better, w_new, best[r])
            par[r] = np.where(better, jj[:, None], par[r])
    else:
        # BFS of [L Alg. 1] in lock-step: discovery rank `disc`; parent = adjacent node dequeued first.
        big_i = np.iinfo(np.int64).max
        disc = np.where(known, 0, big_i)
        cnt = has_root.astype(np.int64)
        for _ in range(k - 1):
            adj = E & known[:, :, None] & ~known[:, None, :]  # parent i known, child j new
            new = adj.any(1)
            if not new.any():
                break
            pd = np.where(adj, disc[:, :, None], big_i)
            parent = np.argmin(pd, axis=1)  # (N, K)
            pdisc = np.take_along_axis(disc, parent, axis=1)
            key = np.where(new, pdisc * k + np.arange(k)[None, :], big_i)
            rank = np.argsort(np.argsort(key, axis=1, kind="stable"), axis=1, kind="stable")
            disc = np.where(new, cnt[:, None] + rank, disc)
            cnt = cnt + new.sum(1)
            lr = logratio[rows, parent, np.arange(k)[None, :]]
            logf = np.where(new, np.take_along_axis(logf, parent, axis=1) + lr, logf)
            known |= new

    f, valid = unit_mean_lengths(logf, known & ok)
    xy = np.stack([f * np.cos(th), f * np.sin(th)], -1)

    # undo the slot permutation
    inv = np.argsort(order, axis=-1) if n else order
    return ScaleFreeResult(
        xy=xy[rows, inv],
        valid=valid[rows, inv],
        rigid=rigid,
        ids=ids_in.copy(),
        length=f[rows, inv],
    )


# -- range & bearing sensor (swarm_envs.sensing.range_bearing, kernels in swarm_envs.sensing.range_bearing_kernels)
def sum_last(a: np.ndarray) -> np.ndarray:
    """Reference of :func:`swarm_envs.sensing.numpy_sums.sum_last` (kernel ``_sum_last``): the sum over the last
    axis by numpy column additions, left to right (``((a0 + a1) + a2) + ...``)."""
    out = a[..., 0].copy()
    for j in range(1, a.shape[-1]):
        out += a[..., j]
    return out


def independent_set(prio: np.ndarray, u: np.ndarray, v: np.ndarray) -> np.ndarray:
    """Reference of :func:`swarm_envs.sensing.range_bearing_kernels.priority_independent_set` and
    :func:`~swarm_envs.sensing.range_bearing_kernels.priority_independent_set_sorted` (the contention schedule of
    :meth:`swarm_envs.sensing.range_bearing.RangeBearingSensor.fire_mask`): (N,) bool greedy maximal
    independent set in decreasing priority (distinct ``prio``) of the graph with edges (u[e], v[e]), by
    vectorised Luby rounds: an undecided node joins when its priority beats every undecided neighbour's;
    the neighbours of the joined nodes drop out."""
    N = prio.size
    a = np.concatenate([u, v])
    b = np.concatenate([v, u])
    fired = np.zeros(N, dtype=bool)
    undecided = np.ones(N, dtype=bool)
    while undecided.any():
        m = undecided[a] & undecided[b]
        nbmax = np.full(N, -1.0)
        np.maximum.at(nbmax, a[m], prio[b[m]])
        new = undecided & (prio > nbmax)
        fired |= new
        undecided &= ~new
        blocked = np.zeros(N, dtype=bool)
        blocked[a[new[b]]] = True
        undecided &= ~blocked
    return fired


def group_argmax(values: np.ndarray, starts: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """Reference of :func:`swarm_envs.sensing.range_bearing_kernels.group_brightest` (with ``values`` the row maxima of its
    gains; also the ``best`` rows of :func:`~swarm_envs.sensing.range_bearing_kernels.firing_sums`): per contiguous group
    (``starts``, sorted, non-empty groups), the label of the row with the largest value (first on ties);
    ``values`` without NaN."""
    n = values.size
    group = np.repeat(np.arange(starts.size), np.diff(np.r_[starts, n]))
    top = np.maximum.reduceat(values, starts)
    best = np.flatnonzero(values == top[group])  # every group holds >= 1 of its maxima
    return labels[best[np.searchsorted(best, starts)]]


def pick_ids(heard: np.ndarray, ident_h: np.ndarray, crc_h: np.ndarray, id_check: bool = True) -> np.ndarray:
    """Reference of :func:`swarm_envs.sensing.range_bearing_kernels.pick_ids`, the decode rule of
    :func:`swarm_envs.sensing.range_bearing_frames.decode_ids`: ``heard`` (G, n_d) bool, ``ident_h``/``crc_h`` (H,)
    the id and CRC words of the heard channels in ``np.nonzero(heard)`` order. Returns (G,) the id all
    checking channels name, :data:`~swarm_envs.sensing.range_bearing_frames.NOT_HEARD` or
    :data:`~swarm_envs.sensing.range_bearing_frames.CONFLICT`."""
    from swarm_envs.sensing.range_bearing_frames import CRC16, CONFLICT, NOT_HEARD
    from swarm_envs.sensing.range_bearing_frames import ID_BITS

    G, n_d = heard.shape
    hg, hi = np.nonzero(heard)
    ident = np.zeros((G, n_d), dtype=np.int64)
    crc = np.zeros((G, n_d), dtype=np.int64)
    ident[hg, hi] = ident_h
    crc[hg, hi] = crc_h
    ok = heard
    if id_check:
        ok = ok & (CRC16[ident] == crc)
    big = np.int64(2**ID_BITS)
    lo = np.where(ok, ident, big).min(axis=1)
    top = np.where(ok, ident, -1).max(axis=1)
    return np.where(lo == big, NOT_HEARD, np.where(lo == top, lo, CONFLICT))


# -- bearing exchange (swarm_envs.sensing.exchange, kernels in swarm_envs.sensing.exchange_kernels) ------------
def _bits_uint(b: np.ndarray) -> np.ndarray:
    """(..., w) bits, MSB first -> (...,) uint."""
    b = np.asarray(b, dtype=np.int64)
    w = b.shape[-1]
    return (b << np.arange(w - 1, -1, -1)).sum(-1)


def decode_rows(bits: np.ndarray, id_bits: int, count_bits: int, max_entries: int, bearing_bits: int = 4) -> tuple[np.ndarray, np.ndarray]:
    """Reference of :func:`swarm_envs.sensing.exchange.decode_rows` (kernel
    :func:`swarm_envs.sensing.exchange_kernels.decode_bits`): bits (R, >= needed, zero padded to that) -> ids (R,
    max_entries) (-1 pad), bearings (rad), by reshaping the entries and weighting their bits."""
    from swarm_envs.sensing.exchange import dequantise

    bits = np.asarray(bits, dtype=np.uint8)
    R = bits.shape[0]
    e = id_bits + bearing_bits
    need = count_bits + max_entries * e
    if bits.shape[1] < need:
        bits = np.concatenate([bits, np.zeros((R, need - bits.shape[1]), np.uint8)], 1)
    count = np.minimum(_bits_uint(bits[:, :count_bits]), max_entries)
    ent = bits[:, count_bits:need].reshape(R, max_entries, e)
    ids = _bits_uint(ent[..., :id_bits])
    th = dequantise(_bits_uint(ent[..., id_bits:]), bearing_bits)
    keep = np.arange(max_entries)[None, :] < count[:, None]
    return np.where(keep, ids, -1), np.where(keep, th, np.nan)


def encode_tables(
    tab_ids: np.ndarray, tab_bear: np.ndarray, tab_time: np.ndarray, robots: np.ndarray, offset: np.ndarray,
    max_entries: int, id_bits: int, count_bits: int, bearing_bits: int,
) -> tuple[np.ndarray, np.ndarray]:
    """Reference of :func:`swarm_envs.sensing.exchange_kernels.encode_tables` (the messages of
    :meth:`swarm_envs.sensing.exchange.BearingExchange.encode`), same arguments: each robot's table slots
    sorted most recently heard first (stable), the first ``max_entries``, ids minus the robot's ``offset``,
    encoded by :func:`swarm_envs.sensing.exchange.encode_rows`. Returns bits (R, n_bits) uint8 and the
    payload lengths (R,)."""
    from swarm_envs.sensing.exchange import encode_rows

    robots = np.asarray(robots, dtype=np.int64)
    o = np.argsort(-tab_time[robots], axis=1, kind="stable")
    ids = np.take_along_axis(tab_ids[robots], o, 1)[:, :max_entries]
    th = np.take_along_axis(tab_bear[robots], o, 1)[:, :max_entries]
    local = np.where(ids >= 0, ids - offset[robots][:, None], -1)  # ids in a copy's own numbering
    bits = encode_rows(local, th, id_bits, count_bits, bearing_bits)
    lens = count_bits + (ids >= 0).sum(1) * (id_bits + bearing_bits)
    return bits, lens


def roll_tables(
    robots: np.ndarray, tab_ids: np.ndarray, tab_bear: np.ndarray, tab_time: np.ndarray, row_ids: np.ndarray,
    row_bear: np.ndarray, row_time: np.ndarray, pub_ids: np.ndarray, pub_bear: np.ndarray, pub_time: np.ndarray,
    pub_row_ids: np.ndarray, pub_row_bear: np.ndarray, pub_row_time: np.ndarray, never: int,
) -> None:
    """Reference of :func:`swarm_envs.sensing.exchange_kernels.roll_tables`
    (:meth:`swarm_envs.sensing.exchange.BearingExchange.start_rounds`), same arguments, in place: the
    ``robots``' filled tables are copied to the published ones by fancy indexing, then emptied (ids -1,
    bearings NaN, times ``never``)."""
    filled = (tab_ids, tab_bear, tab_time, row_ids, row_bear, row_time)
    published = (pub_ids, pub_bear, pub_time, pub_row_ids, pub_row_bear, pub_row_time)
    for fill, pub, value in zip(filled, published, (-1, np.nan, never, -1, np.nan, never)):
        pub[robots] = fill[robots]
        fill[robots] = value


def store_deliveries(
    r: np.ndarray, o: np.ndarray, own_b: np.ndarray, hit: np.ndarray, ids: np.ndarray, th: np.ndarray, now: np.ndarray,
    tab_ids: np.ndarray, tab_bear: np.ndarray, tab_time: np.ndarray, row_ids: np.ndarray, row_bear: np.ndarray,
    row_time: np.ndarray,
) -> None:
    """Reference of :func:`swarm_envs.sensing.exchange_kernels.store_deliveries` (the table update of
    :meth:`swarm_envs.sensing.exchange.BearingExchange.receive`), same arguments, in place: the deliveries
    in waves of at most one per receiver (the kernel's order per receiver); in a wave each delivery's
    sender entry (else the oldest slot; empty slots are the oldest) gets its row and, when the receiver
    has a bearing of the sender (``hit``), that bearing and the time ``now[receiver]``; a delivery without
    a bearing only refreshes an existing entry."""
    todo = np.arange(r.size)
    while todo.size:
        _, first = np.unique(r[todo], return_index=True)
        wave = todo[first]
        _store_wave(r[wave], o[wave], own_b[wave], hit[wave], ids[wave], th[wave], now, tab_ids, tab_bear, tab_time, row_ids, row_bear, row_time)
        todo = np.setdiff1d(todo, wave, assume_unique=True)


def _store_wave(r, o, own_b, hit, ids, th, now, tab_ids, tab_bear, tab_time, row_ids, row_bear, row_time) -> None:
    """One wave of :func:`store_deliveries` (distinct receivers ``r``)."""
    match = tab_ids[r] == o[:, None]
    has = match.any(1)
    # slot: existing entry, else the oldest (empty slots are the oldest)
    slot = np.where(has, np.argmax(match, 1), np.argmin(tab_time[r], 1))
    # a sender we have no bearing for (link gone at delivery) only refreshes an existing entry's row
    ok = has | hit
    r, o, slot, own_b, hit, ids, th = r[ok], o[ok], slot[ok], own_b[ok], hit[ok], ids[ok], th[ok]
    tab_ids[r, slot] = o
    tab_bear[r, slot] = np.where(hit, own_b, tab_bear[r, slot])
    tab_time[r, slot] = np.where(hit, now[r], tab_time[r, slot])
    row_ids[r, slot] = ids
    row_bear[r, slot] = th
    row_time[r, slot] = now[r]
