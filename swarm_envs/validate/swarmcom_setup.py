"""Shared set-ups of the SwarmCom validation [T20]: the paper's published figures and the swept settings,
random robot placements (a centre robot with others in its 61 cm disc, robots in the 72 x 72 cm arena) and
the random walk of [T20 Alg. 1] with its snapshots; used by the channel count (Figs. 20-21), the flooding
experiment (Fig. 16b) and the report."""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from swarm_envs.sim.platforms import get_platform

PLATFORM = "epuck"
SEP = 3.0  # m between independent scenes (> ir_range)
PAPER_RANGE = {75: 21.0, 25: 33.0, 10: 45.0}  # cm [T20 Sec. 6.2.4, Fig. 12a]
PAPER_RELIABLE_CM = 61.0  # [T20 Sec. 7]
PAPER_ARENA_NC = {10: 4, 20: 6, 30: 9}  # [T20 Fig. 21]
ARENA = 0.72  # m [T20 Sec. 6.1]
DISC_R = 0.61  # m, communication range used for Fig. 20a
OCC_RULES = ("ray", "centre")  # per-ray line of sight (as simulated) and a centre-line rule (a pair cut by any robot on the segment)
PAPER_MTR = 5  # Fig. 20a: the 61 cm range of m_tr = 5 [T20 Sec. 6.2.6 ("see Table 12a"), Sec. 7]
#: Fig. 21's m_tr is not stated in [T20 Sec. 6.2.6]; the mobile experiments of Sec. 6.2.2 (and 6.2.3, configured
#: "as in the flooding experiment") use m_tr = 10 (45 cm). Both that and Fig. 20a's m_tr = 5 are measured.
FIG21_MTR = 10
FIG21_MTRS = (FIG21_MTR, PAPER_MTR)
M_TR_SWEEP = (5, 10, 25, 75)  # relative thresholds of the paper's ranges 61, 45, 33, 21 cm [Sec. 6.2.4, 7]
PAPER_FIG20A = {"bound": 15, "densest": 6}  # [T20 Sec. 6.2.6]
PAPER_BITRATE_RELIABLE = {310: 61.0, 1800: 14.0}  # cm, P_e < 0.01, m_tr = 5 [T20 Sec. 7]
BITRATE_SWEEP = (310, 650, 1080, 1160, 1670, 1800)  # the e-puck's rates [T20 Sec. 5]; Fig. 10: 310, 650, 1160


def _rsa(n: int, rng: np.random.Generator, inside, sample, min_dist: float, fixed: np.ndarray, max_tries: int = 20000) -> np.ndarray:
    """Random sequential addition of n discs (centres at least min_dist apart) after the ``fixed`` ones."""
    pts = [p for p in fixed]
    arr = np.array(pts).reshape(-1, 2)
    tries = 0
    while len(pts) < len(fixed) + n:
        cand = sample(64)
        cand = cand[inside(cand)]
        for c in cand:
            if arr.size == 0 or np.min(np.sum((arr - c) ** 2, axis=1)) >= min_dist**2:
                pts.append(c)
                arr = np.array(pts)
                if len(pts) == len(fixed) + n:
                    break
        tries += 1
        if tries > max_tries:
            raise RuntimeError("random sequential addition failed; density too high")
    return np.array(pts)


def _hex_disc(n_others: int, rng: np.random.Generator, radius: float, spacing: float, sweeps: int) -> np.ndarray:
    """Dense random configuration: centre robot at the origin, others on a randomly rotated hexagonal
    lattice cut to the disc (random sites kept), then hard-disk Monte Carlo shaking (conservative
    simultaneous moves: a move is accepted only if clear of every other robot's old and new position)."""
    a = spacing * 1.0005
    rot = rng.uniform(0, np.pi / 3)
    k = int(np.ceil(radius / a)) + 2
    i, j = np.meshgrid(np.arange(-k, k + 1), np.arange(-k, k + 1))
    lat = np.stack([a * (i + 0.5 * j), a * (np.sqrt(3) / 2) * j], -1).reshape(-1, 2)
    c, s = np.cos(rot), np.sin(rot)
    lat = lat @ np.array([[c, s], [-s, c]])
    r = np.hypot(lat[:, 0], lat[:, 1])
    sites = lat[(r <= radius) & (r > 1e-9)]
    n_others = min(n_others, sites.shape[0])  # the lattice holds ~270 others within 61 cm (caller reports it)
    pts = np.vstack([[0.0, 0.0], sites[rng.choice(sites.shape[0], n_others, replace=False)]])
    step = 0.5 * spacing
    for _ in range(sweeps):
        prop = pts + rng.uniform(-step, step, pts.shape)
        prop[0] = 0.0
        ok = np.hypot(prop[:, 0], prop[:, 1]) <= radius
        n = pts.shape[0]
        dd, ii = cKDTree(np.vstack([pts, prop])).query(prop, k=4)
        own = (ii == np.arange(n)[:, None]) | (ii == n + np.arange(n)[:, None])
        ok &= np.where(own, np.inf, dd).min(axis=1) >= spacing
        ok[0] = False
        pts[ok] = prop[ok]
        rate = ok[1:].mean()
        step = float(np.clip(step * (1.2 if rate > 0.4 else 0.8), 1e-4, 0.5 * spacing))
    return pts


def disc_configuration(n_others: int, rng: np.random.Generator, radius: float = DISC_R) -> np.ndarray:
    """Centre robot at the origin plus ``n_others`` non-overlapping robots with centres within ``radius``."""
    p = get_platform(PLATFORM)
    dmin = 2 * p.radius
    phi = (n_others + 1) * p.radius**2 / (radius + p.radius) ** 2
    if phi < 0.3:
        def sample(m):
            rr = radius * np.sqrt(rng.random(m))
            th = rng.uniform(-np.pi, np.pi, m)
            return np.stack([rr * np.cos(th), rr * np.sin(th)], -1)

        return _rsa(n_others, rng, lambda c: np.ones(len(c), bool), sample, dmin, np.zeros((1, 2)))
    return _hex_disc(n_others, rng, radius, dmin, sweeps=60)


def arena_configuration(n: int, rng: np.random.Generator, side: float = ARENA) -> np.ndarray:
    """Robot 0 static at the arena centre, n-1 others uniform non-overlapping inside the walls."""
    p = get_platform(PLATFORM)
    r = p.radius
    c = np.array([[side / 2, side / 2]])
    return _rsa(n - 1, rng, lambda q: np.ones(len(q), bool), lambda m: rng.uniform(r, side - r, (m, 2)), 2 * r, c)


class RandomWalk:
    """[T20 Alg. 1] for many robots, kinematic: rotate by a random angle in (-pi, pi] at the maximum
    angular speed, then drive at a random v in [-128, 128] mm/s for t_m; a move that would overlap another
    robot or leave the arena is not made (the robot stays put for that step)."""

    def __init__(self, n: int, rng: np.random.Generator, t_m: float = 2.0, dt: float = 0.1) -> None:
        p = get_platform(PLATFORM)
        self.rng, self.t_m, self.dt = rng, t_m, dt
        self.v_max, self.w_max = p.max_speed, p.max_angular_speed
        self.turn_left = np.zeros(n)
        self.move_left = np.zeros(n)
        self.v = np.zeros(n)
        self.n = n

    def _new(self, idx: np.ndarray) -> None:
        self.turn_left[idx] = self.rng.uniform(-np.pi, np.pi, idx.size)
        self.v[idx] = self.rng.uniform(-self.v_max, self.v_max, idx.size)
        self.move_left[idx] = self.t_m

    def step(self, pos: np.ndarray, head: np.ndarray, scene: np.ndarray, origin: np.ndarray, side: float, radius: float, static: np.ndarray) -> None:
        done = np.flatnonzero((np.abs(self.turn_left) < 1e-12) & (self.move_left <= 1e-12))
        if done.size:
            self._new(done)
        turning = np.abs(self.turn_left) > 1e-12
        dth = np.clip(self.turn_left, -self.w_max * self.dt, self.w_max * self.dt) * turning
        head += np.where(static, 0.0, dth)
        self.turn_left -= dth
        moving = ~turning & (self.move_left > 1e-12)
        self.move_left[moving] -= self.dt
        v = np.where(moving & ~static, self.v, 0.0)
        prop = pos + (v * self.dt)[:, None] * np.stack([np.cos(head), np.sin(head)], -1)
        loc = prop - origin[scene]
        ok = np.all((loc >= radius) & (loc <= side - radius), axis=1)
        n = pos.shape[0]
        pairs = cKDTree(np.vstack([pos, prop])).query_pairs(2 * radius - 1e-9, output_type="ndarray")
        pairs = pairs[pairs[:, 0] % n != pairs[:, 1] % n]
        for col in (0, 1):  # a proposed position touching any other robot (old or new place) is refused
            ok[pairs[pairs[:, col] >= n, col] - n] = False
        pos[ok] = prop[ok]


def arena_walk_snapshots(n: int, rng: np.random.Generator, replicas: int, snapshots: int, period_s: float = 30.0) -> list[tuple[np.ndarray, np.ndarray]]:
    """Snapshots like [T20 Fig. 21]: robot 0 static at the centre of the 72 x 72 cm arena, the others doing
    the random walk of [T20 Alg. 1]; ``replicas`` arenas side by side, one snapshot of each every
    ``period_s`` (the paper counts lit robots every 30 s), after a first ``period_s`` of walking."""
    p = get_platform(PLATFORM)
    scene = np.repeat(np.arange(replicas), n)
    origin = np.stack([SEP * np.arange(replicas), np.zeros(replicas)], -1)
    pos = np.vstack([arena_configuration(n, rng) for _ in range(replicas)]) + origin[scene]
    head = rng.uniform(-np.pi, np.pi, n * replicas)
    static = np.zeros(n * replicas, dtype=bool)
    static[::n] = True
    walk = RandomWalk(n * replicas, rng)
    out = []
    steps = int(round(period_s / walk.dt))
    for _ in range(snapshots):
        for _ in range(steps):
            walk.step(pos, head, scene, origin, ARENA, p.radius, static)
        for r in range(replicas):
            out.append((pos[r * n : (r + 1) * n] - origin[r], head[r * n : (r + 1) * n].copy()))
    return out
