"""Spawning: robots placed at random, non-overlapping, inside an arena and away from obstacles, and the
lattice bound of how many fit (positions in m)."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from swarm_envs.sim.arena import Arena

__all__ = ["SPAWN_GAP", "SPAWN_STALL_ROUNDS", "LATTICES", "LATTICE_SHIFTS", "lattice_lower_bound", "lattice_positions", "fit_count", "check_capacity", "spawn_positions"]

#: the gap (fraction of the radius) random placement keeps between robots and from the walls
SPAWN_GAP = 0.1

#: random placement rounds in a row that place no robot before the spawner turns to a lattice
SPAWN_STALL_ROUNDS = 8

#: lattices tried by :func:`_best_lattice`: hexagonal with rows along x, hexagonal with rows along y, square
LATTICES = ("hex", "hex_rotated", "square")

#: shifts per axis of a lattice cell tried by :func:`_best_lattice` (besides the wall-aligned and centred ones)
LATTICE_SHIFTS = 8


def _lattice(kind: str, pitch: float, extent: float, shift: tuple[float, float]) -> np.ndarray:
    """Points (k, 2) of a lattice of ``kind`` (:data:`LATTICES`) with nearest-neighbour distance ``pitch``
    (m), shifted by ``shift`` (m), covering the square [-extent, extent]^2."""
    row = pitch * np.sqrt(3) / 2 if kind != "square" else pitch
    n_i, n_j = int(np.ceil(extent / pitch)) + 2, int(np.ceil(extent / row)) + 2
    i, j = np.meshgrid(np.arange(-n_i, n_i + 1), np.arange(-n_j, n_j + 1))
    offset = 0.5 * (j % 2) if kind != "square" else 0.0
    pts = np.stack([(i + offset) * pitch + shift[0], j * row + shift[1]], -1).reshape(-1, 2)
    return pts[:, ::-1].copy() if kind == "hex_rotated" else pts


def _shifts(kind: str, pitch: float, inner: float) -> list[tuple[float, float]]:
    """Shifts of a lattice to try: centred, aligned with the walls (a point on the lowest row and column a
    centre may take, ``-inner``, for either row parity) and a grid over the lattice cell."""
    row = pitch * np.sqrt(3) / 2 if kind != "square" else pitch
    along, across = (pitch, row) if kind != "hex_rotated" else (row, pitch)
    period = (2 * along if kind == "hex_rotated" else along, 2 * across if kind == "hex" else across)
    aligned = [(-inner + a, -inner + b) for a in (0.0, 0.5 * pitch) for b in (0.0, row if kind != "square" else 0.0)]
    grid = [(a, b) for a in np.linspace(0, period[0], LATTICE_SHIFTS, endpoint=False) for b in np.linspace(0, period[1], LATTICE_SHIFTS, endpoint=False)]
    return [(0.0, 0.0), (0.5 * pitch, 0.0), (0.0, 0.5 * pitch)] + aligned + grid


def _best_lattice(region: Arena, radius: float, gap: float, avoid: np.ndarray | None = None, avoid_distance: float = 0.0) -> np.ndarray:
    """The lattice placement of discs of ``radius`` (m) with ``gap`` (m) between neighbours that fits the
    most discs in ``region`` (at least ``avoid_distance`` m from every point of ``avoid``), over the
    :data:`LATTICES` and their :func:`_shifts`: the densest placement the spawner falls back to, and the
    fit test of the build. Deterministic; O(area / pitch^2) per lattice and shift."""
    pitch = 2 * radius + gap
    inner = region.half - radius - 0.5 * gap  # centres stay within this distance of the middle
    best = np.empty((0, 2))
    if inner < 0:
        return best
    if avoid is None and (region.shape, region.size, radius, gap) in _LATTICE_CACHE:
        return _LATTICE_CACHE[region.shape, region.size, radius, gap]
    for kind in LATTICES:
        for shift in _shifts(kind, pitch, inner):
            pts = _lattice(kind, pitch, region.half, shift)
            pts = pts[region.contains(pts, radius + 0.5 * gap)]
            if avoid is not None and len(avoid) and len(pts):
                pts = pts[_far_from(pts, avoid, avoid_distance)]
            if len(pts) > len(best):
                best = pts
    best.setflags(write=False)
    if avoid is None:
        if len(_LATTICE_CACHE) >= 64:
            _LATTICE_CACHE.clear()
        _LATTICE_CACHE[region.shape, region.size, radius, gap] = best
    return best

#: the best lattice of recent (shape, size, radius, gap): a crowded scene spawns from it at every reset
_LATTICE_CACHE: dict[tuple, np.ndarray] = {}


def lattice_lower_bound(region: Arena, radius: float, gap: float) -> int:
    """A lower bound on how many discs any shifted hexagonal lattice (pitch 2 radius + gap) fits in
    ``region``, in O(1): rows x points per row inside the largest inscribed square."""
    pitch = 2 * radius + gap
    inner = region.half - radius - 0.5 * gap  # centres stay within this distance of the middle
    if region.shape == "circle":
        inner /= np.sqrt(2.0)  # the inscribed square of the disc of centres
    if inner <= 0:
        return 0
    # an arithmetic progression with step s has at least floor(L / s) points in any interval of length L
    return int(np.floor(2 * inner / (pitch * np.sqrt(3) / 2))) * int(np.floor(2 * inner / pitch))


def _lattice_block(region: Arena, radius: float, gap: float, n: int) -> np.ndarray:
    """At least ``n`` <= :func:`lattice_lower_bound` lattice points (hexagonal, pitch 2 radius + gap) in the
    smallest centred square that holds them inside ``region``: O(n), whatever the region's size."""
    pitch = 2 * radius + gap
    row = pitch * np.sqrt(3) / 2
    inner = region.half - radius - 0.5 * gap
    if region.shape == "circle":
        inner /= np.sqrt(2.0)
    half = inner
    for rows in range(1, n + 1):  # the narrowest square of rows x columns >= n (the lower bound's count)
        w = 0.5 * rows * row
        if np.floor(2 * w / row) * np.floor(2 * w / pitch) >= n:
            half = min(inner, w + 1e-9 * pitch)
            break
    pts = _lattice("hex", pitch, half, (0.0, 0.0))
    return pts[np.all(np.abs(pts) <= half, axis=1)]


def lattice_positions(
    region: Arena, radius: float, gap: float = 0.0, n: int | None = None, avoid: np.ndarray | None = None, avoid_distance: float = 0.0
) -> np.ndarray:
    """The lattice points (k, 2) m the spawner falls back to: discs of ``radius`` (m) with ``gap`` (m)
    between neighbours inside ``region``, at least ``avoid_distance`` (m) from every point of ``avoid``.
    The densest lattice placement (:func:`_best_lattice`; deterministic), or, when ``n`` is given and the
    region is roomy, an O(n) block of at least ``n`` points of one lattice (fewer only if ``avoid`` is
    crowded). A spawner that picks its robots among these points succeeds whenever there are enough."""
    avoid = None if avoid is None or not len(avoid) else np.asarray(avoid, dtype=float)
    extra = 0 if avoid is None else 7 * len(avoid)  # an open disc of one pitch holds at most 4 lattice points
    if n is not None and n + extra <= lattice_lower_bound(region, radius, gap):
        pts = _lattice_block(region, radius, gap, n + extra)
        return pts if avoid is None else pts[_far_from(pts, avoid, avoid_distance)]
    return _best_lattice(region, radius, gap, avoid, avoid_distance)


def fit_count(n: int, radius: float, region: Arena, gap: float = 0.0) -> int:
    """How many discs of ``radius`` (m) with ``gap`` (m) between neighbours the spawner can place in
    ``region`` for sure, up to ``n`` (a lattice placement, :func:`_best_lattice`). O(1) when the region is
    roomy (:func:`lattice_lower_bound` >= n); otherwise the lattices are enumerated, which costs O(n)
    because the region is then small."""
    if n <= lattice_lower_bound(region, radius, gap):
        return n
    return min(n, len(_best_lattice(region, radius, gap)))


def check_capacity(n: int, radius: float, region: Arena, gap: float = 0.0) -> None:
    """Raise ``ValueError`` saying how many fit when :func:`spawn_positions` cannot place ``n`` discs of
    ``radius`` (m) in ``region`` for every seed, i.e. when no lattice of :func:`_best_lattice` with ``gap``
    (m; default 0, discs touching) holds them. If it passes, ``spawn_positions`` succeeds for every seed."""
    fit = fit_count(n, radius, region, gap)
    if n > fit:
        raise ValueError(
            f"cannot place {n} robots of diameter {2 * radius:.3f} m in a {region.shape} region of size "
            f"{region.size:.4g} m: at most {fit} fit (the densest lattice placement, robots "
            + (f"{gap * 1e3:.1f} mm apart" if gap else "touching") + "); use fewer robots or a larger arena_size"
        )


def spawn_positions(
    rng: np.random.Generator,
    n: int,
    radius: float,
    arena: Arena,
    region: Arena | None = None,
    gap: float | None = None,
    max_tries: int = 50,
    avoid: np.ndarray | None = None,
    avoid_distance: float = 0.0,
    lattice_gap: float = 0.0,
) -> np.ndarray:
    """Seeded non-overlapping disc positions (n, 2) in metres inside ``region`` (default: the arena),
    each at least ``avoid_distance`` (m) from every point of ``avoid`` (k, 2) m (e.g. robots already placed).

    Random sequential placement (batched candidates, KD-tree checks) keeping ``gap`` (m; default
    :data:`SPAWN_GAP` radius) between discs: cost O(n log n), independent of the region's area. Where that
    stalls (:data:`SPAWN_STALL_ROUNDS` rounds without progress, or ``max_tries`` rounds), a random subset
    of a randomly shifted hexagonal lattice with the same gap, and last a random subset of the densest
    lattice placement with ``lattice_gap`` (m; default 0, touching; :func:`_best_lattice`, or an O(n) block
    of it in a roomy region). Without ``avoid`` this always succeeds when :func:`check_capacity` (with
    ``lattice_gap``) passes and raises its ``ValueError`` otherwise; with ``avoid`` it raises
    ``ValueError`` when even the lattice cannot keep away from those points.
    """
    region = region or arena
    gap = SPAWN_GAP * radius if gap is None else gap
    min_dist = 2 * radius + gap
    if avoid is not None and not len(avoid):
        avoid = None
    if avoid is None:
        check_capacity(n, radius, region, lattice_gap)
    placed = np.empty((0, 2))
    stalled = 0
    room = region.half - radius - 0.5 * gap > 0  # random placement keeps the gap from the walls too
    for _ in range(max_tries if room else 0):
        need = n - len(placed)
        if need == 0 or stalled >= SPAWN_STALL_ROUNDS:
            break
        cand = region.sample(rng, 4 * need + 8, radius + 0.5 * gap)
        if avoid is not None:
            cand = cand[_far_from(cand, avoid, avoid_distance)]
        if len(placed):
            d, _ = cKDTree(placed).query(cand, k=1)
            cand = cand[d >= min_dist]
        # greedy accept among the candidates themselves, in random order
        keep: list[int] = []
        if len(cand):
            close = cKDTree(cand).query_pairs(min_dist, output_type="ndarray")
            blocked = np.zeros(len(cand), dtype=bool)
            neighbours: list[list[int]] = [[] for _ in range(len(cand))]
            for a, b in close:
                neighbours[a].append(b)
                neighbours[b].append(a)
            for idx in range(len(cand)):
                if not blocked[idx]:
                    keep.append(idx)
                    blocked[neighbours[idx]] = True
                    if len(keep) == need:
                        break
        stalled = 0 if keep else stalled + 1
        placed = np.concatenate([placed, cand[keep]], axis=0)
    if len(placed) == n:
        return placed
    roomy = avoid is None and n <= lattice_lower_bound(region, radius, lattice_gap)
    if not roomy or (region.size / min_dist) ** 2 <= 50 * n:  # enumerating the region costs O(n)
        for _ in range(10):  # a random subset of a randomly shifted lattice with the random placement's gap
            pts = _lattice("hex", min_dist, region.half, tuple(rng.uniform(0, min_dist, 2)))
            pts = pts[region.contains(pts, radius + 0.5 * gap)]
            if avoid is not None and len(pts):
                pts = pts[_far_from(pts, avoid, avoid_distance)]
            if len(pts) >= n:
                return pts[np.sort(rng.choice(len(pts), n, replace=False))]
    lattice = lattice_positions(region, radius, lattice_gap, n, avoid, avoid_distance)
    if len(lattice) < n:
        raise ValueError(
            f"could not place {n} robots of radius {radius:.3f} m away from the {len(avoid)} given points: at most "
            f"{len(lattice)} fit; use a larger arena_size"
        )
    return lattice[np.sort(rng.choice(len(lattice), n, replace=False))]


def _far_from(points: np.ndarray, others: np.ndarray, distance: float) -> np.ndarray:
    """(len(points),) bool: the point is at least ``distance`` from every one of ``others``."""
    d, _ = cKDTree(others).query(points, k=1)
    return d >= distance
