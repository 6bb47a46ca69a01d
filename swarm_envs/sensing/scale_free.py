"""Scale-free neighbour coordinates from bearing-only measurements [L Ch. 4-5].

A robot u measures only bearings ``theta_u(w)`` (angle of ``p_w - p_u`` in u's body frame, radians,
counter-clockwise, docs/design.md#conventions). After the two-step exchange of [L Sec. 5.2.2] it also knows, for each
neighbour v, the bearings ``theta_v(w)`` that v measured. From these it computes *scale-free*
coordinates: its neighbours' positions in its own frame up to one unknown positive scale
``f_u(w) = a_u ||p_u - p_w||`` [L Sec. 4.2]. We fix the scale so that the mean neighbour distance is 1.

Two algorithms:

* **Null-space k-hop method** [L Sec. 5.3, Eq. (5.1)] (:func:`coordinates` with ``method="null_space"``).
  The labelled k-neighbourhood ``G_u^k`` is the subgraph induced by the robots within k hops of u, with
  both bearings of every edge (k + 1 communication steps, [L Sec. 5.2.1]). Each directed cycle C gives
  ``sum_{(w,v) in C} f(w,v) cos(phi_w(v)) = 0`` and the sine twin, where ``phi`` is the edge direction in
  one common frame. [L Eq. (5.1)] is written with raw bearings ``theta_w(v)``; those live in different
  body frames, so we first rotate every frame into u's frame with the reciprocal bearings along a BFS
  spanning tree: ``h_c = h_p + theta_p(c) + pi - theta_c(p)`` (exact for noiseless bearings, where every
  cycle of frame rotations closes). The cycle basis is the fundamental cycle basis of that spanning tree
  (one cycle per non-tree edge, m - n + 1 cycles). ``A`` is ``2(m - n + 1) x m``; its null space comes from
  an SVD, taken on an equivalent reduced system: each cycle's component across the non-tree edge is one
  equation on the n - 1 tree lengths, and its component along it gives the non-tree length, so the SVD is
  of an ``(m - n + 1) x (n - 1)`` matrix (same null space, several times faster). u is *rigid* iff the null space restricted to u's own edges (``N'``) has dimension 1.

  Numerical tolerances: a singular value of A counts as zero when it is below
  ``NULL_RTOL * max(1, s_max)`` (``NULL_RTOL = 1e-9``; entries are sums of unit-vector components along
  tree paths, and noiseless float64 bearings give residuals ~1e-14). ``N'`` has orthonormal-basis rows of size O(1); its
  rank counts singular values above ``RESTRICT_TOL = 1e-6``. The method is meant for exact bearings (the
  rigidity study of [L Fig. 5.1]); with quantised bearings A generically has full column rank and u is
  reported non-rigid.

* **2-hop algorithm** [L Algs. 1-4] (``method="two_hop"``, and the batched :func:`coordinates_all`).
  Only triangles (u, z, w) with z, w in N(u) and z-w an edge. Inner angles
  ``psi_u = |theta_u(z) - theta_u(w)|``, ``psi_z = |theta_z(u) - theta_z(w)|``,
  ``psi_w = |theta_w(z) - theta_w(u)|`` (each wrapped to [0, pi]). ``SINELAW(u, z, w) = f_z sin(psi_z) /
  sin(psi_w)`` (law of sines: ``|uw| / sin(psi_z) = |uz| / sin(psi_w)``). Lengths propagate from a root
  with ``f_root = 1`` over the *neighbour graph* (vertices N(u), an edge z-w for each usable triangle).
  Computable iff that graph is connected [L Sec. 5.5.1].

  - ANGLEBALANCE [L Alg. 2]: each triangle's three inner angles get ``(pi - (psi_u + psi_z + psi_w)) / 3``.
  - Noise sensitivity [L Alg. 3, SINCOS; garbled in the PDF]. Our reading: the triangle's ratio is
    ``g = sin(psi_v) / sin(psi_w)`` (``SinVW``); its gradient w.r.t. (psi_v, psi_w) is
    ``(cos psi_v / sin psi_w, -sin psi_v cos psi_w / sin^2 psi_w)``, whose squared norm is the PDF's
    ``CosSinVW = (cos psi_v / sin psi_w)^2 + (sin psi_v cos psi_w / sin^2 psi_w)^2``. The relative
    sensitivity (gradient norm over value, squared) is ``CosSinVW / SinVW^2 = cot^2 psi_v + cot^2 psi_w``.
    It is symmetric in v and w, so it weights the undirected neighbour-graph edge. A minimum spanning tree
    is invariant under any strictly increasing transform of the weights, so whether Alg. 3 squares the
    ratio or not does not change the tree; we use ``1 + cot^2 psi_v + cot^2 psi_w`` (the 1 keeps weights
    strictly positive). Lengths propagate only along the MST (Prim's algorithm from the root) [L Alg. 4].
  - Degenerate triangles (``min(psi, pi - psi) < DEGENERATE_ANGLE`` at z or w after balancing) are
    skipped: they never produce a length, so no NaN or inf reaches an observation.
  - Root and visiting order: neighbours are ordered counter-clockwise by bearing in [0, 2 pi) from u's
    x-axis (ties by id), following [L Fig. 4.3] ("the first neighbour encountered counter-clockwise from
    the x-axis" gets coefficient 1). Without noise sensitivity the traversal is exactly the BFS queue of
    [L Alg. 1]: the root is the first neighbour in that order, a node's parent is the first dequeued node
    adjacent to it, and white neighbours are enqueued in that order. If the neighbour graph is
    disconnected, u is not rigid; we still return the lengths of the largest component (ties: the one
    holding the earliest neighbour) with the others NaN, since ratios across components are unknown.

Output (both methods): neighbour positions ``xy = f_w (cos theta_u(w), sin theta_u(w))`` with the mean of
the valid ``f_w`` equal to 1, NaN for non-neighbours and uncomputable neighbours, and the rigid flag
(a robot with exactly one neighbour is rigid; a robot with none is not).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, replace

import numpy as np

from swarm_envs._compile._worker import run_chunks
from swarm_envs.sensing.exchange import BearingExchange, NeighbourKnowledge
from swarm_envs.sim.geometry import wrap_angle
from swarm_envs.sensing.scale_free_kernels import slot_keys, two_hop_propagate, two_hop_triangles, unit_mean_positions
from swarm_envs.sensing.numpy_sums import PAIRWISE_INIT

__all__ = [
    "coordinates",
    "coordinates_all",
    "coordinates_all_chunks",
    "ScaleFreeSensor",
    "NeighbourKnowledge",
    "ScaleFreeResult",
    "knowledge_from_matrix",
    "null_space_lengths",
    "triangle_sensitivity",
    "triangle_angles",
    "unit_mean_lengths",
    "angle_balance",
    "DEGENERATE_ANGLE",
    "NULL_RTOL",
    "RESTRICT_TOL",
]

DEGENERATE_ANGLE = 1e-6  # rad: a triangle whose angle at z or w is this close to 0 or pi is skipped
NULL_RTOL = 1e-9  # relative singular-value tolerance for the null space of A
RESTRICT_TOL = 1e-6  # singular-value tolerance for the rank of N' (rows of an orthonormal basis)
ANGLE_DECIMALS = 10  # 2-hop inner angles are rounded to 1e-10 rad (tie-breaking, see coordinates_all)


# --------------------------------------------------------------------------------------------------
# Batched 2-hop algorithm
# --------------------------------------------------------------------------------------------------


@dataclass
class ScaleFreeResult:
    """Batched scale-free coordinates.

    Attributes:
        xy: (N, K, 2) neighbour positions in each robot's frame, mean valid distance 1 (NaN where invalid).
        valid: (N, K) bool, length computed.
        rigid: (N,) bool, every neighbour's length computable [L Sec. 5.5.1].
        ids: (N, K) int, neighbour ids (-1 = empty slot), same slots as the input.
        length: (N, K) scale-free length ``f_w`` (NaN where invalid).
    """

    xy: np.ndarray
    valid: np.ndarray
    rigid: np.ndarray
    ids: np.ndarray
    length: np.ndarray


def angle_balance(psi_u: np.ndarray, psi_z: np.ndarray, psi_w: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """ANGLEBALANCE [L Alg. 2]: add ``(pi - (psi_u + psi_z + psi_w)) / 3`` to each inner angle (rad), so
    the three sum to pi."""
    corr = (np.pi - (psi_u + psi_z + psi_w)) / 3.0
    return psi_u + corr, psi_z + corr, psi_w + corr


def triangle_sensitivity(psi_v: np.ndarray, psi_w: np.ndarray) -> np.ndarray:
    """Relative noise sensitivity of ``sin(psi_v) / sin(psi_w)`` [L Alg. 3, our reading].

    ``|grad g|^2 / g^2 = cot^2 psi_v + cot^2 psi_w`` (angles in rad); returned as ``1 + that`` so that a
    minimum spanning tree (invariant under increasing transforms) never sees a zero weight.
    """
    sv, sw = np.sin(psi_v), np.sin(psi_w)
    with np.errstate(divide="ignore", invalid="ignore"):
        return 1.0 + (np.cos(psi_v) / sv) ** 2 + (np.cos(psi_w) / sw) ** 2


def coordinates_all(
    knowledge: NeighbourKnowledge,
    noise_sensitivity: bool = True,
    angle_balance: bool = True,
) -> ScaleFreeResult:
    """2-hop scale-free coordinates for every robot at once [L Algs. 1-4] (module docstring).

    The slot sort, id matching, components and BFS / Prim run robot by robot in
    :mod:`swarm_envs.sensing.scale_free_kernels`, every floating-point formula (inner angles rounded to
    1e-``ANGLE_DECIMALS`` rad, ANGLEBALANCE, law of sines, sensitivities, normalisation) in numpy here; the
    result equals the vectorised numpy reference :func:`swarm_envs._compile.reference.coordinates_all` bit for bit.

    Args:
        knowledge: see :class:`NeighbourKnowledge`.
        noise_sensitivity: propagate along the minimum spanning tree of triangle sensitivities [L Alg. 4]
            instead of the plain BFS tree [L Alg. 1].
        angle_balance: apply ANGLEBALANCE [L Alg. 2] before the law of sines.

    Returns:
        :class:`ScaleFreeResult`.
    """
    ids_in = np.asarray(knowledge.ids, dtype=np.int64)
    n, k = ids_in.shape
    th_in = np.asarray(knowledge.bearings, dtype=float)
    rid_in = np.asarray(knowledge.row_ids, dtype=np.int64)
    rth_in = np.asarray(knowledge.row_bearings, dtype=float)
    self_ids = (
        np.arange(n, dtype=np.int64) if knowledge.robot_ids is None else np.asarray(knowledge.robot_ids, np.int64)
    )
    # slot validity and sort keys (bearing in [0, 2pi), then id), one pass
    slot_ok_in, key_b, key_id, cap = slot_keys(ids_in, th_in, 2.0 * np.pi, np.iinfo(np.int64).max)
    order, inv, ok, th, starts, tu, ti, tj, vals = two_hop_triangles(
        key_b, key_id, ids_in, th_in, slot_ok_in, rid_in, rth_in, self_ids, int(cap)
    )
    # the float formulas on the triangle list
    Pij, Pji, good = triangle_angles(vals[:, 0], vals[:, 1], vals[:, 2], vals[:, 3], vals[:, 4], vals[:, 5], angle_balance)
    tu, ti, tj, Pij, Pji = tu[good], ti[good], tj[good], Pij[good], Pji[good]
    starts = np.searchsorted(tu, np.arange(n + 1))
    logratio = np.log(np.sin(Pij)) - np.log(np.sin(Pji))
    if noise_sensitivity:
        with np.errstate(divide="ignore", invalid="ignore"):
            weight = triangle_sensitivity(Pij, Pji)
    else:
        weight = np.zeros(0)
    logf, known, rigid = two_hop_propagate(ok, starts, ti, tj, logratio, weight, noise_sensitivity)
    if k <= 128:  # normalisation, slot order and positions in one pass (kernels.unit_mean_positions)
        f, valid, xy = unit_mean_positions(np.exp(logf), known & ok, inv, np.cos(th_in), np.sin(th_in), PAIRWISE_INIT)
        return ScaleFreeResult(xy=xy, valid=valid, rigid=rigid, ids=ids_in.copy(), length=f)
    f, valid = unit_mean_lengths(logf, known & ok)
    # undo the slot permutation before the (element-wise) positions
    f = np.take_along_axis(f, inv, 1)
    xy = np.stack([f * np.cos(th_in), f * np.sin(th_in)], -1)
    return ScaleFreeResult(xy=xy, valid=np.take_along_axis(valid, inv, 1), rigid=rigid, ids=ids_in.copy(), length=f)


def coordinates_all_chunks(knowledge: NeighbourKnowledge, n_chunks: int, noise_sensitivity: bool = True, angle_balance: bool = True) -> ScaleFreeResult:
    """:func:`coordinates_all` with the robots cut into ``n_chunks`` contiguous ranges of rows, each computed by
    one thread (the calling thread and the helpers of :func:`swarm_envs._compile._worker.run_chunks`): a
    robot's coordinates depend on its own row of ``knowledge`` only (its slots and the rows its neighbours
    reported), every formula is element-wise or robot by robot, and the compiled kernels release the GIL,
    so the result is the same bit for bit for any number of chunks (for a large scene on several cores)."""
    n = knowledge.ids.shape[0]
    n_chunks = max(1, min(int(n_chunks), n))
    if n_chunks == 1:
        return coordinates_all(knowledge, noise_sensitivity, angle_balance)
    robot_ids = np.arange(n, dtype=np.int64) if knowledge.robot_ids is None else np.asarray(knowledge.robot_ids, np.int64)
    bounds = [n * c // n_chunks for c in range(n_chunks + 1)]

    def chunk(c: int) -> ScaleFreeResult:
        rows = slice(bounds[c], bounds[c + 1])
        part = replace(
            knowledge, ids=knowledge.ids[rows], bearings=knowledge.bearings[rows], row_ids=knowledge.row_ids[rows],
            row_bearings=knowledge.row_bearings[rows], row_age=None if knowledge.row_age is None else knowledge.row_age[rows],
            robot_ids=robot_ids[rows],
        )
        return coordinates_all(part, noise_sensitivity, angle_balance)

    parts = run_chunks(chunk, n_chunks)
    return ScaleFreeResult(*(np.concatenate([getattr(p, name) for p in parts]) for name in ("xy", "valid", "rigid", "ids", "length")))


def knowledge_from_matrix(bearings: np.ndarray, robots: np.ndarray | None = None) -> NeighbourKnowledge:
    """Build :class:`NeighbourKnowledge` from a full bearing matrix (ideal, lossless exchange).

    ``bearings[a, b] = theta_a(b)`` (rad), NaN where a does not see b. Each robot in ``robots`` (default
    all) gets its own row and the rows of the robots it sees, as after [L Sec. 5.2.2].
    """
    B = np.asarray(bearings, dtype=float)
    n = B.shape[0]
    robots = np.arange(n) if robots is None else np.asarray(robots, dtype=np.int64).reshape(-1)
    seen = ~np.isnan(B)
    np.fill_diagonal(seen, False)
    kmax = max(1, int(seen.sum(1).max())) if n else 1
    # slot layout of every robot's own row: ids sorted ascending
    order = np.argsort(~seen, axis=1, kind="stable")[:, :kmax]
    all_ids = np.where(np.take_along_axis(seen, order, 1), order, -1)
    all_b = np.where(all_ids >= 0, np.take_along_axis(B, np.maximum(order, 0), 1), np.nan)
    ids = all_ids[robots]
    th = all_b[robots]
    safe = np.maximum(ids, 0)
    row_ids = np.where((ids >= 0)[:, :, None], all_ids[safe], -1)
    row_b = np.where((ids >= 0)[:, :, None], all_b[safe], np.nan)
    return NeighbourKnowledge(
        ids=ids,
        bearings=th,
        row_ids=row_ids,
        row_bearings=row_b,
        row_age=np.where(ids >= 0, 0, -1),
        robot_ids=robots,
    )


# --------------------------------------------------------------------------------------------------
# Null-space k-hop method [L Sec. 5.3]
# --------------------------------------------------------------------------------------------------


def _khop(sym: np.ndarray, u: int, k: int) -> np.ndarray:
    """Vertices within k hops of u over the symmetric edge set (u first)."""
    dist = {u: 0}
    q = deque([u])
    out = [u]
    while q:
        a = q.popleft()
        if dist[a] == k:
            continue
        for b in np.nonzero(sym[a])[0]:
            b = int(b)
            if b not in dist:
                dist[b] = dist[a] + 1
                out.append(b)
                q.append(b)
    return np.asarray(out, dtype=np.int64)


def _null_space_basis(B: np.ndarray, verts: np.ndarray, sym: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Edges (m, 2) of the subgraph induced by ``verts`` and a basis (m, d) of the null space of A.

    Frames are rotated into verts[0]'s frame along a BFS spanning tree; fundamental cycle basis of that
    tree; A stacks the cos and sin rows of [L Eq. (5.1)] for each cycle.
    """
    nv = len(verts)
    sub = sym[np.ix_(verts, verts)]
    ea, eb = np.nonzero(np.triu(sub, 1))
    m = len(ea)
    if m == 0:
        return np.zeros((0, 2), np.int64), np.zeros((0, 0))
    eid = -np.ones((nv, nv), dtype=np.int64)
    eid[ea, eb] = np.arange(m)
    eid[eb, ea] = np.arange(m)
    Bs = B[np.ix_(verts, verts)]
    # BFS spanning tree from local vertex 0 with frame offsets h (rad, relative to vertex 0's frame)
    h = np.full(nv, np.nan)
    h[0] = 0.0
    parent = -np.ones(nv, dtype=np.int64)
    tree_edge = np.zeros(m, dtype=bool)
    q = deque([0])
    order = [0]
    while q:
        a = q.popleft()
        for b in np.nonzero(sub[a])[0]:
            if np.isnan(h[b]):
                h[b] = h[a] + Bs[a, b] + np.pi - Bs[b, a]
                parent[b] = a
                tree_edge[eid[a, b]] = True
                q.append(b)
                order.append(int(b))
    # edge directions a->b (a < b) in the common frame: circular mean of the two reciprocal readings
    d1 = h[ea] + Bs[ea, eb]
    d2 = h[eb] + Bs[eb, ea] + np.pi
    D = np.stack([np.cos(d1) + np.cos(d2), np.sin(d1) + np.sin(d2)], -1)
    D /= np.linalg.norm(D, axis=-1, keepdims=True)
    # position of each vertex as a linear function of tree-edge lengths: Px, Py (nv, m)
    Pxy = np.zeros((nv, 2, m))
    for b in order[1:]:
        a = parent[b]
        e = eid[a, b]
        s = 1.0 if a < b else -1.0  # traversal a->b vs stored orientation (min, max)
        Pxy[b] = Pxy[a]
        Pxy[b, :, e] += s * D[e]
    nt = np.nonzero(~tree_edge)[0]
    if len(nt) == 0:
        return np.stack([verts[ea], verts[eb]], -1), np.eye(m)
    # Cycle of non-tree edge e = (a, b): f_e D_e - (p_b - p_a) = 0 (x and y rows of A, [L Eq. (5.1)]).
    # Equivalent reduced system on the n - 1 tree lengths t (same null space, much smaller SVD):
    # the component across D_e gives one row of C, ``D_e_perp . (p_b - p_a)(t) = 0``, and the component
    # along D_e fixes ``f_e = D_e . (p_b - p_a)(t)``. So null(A) = {(t, L t) : C t = 0}.
    tc = np.nonzero(tree_edge)[0]
    delta = (Pxy[eb[nt]] - Pxy[ea[nt]])[:, :, tc]  # (c, 2, n - 1)
    Dn = D[nt]
    C = -Dn[:, 1, None] * delta[:, 0] + Dn[:, 0, None] * delta[:, 1]  # D_perp . delta
    Lnt = Dn[:, 0, None] * delta[:, 0] + Dn[:, 1, None] * delta[:, 1]  # D . delta
    _, s, vt = np.linalg.svd(C, full_matrices=True)
    rank = int(np.sum(s > NULL_RTOL * max(1.0, s[0] if len(s) else 0.0)))
    T = vt[rank:].T  # (n - 1, d)
    N = np.zeros((m, T.shape[1]))
    N[tc] = T
    N[nt] = Lnt @ T
    if N.shape[1]:
        N, _ = np.linalg.qr(N)  # orthonormal basis of null(A)
    return np.stack([verts[ea], verts[eb]], -1), N


def null_space_lengths(
    bearings: np.ndarray, u: int, k: int = 1, cache: dict | None = None
) -> tuple[np.ndarray, np.ndarray, bool]:
    """Null-space k-hop method [L Sec. 5.3, Eq. (5.1)] for robot u.

    Args:
        bearings: (n, n) ``theta_a(b)`` (rad), NaN where there is no edge. Edges need both bearings.
        u: robot index.
        k: communication depth (hops); the labelled k-neighbourhood is induced by the robots within k hops.
        cache: optional dict reused across robots of one graph; the null space only depends on the vertex
            set (a rotation of the common frame does not change it), so robots with the same
            k-neighbourhood share one SVD.

    Returns:
        ``(nbrs, lengths, rigid)``: u's neighbours over symmetric edges, their scale-free lengths (mean 1;
        NaN where not determined), and the rigid flag (``dim N' == 1``). If u is not rigid, the largest
        group of u's edges whose ratios are still determined (parallel rows of ``N'``) gets lengths.
    """
    B = np.asarray(bearings, dtype=float)
    sym = ~np.isnan(B) & ~np.isnan(B.T)
    np.fill_diagonal(sym, False)
    nbrs = np.nonzero(sym[u])[0]
    if len(nbrs) == 0:
        return nbrs, np.zeros(0), False
    verts = _khop(sym, u, k)
    key = tuple(sorted(verts.tolist()))
    if cache is not None and key in cache:
        edges, N = cache[key]
    else:
        verts_c = np.asarray(key, dtype=np.int64)
        edges, N = _null_space_basis(B, verts_c, sym)
        if cache is not None:
            cache[key] = (edges, N)
    # rows of u's edges, in the order of nbrs
    lo, hi = np.minimum(u, nbrs), np.maximum(u, nbrs)
    lut = {(int(a), int(b)): i for i, (a, b) in enumerate(edges)}
    rows = np.array([lut[(int(a), int(b))] for a, b in zip(lo, hi)])
    Np = N[rows]
    if Np.shape[1] == 0:  # no realisation at all (inconsistent bearings)
        return nbrs, np.full(len(nbrs), np.nan), False
    uu, s, _ = np.linalg.svd(Np, full_matrices=False)
    dim = int(np.sum(s > RESTRICT_TOL))
    lengths = np.full(len(nbrs), np.nan)
    if dim == 1:
        v = uu[:, 0] * s[0]
        lengths = np.abs(v)
        rigid = True
    else:
        rigid = False
        norms = np.linalg.norm(Np, axis=1)
        unit = Np / np.maximum(norms, 1e-300)[:, None]
        par = (np.abs(unit @ unit.T) > 1.0 - 1e-9) & (norms[:, None] > RESTRICT_TOL) & (norms[None] > RESTRICT_TOL)
        sizes = par.sum(1)
        best = int(np.argmax(sizes))
        if sizes[best] >= 1 and norms[best] > RESTRICT_TOL:
            g = par[best]
            lengths[g] = np.abs(Np[g] @ unit[best])
    good = np.isfinite(lengths)
    if good.any():
        lengths = lengths / lengths[good].mean()
    return nbrs, lengths, rigid


# --------------------------------------------------------------------------------------------------
# Single-robot entry point (public API)
# --------------------------------------------------------------------------------------------------


def coordinates(
    bearings: np.ndarray,
    u: int,
    method: str = "two_hop",
    k: int = 1,
    noise_sensitivity: bool = True,
    angle_balance: bool = True,
) -> tuple[np.ndarray, bool]:
    """Scale-free coordinates of robot u's neighbours in u's frame [L Ch. 5].

    Args:
        bearings: (n, n) array, ``bearings[a, b] = theta_a(b)`` (rad, b's bearing in a's body frame), NaN
            where there is no edge.
        u: the robot.
        method: ``"two_hop"`` [L Algs. 1-4] or ``"null_space"`` [L Sec. 5.3] (uses ``k``).
        k: communication depth of the null-space method (the 2-hop algorithm is k = 1 by construction).
        noise_sensitivity, angle_balance: 2-hop options [L Algs. 2-4].

    Returns:
        ``(xy, rigid)``: xy (n, 2) neighbour positions scaled so the mean neighbour distance is 1 (NaN for
        non-neighbours and for neighbours whose length is not computable), and the rigid flag.
    """
    B = np.asarray(bearings, dtype=float)
    n = B.shape[0]
    xy = np.full((n, 2), np.nan)
    if method == "two_hop":
        kn = knowledge_from_matrix(B, robots=np.array([u]))
        res = coordinates_all(kn, noise_sensitivity=noise_sensitivity, angle_balance=angle_balance)
        sel = res.ids[0] >= 0
        xy[res.ids[0, sel]] = res.xy[0, sel]
        return xy, bool(res.rigid[0])
    if method == "null_space":
        nbrs, lengths, rigid = null_space_lengths(B, u, k)
        th = B[u, nbrs]
        xy[nbrs] = np.stack([lengths * np.cos(th), lengths * np.sin(th)], -1)
        return xy, rigid
    raise ValueError(f"unknown method {method!r}; allowed: 'two_hop', 'null_space'")


def unit_mean_lengths(logf: np.ndarray, valid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(N, K) neighbour lengths ``exp(logf)`` where ``valid`` (NaN elsewhere), scaled so that each robot's
    valid lengths have mean 1; returns them with ``valid``."""
    f = np.where(valid, np.exp(logf), np.nan)
    nv = valid.sum(-1)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean_f = np.nansum(np.where(valid, f, 0.0), -1) / np.maximum(nv, 1)
    return f / np.where(nv > 0, mean_f, 1.0)[:, None], valid


def triangle_angles(
    i_u: np.ndarray, i_j: np.ndarray, j_u: np.ndarray, j_i: np.ndarray, u_i: np.ndarray, u_j: np.ndarray, balance: bool
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Inner angles of triangles (u, i, j) from the bearings ``theta_i(u), theta_i(j), theta_j(u), theta_j(i),
    theta_u(i), theta_u(j)`` (rad): ``Pij`` at i and ``Pji`` at j, rounded to 1e-ANGLE_DECIMALS rad and
    angle-balanced [L Alg. 2] when ``balance``, and ``good``: the non-degenerate ones (both away from 0 and pi).
    Shared by :func:`coordinates_all` and its numpy reference (:func:`swarm_envs._compile.reference.coordinates_all`)."""
    Pij = np.round(np.abs(wrap_angle(i_u - i_j)), ANGLE_DECIMALS)
    Pji = np.round(np.abs(wrap_angle(j_u - j_i)), ANGLE_DECIMALS)
    pu = np.round(np.abs(wrap_angle(u_i - u_j)), ANGLE_DECIMALS)
    if balance:
        _, Pij, Pji = angle_balance(pu, Pij, Pji)
    good = (
        (np.minimum(Pij, np.pi - Pij) > DEGENERATE_ANGLE)
        & (np.minimum(Pji, np.pi - Pji) > DEGENERATE_ANGLE)
        & (Pij < np.pi)
        & (Pji < np.pi)
    )
    return Pij, Pji, good


class ScaleFreeSensor:
    """Batched entry point for an environment: IR links -> bearings -> exchange -> 2-hop coordinates.

    Per control step: ``sensor.send(network)`` (network mode only, before the network step), then
    ``result = sensor.step(links, deliveries)``. Bearings come from the r-one sector rule
    (:func:`swarm_envs.sensing.bearing_sensor.sense_bearings`) unless ``readings`` is passed to
    :meth:`step` (any object with ``rx, tx, bearing, valid`` per link, e.g. R&B estimates: docs/design.md#bearing-only-sensing
    ``bearing_source``).

    Args:
        n_robots: swarm size.
        platform: platform whose IR channels define the sectors (``"rone"``).
        exchange: ``"ideal"`` or ``"network"`` (:class:`swarm_envs.sensing.exchange.BearingExchange`).
        k_max: neighbour table slots K (use at least the largest expected degree: beyond K the
            lowest-id neighbours are kept and the rest are ignored).
        noise_sensitivity, angle_balance: 2-hop options [L Algs. 2-4].
        **exchange_kwargs: passed to :class:`~swarm_envs.sensing.exchange.BearingExchange` (``network``,
            ``period``, ``bearing_bits``, ``rng``).
    """

    def __init__(
        self,
        n_robots: int,
        platform: str = "rone",
        exchange: str = "ideal",
        k_max: int = 16,
        noise_sensitivity: bool = True,
        angle_balance: bool = True,
        **exchange_kwargs,
    ) -> None:
        from swarm_envs.sim.platforms import get_platform

        self.platform = get_platform(platform)
        self.exchange = BearingExchange(n_robots, exchange, k_max=k_max, **exchange_kwargs)
        self.noise_sensitivity = noise_sensitivity
        self.angle_balance = angle_balance
        self.last_readings = None

    def reset(self, rng: np.random.Generator | None = None) -> None:
        self.exchange.reset(rng)
        self.last_readings = None

    def send(self, network=None) -> int:
        """Queue this step's bearing-list messages (network mode; no-op when ideal)."""
        return self.exchange.send(network)

    def step(self, links, deliveries=None, readings=None) -> ScaleFreeResult:
        """Sense (unless ``readings`` is given), exchange and compute every robot's coordinates."""
        if readings is None:
            from swarm_envs.sensing.bearing_sensor import sense_bearings

            readings = sense_bearings(links, self.platform)
        self.last_readings = readings
        kn = self.exchange.step(readings, deliveries)
        return coordinates_all(kn, noise_sensitivity=self.noise_sensitivity, angle_balance=self.angle_balance)
