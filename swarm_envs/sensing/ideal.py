"""The ``sensing="ideal"`` stack: exact, noiseless, lossless values in the same layout as the full stack.

An ablation (what would a policy do with perfect sensing?) and a check that the observation layout is
right. Neighbours are all robots within the platform's IR range (no occlusion by robots; a static obstacle
segment crossing the centre line separates a pair); messages reach every robot in range instantly; scale-free coordinates are the true relative positions divided by the mean
neighbour distance.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from scipy.spatial import cKDTree

from swarm_envs._compile._numba import njit
from swarm_envs.sensing.observation import nearest_slots, wrap_difference_scalar, wrapped_difference
from swarm_envs.sim.platforms import Platform
from swarm_envs.sensing.base import MessageReadings, NeighbourReadings, ScaleFreeReadings, SensorFrame

__all__ = ["IdealSensing", "candidate_pairs", "copy_pairs", "directed_pairs", "directed_links", "neighbour_pairs"]

#: robots per copy up to which :func:`copy_pairs` checks every pair of a copy; larger copies use a cell grid
BRUTE_FORCE_MAX = 64


def candidate_pairs(positions: np.ndarray, max_range: float, copy: np.ndarray | None = None) -> np.ndarray:
    """(P, 2) index pairs i < j of centres closer than ``max_range`` (m), sorted; KD-tree, not N^2.

    ``copy`` (N,) gives each robot's env copy: robots of different copies are never paired (the tree gets
    a third coordinate that puts copies beyond the range of each other; within a copy it is 0, so the
    distances and the pairs are those of the copy alone). Sorted lexicographically, so each copy's pairs
    come in the same order as in a single env.
    """
    positions = np.asarray(positions, dtype=float).reshape(-1, 2)
    if copy is not None and len(positions):
        lift = np.asarray(copy, dtype=float).reshape(-1, 1) * (2.0 * float(max_range) + 1.0)
        points = np.concatenate([positions, lift], axis=1)
    else:
        points = positions
    pairs = cKDTree(points).query_pairs(max_range, output_type="ndarray")
    if len(pairs) == 0:
        return np.zeros((0, 2), dtype=np.int64)
    pairs = pairs.astype(np.int64)
    # lexicographic order by one argsort of a unique integer key (as lexsort, ~2.5x faster)
    return pairs[np.argsort(pairs[:, 0] * len(points) + pairs[:, 1])]


def copy_pairs(positions: np.ndarray, max_range: float, copy_size: int) -> np.ndarray:
    """:func:`candidate_pairs` of rows grouped in env copies of ``copy_size`` consecutive robots: the same
    (P, 2) sorted pairs i < j of one copy closer than ``max_range`` (m), squared distance ``<= max_range**2``
    as in the KD-tree. Compiled: small copies (at most :data:`BRUTE_FORCE_MAX` robots) check every pair of
    a copy, larger ones the robots of the neighbouring cells of a grid of cells >= ``max_range``; both emit
    the pairs already sorted. Larger copies with a non-finite position or a range <= 0 (no grid):
    :func:`candidate_pairs`."""
    positions = np.ascontiguousarray(positions, dtype=np.float64).reshape(-1, 2)
    copy_size = int(copy_size)
    if copy_size < 1 or len(positions) % copy_size:
        raise ValueError(f"copy_pairs: {len(positions)} rows are not whole copies of {copy_size} robots")
    r2 = float(max_range) * float(max_range)
    if copy_size <= BRUTE_FORCE_MAX:
        return _copy_pairs_kernel(positions, copy_size, r2)
    if np.isfinite(positions).all() and max_range > 0:
        # cells a little larger than the range: a pair in range is never two cells apart despite rounding
        return _grid_pairs_kernel(positions, copy_size, r2, float(max_range) * (1.0 + 1e-6))
    n_copies = len(positions) // copy_size
    copy = np.repeat(np.arange(n_copies), copy_size) if n_copies > 1 else None
    return candidate_pairs(positions, max_range, copy)


def directed_links(pairs: np.ndarray, n_rows: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Both directions of sorted (P, 2) pairs i < j as :func:`directed_pairs` gives them (sorted by
    (rx, tx)), plus the index of each link's pair; ``n_rows`` > every robot index. O(P), compiled (plain
    numpy reference: :func:`swarm_envs._compile.reference.directed_links`)."""
    pairs = np.ascontiguousarray(pairs, dtype=np.int64).reshape(-1, 2)
    if len(pairs) == 0:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty, empty
    return _directed_links_kernel(pairs, int(n_rows))


@njit(cache=True, nogil=True)
def _link_geometry_kernel(positions: np.ndarray, headings: np.ndarray, rx: np.ndarray, tx: np.ndarray):  # pragma: no cover - compiled
    """Per link: offset ``p_tx - p_rx`` (dx, dy) (m), rx's heading and ``wrap_angle(h_tx - h_rx)`` (rad),
    in one pass (:func:`swarm_envs.sensing.observation.wrap_difference_scalar`: the bits of ``wrap_angle``)."""
    P = len(rx)
    dx = np.empty(P, np.float64)
    dy = np.empty(P, np.float64)
    heading_rx = np.empty(P, np.float64)
    heading = np.empty(P, np.float64)
    for q in range(P):
        r, t = rx[q], tx[q]
        dx[q] = positions[t, 0] - positions[r, 0]
        dy[q] = positions[t, 1] - positions[r, 1]
        heading_rx[q] = headings[r]
        heading[q] = wrap_difference_scalar(headings[t], headings[r])
    return dx, dy, heading_rx, heading


@njit(cache=True, nogil=True)
def _scale_free_kernel(order: np.ndarray, distance: np.ndarray, cos_sin: np.ndarray, mean_distance: np.ndarray):  # pragma: no cover - compiled
    """Slot (r, c): ``distance * (cos, sin) / scale`` of its link, scale = robot r's mean neighbour
    distance (1 if not positive); zero for empty slots."""
    n, k = order.shape
    out = np.empty((n, k, 2), np.float64)
    out[:] = 0.0
    for r in range(n):
        scale = mean_distance[r] if mean_distance[r] > 0 else 1.0
        for c in range(k):
            o = order[r, c]
            if o >= 0:
                out[r, c, 0] = distance[o] * cos_sin[r, c, 0] / scale
                out[r, c, 1] = distance[o] * cos_sin[r, c, 1] / scale
    return out


@njit(cache=True, nogil=True)
def _copy_pairs_kernel(positions: np.ndarray, m: int, r2: float) -> np.ndarray:  # pragma: no cover - compiled
    """Pairs i < j of each copy of ``m`` rows with dx^2 + dy^2 <= r2, in (i, j) order (one pass into a
    buffer of the n (m - 1) / 2 pairs the copies have at most)."""
    n = positions.shape[0]
    out = np.empty((n * (m - 1) // 2, 2), np.int64)
    p = 0
    for o in range(0, n, m):
        for i in range(o, o + m):
            xi, yi = positions[i, 0], positions[i, 1]
            for j in range(i + 1, o + m):
                dx = positions[j, 0] - xi
                dy = positions[j, 1] - yi
                if dx * dx + dy * dy <= r2:
                    out[p, 0] = i
                    out[p, 1] = j
                    p += 1
    return out[:p]


@njit(cache=True, nogil=True)
def _grid_pairs_kernel(positions: np.ndarray, m: int, r2: float, cell: float) -> np.ndarray:  # pragma: no cover - compiled
    """Pairs i < j of each copy of ``m`` rows with dx^2 + dy^2 <= r2, in (i, j) order: robots binned in
    square cells of side ``cell`` (>= the range; doubled until there are at most ~4 m cells), each
    robot's partners j > i collected from its 3 x 3 cells and sorted."""
    n = positions.shape[0]
    out = np.empty((max(16, 8 * n), 2), np.int64)
    p = 0
    buf = np.empty(m, np.int64)
    for o in range(0, n, m):
        xmin, ymin = positions[o, 0], positions[o, 1]
        xmax, ymax = xmin, ymin
        for i in range(o, o + m):
            xmin = min(xmin, positions[i, 0])
            xmax = max(xmax, positions[i, 0])
            ymin = min(ymin, positions[i, 1])
            ymax = max(ymax, positions[i, 1])
        side = cell
        nx = int((xmax - xmin) / side) + 1
        ny = int((ymax - ymin) / side) + 1
        while nx * ny > 4 * m + 16:
            side *= 2.0
            nx = int((xmax - xmin) / side) + 1
            ny = int((ymax - ymin) / side) + 1
        cx = np.empty(m, np.int64)
        cy = np.empty(m, np.int64)
        start = np.empty(nx * ny + 1, np.int64)
        start[:] = 0
        for a in range(m):
            cx[a] = int((positions[o + a, 0] - xmin) / side)
            cy[a] = int((positions[o + a, 1] - ymin) / side)
            start[cx[a] * ny + cy[a] + 1] += 1
        for c in range(nx * ny):
            start[c + 1] += start[c]
        fill = start[:-1].copy()
        members = np.empty(m, np.int64)
        for a in range(m):  # counting sort: each cell lists its robots in increasing index
            c = cx[a] * ny + cy[a]
            members[fill[c]] = a
            fill[c] += 1
        for a in range(m):
            xi, yi = positions[o + a, 0], positions[o + a, 1]
            cnt = 0
            for gx in range(max(cx[a] - 1, 0), min(cx[a] + 2, nx)):
                for gy in range(max(cy[a] - 1, 0), min(cy[a] + 2, ny)):
                    c = gx * ny + gy
                    for q in range(start[c + 1] - 1, start[c] - 1, -1):  # members > a, from the top
                        b = members[q]
                        if b <= a:
                            break
                        dx = positions[o + b, 0] - xi
                        dy = positions[o + b, 1] - yi
                        if dx * dx + dy * dy <= r2:
                            buf[cnt] = b
                            cnt += 1
            if cnt == 0:
                continue
            if cnt > 64:
                part = np.sort(buf[:cnt])
                for q in range(cnt):
                    buf[q] = part[q]
            else:  # insertion sort of the few partners
                for q in range(1, cnt):
                    v = buf[q]
                    w = q - 1
                    while w >= 0 and buf[w] > v:
                        buf[w + 1] = buf[w]
                        w -= 1
                    buf[w + 1] = v
            if p + cnt > out.shape[0]:
                grown = np.empty((2 * out.shape[0] + cnt, 2), np.int64)
                for q in range(p):
                    grown[q, 0], grown[q, 1] = out[q, 0], out[q, 1]
                out = grown
            for q in range(cnt):
                out[p, 0] = o + a
                out[p, 1] = o + buf[q]
                p += 1
    return out[:p].copy()


@njit(cache=True, nogil=True)
def _directed_links_kernel(pairs: np.ndarray, n_rows: int):  # pragma: no cover - compiled
    """Row r's links in (rx, tx) order: first tx < r (pairs (tx, r), met in increasing tx), then tx > r
    (pairs (r, tx), also increasing) -- a counting sort, no comparison sort."""
    P = pairs.shape[0]
    lower = np.empty(n_rows, np.int64)
    lower[:] = 0
    degree = np.empty(n_rows, np.int64)
    degree[:] = 0
    for p in range(P):
        lower[pairs[p, 1]] += 1
        degree[pairs[p, 0]] += 1
        degree[pairs[p, 1]] += 1
    low_at = np.empty(n_rows, np.int64)
    high_at = np.empty(n_rows, np.int64)
    start = 0
    for r in range(n_rows):
        low_at[r] = start
        high_at[r] = start + lower[r]
        start += degree[r]
    rx = np.empty(2 * P, np.int64)
    tx = np.empty(2 * P, np.int64)
    link = np.empty(2 * P, np.int64)
    for p in range(P):
        i, j = pairs[p, 0], pairs[p, 1]
        q = low_at[j]
        rx[q], tx[q], link[q] = j, i, p
        low_at[j] = q + 1
        q = high_at[i]
        rx[q], tx[q], link[q] = i, j, p
        high_at[i] = q + 1
    return rx, tx, link


def neighbour_pairs(positions: np.ndarray, max_range: float, copy: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Both directions (rx, tx) of every pair of centres closer than ``max_range`` (m), sorted by (rx, tx).

    ``copy`` as in :func:`candidate_pairs` (no pair crosses copies).
    """
    return directed_pairs(candidate_pairs(positions, max_range, copy))


def directed_pairs(pairs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Both directions (rx, tx) of (P, 2) undirected index pairs, sorted by (rx, tx)."""
    if len(pairs) == 0:
        empty = np.zeros(0, dtype=np.int64)
        return empty, empty
    rx = np.concatenate([pairs[:, 0], pairs[:, 1]])
    tx = np.concatenate([pairs[:, 1], pairs[:, 0]])
    order = np.argsort(rx * (int(pairs.max()) + 1) + tx)  # (rx, tx) keys are unique: same order as lexsort
    return rx[order], tx[order]


class IdealSensing:
    """Ground-truth sensing within IR range (see module docstring), for ``n_copies`` env copies of
    ``n_robots`` robots each (rows = robots of all copies, copy-major)."""

    def __init__(
        self, platform: Platform, n_robots: int, n_neighbours: int, message_bits: int, n_copies: int = 1, obstacles: np.ndarray | None = None
    ) -> None:
        self.platform = platform
        #: static obstacle segments (S, 2, 2) m: a pair whose centre segment crosses one is no neighbour
        self.obstacles = obstacles if obstacles is not None and len(obstacles) else None
        self.copy_size = int(n_robots)
        self.n_copies = int(n_copies)
        self.n = self.copy_size * self.n_copies
        self.copy = np.repeat(np.arange(self.n_copies), self.copy_size)
        self.k = n_neighbours
        self.message_bits = message_bits

    @classmethod
    def from_config(
        cls, platform: Platform, n_robots: int, config: dict[str, Any], n_copies: int = 1, obstacles: np.ndarray | None = None
    ) -> IdealSensing:
        """The stack for a task's resolved settings ``config`` (:mod:`swarm_envs.sensing.stacks`)."""
        return cls(platform, n_robots, config["n_neighbours"], config["message_bits"], n_copies, obstacles=obstacles)

    def reset(self, copies: np.ndarray | None = None, rngs: list[np.random.Generator] | None = None) -> None:
        """Nothing to reset: the ideal stack is stateless and noiseless."""

    def step(
        self,
        positions: np.ndarray,
        headings: np.ndarray,
        payloads: np.ndarray | None,
        sending: np.ndarray | None = None,
        silent: np.ndarray | None = None,
        emit_off: np.ndarray | None = None,
        detect_off: np.ndarray | None = None,
    ) -> SensorFrame:
        """One step for all robots; ``payloads`` (N, b) bool or None, ``sending`` (N,) bool robots whose
        payload goes out this step (default: all when payloads are given); ``silent`` (N,) bool switched-off
        robots (no neighbours, not a neighbour); ``emit_off`` (N,) bool robots no one senses (receive-only),
        ``detect_off`` (N,) bool robots that sense no one (transmit-only)."""
        positions = np.asarray(positions, dtype=np.float64)
        headings = np.asarray(headings, dtype=np.float64)
        pairs = copy_pairs(positions, self.platform.ir_range, self.copy_size)
        if silent is not None and np.any(silent):
            pairs = pairs[~(silent[pairs[:, 0]] | silent[pairs[:, 1]])]
        if self.obstacles is not None and len(pairs):
            from swarm_envs.ir.blocking import rays_blocked

            pairs = pairs[~rays_blocked(positions[pairs[:, 0]], positions[pairs[:, 1]], self.obstacles)]
        rx, tx, link = directed_links(pairs, self.n)
        # exact pose of tx seen by rx (its distance, bearing and heading in rx's frame); the two directions of a pair have
        # opposite offsets, so one hypot per pair gives both distances bit for bit
        dx, dy, heading_rx, heading = _link_geometry_kernel(positions, headings, rx, tx)
        pair_link = np.flatnonzero(rx < tx)  # each pair's i -> j link (offset p_j - p_i)
        distance = np.hypot(dx[pair_link], dy[pair_link])[link]
        bearing = wrapped_difference(np.arctan2(dy, dx), heading_rx)
        one_way = np.zeros(len(rx), dtype=bool)
        if emit_off is not None:
            one_way |= np.asarray(emit_off, dtype=bool)[tx]
        if detect_off is not None:
            one_way |= np.asarray(detect_off, dtype=bool)[rx]
        if one_way.any():  # the links from robots that do not emit and to robots that do not detect
            rx, tx, distance, bearing, heading = (v[~one_way] for v in (rx, tx, distance, bearing, heading))
        # the k nearest links of every robot, for the scale-free coordinates and (reused) the observations
        order = nearest_slots(self.n, rx, distance, self.k)
        valid = order >= 0
        kept = np.where(valid, order, 0)  # empty slots read link 0 and are zeroed below
        if len(rx):
            b = bearing[kept]
            cos_sin = np.stack([np.cos(b), np.sin(b)], -1)
        else:
            cos_sin = np.zeros((self.n, self.k, 2))
        neighbours = NeighbourReadings(rx, tx, distance, bearing, heading, np.zeros(len(rx)), slots=order, slot_cos_sin=cos_sin)

        if self.message_bits > 0 and payloads is not None:
            got = np.ones(len(rx), dtype=bool) if sending is None else np.asarray(sending, bool)[tx]
            messages = MessageReadings(rx[got], tx[got], bearing[got], payloads[tx[got]].astype(float), distance[got])
        else:
            messages = MessageReadings(payload=np.zeros((0, self.message_bits)))

        # scale-free coordinates [L]: true offsets over the mean neighbour distance, the k nearest per robot
        # (only the kept links are turned into coordinates)
        mean_distance = np.bincount(rx, distance, self.n) / np.maximum(np.bincount(rx, minlength=self.n), 1)
        if len(rx):
            packed = _scale_free_kernel(order, distance, cos_sin, mean_distance)
        else:
            packed = np.zeros((self.n, self.k, 2))
        scale_free = ScaleFreeReadings(packed, valid, valid.any(axis=1), np.where(valid, tx[kept], -1) if len(rx) else np.full(order.shape, -1))
        return SensorFrame(neighbours, messages, scale_free)
