"""Mid-angle navigation: a seeker reaches a goal robot through a network of static relays that tell it the
hop count to the goal, steering through the mid-angles between relays [L Sec. 6.4.4, Alg. 8, Fig. 6.10].

The arena holds a corridor of ``lanes`` lanes (default 1: straight) 6 robot diameters wide, walled off from
the rest of the arena; more lanes wind, each turning into the next behind a wall. Walls are static
obstacles: they stop robots and block infrared light. Static robots stand in *gates*, pairs across the corridor
every gate spacing along its centre line, and the goal robot (static robot 0) at the corridor's far end;
the seekers (the agents, ``robot_0`` ..) start at its other end, out of the goal's infrared range (and,
with more lanes, behind walls).

The static robots run a hop-count firmware over SwarmCom (the "broadcasting their hop distance from the
goal robot" of Alg. 8): the goal broadcasts 0; every other static robot keeps, per static neighbour, the
hop count two consecutive frames of that neighbour agreed on (a single corrupted frame changes nothing),
and broadcasts 1 + the lowest of those confirmed in the last ``HOP_MEMORY_STEPS`` steps (2**b - 1,
"unknown", when none), as ``message_bits`` payload bits (LSB first). It trusts a 0 only from the goal's
id and ignores the seekers' frames. Frames are real SwarmCom frames: lost, collided and corrupted ones shape the
gradient.

Metrics (ground truth): a seeker *arrives* when its centre comes within 2.5 radii of the goal's (touching
it, with a quarter of a diameter to spare); ``success_rate`` = share of seekers that arrived;
``time_to_goal`` = mean over seekers of the arrival time (s), or the time elapsed for a seeker not there
yet (censored at the episode's end); ``path_ratio`` = mean over arrived seekers of the path they drove
until arrival over the shortest path (around the walls' ends at one robot radius, relays ignored, minus
the contact distance), NaN while none arrived; ``collision_fraction`` = share of seekers in contact.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

from swarm_envs.tasks.factories import task_module
from swarm_envs.tasks.task import (
    reward_weight,
    DT,
    Default,
    Platform,
    get_platform,
    Arena,
    BatchState,
    Int,
    Real,
    SettingsError,
    Task,
    bump_any,
    check_capacity,
    distance_to_segments,
    message_range,
    segments_crossed,
    spawn_positions,
)

__all__ = [
    "MidAngleNavigationTask",
    "MidAngleNavigationEnv",
    "Corridor",
    "HOP_MEMORY_STEPS",
    "MAX_STATIC_ROBOTS",
    "MAX_HOP_BITS",
    "arena_size_range",
    "raw_env",
    "parallel_env",
    "env",
]

#: steps a static robot keeps the hop count it last confirmed for a static neighbour (5 s: at 1250 bps it
#: decodes each neighbour every second or two; a newer confirmed value replaces it)
HOP_MEMORY_STEPS = 50
#: a seeker arrives within this many robot radii of the goal's centre
ARRIVAL_RADII = 2.5
#: default lane width, and the narrowest allowed, in robot diameters
LANE_DIAMETERS, MIN_LANE_DIAMETERS = 6.0, 4.5
#: a gate's relays stand this many diameters either side of the centre line (a gap of 3 diameters between them)
GATE_OFFSET_DIAMETERS = 2.0
#: the start square is the lane's square inset by this many robot radii on every side
START_INSET_RADII = 0.1
#: static robots (the goal and the relays) of one corridor at most: building the corridor and spawning take
#: O(relays log relays), but the relays' hop-count memory holds 24 bytes per ordered pair of static robots
#: (96 MB per env copy at 2,000) and make() + reset() take ~1 s at 2,000 (measured; docs/settings.md)
MAX_STATIC_ROBOTS = 2_000
#: message_bits at most: a hop count, and 2**b - 1 for "unknown", is a signed 64-bit integer
MAX_HOP_BITS = 63


def gate_spacing(platform: Platform) -> float:
    """Distance (m) between neighbouring gates along the centre line: 0.4 message ranges, at least 3 diameters."""
    return max(0.4 * message_range(platform), 3.0 * platform.diameter)


def arena_size_range(platform: Platform, lanes: int) -> tuple[float, float]:
    """(smallest, largest) arena side (m, rounded inwards to the mm) the corridor of ``lanes`` lanes for
    ``platform``'s robots is built for.

    Smallest: lanes at least 4.5 robot diameters wide, and with one lane the start square (a lane width of
    6 diameters, inset 0.1 radii) beyond the goal's arrival radius of 2.5 radii, so no seeker starts
    arrived: side >= 1.5 lane widths + 2.4 radii. With more lanes the goal stands a lane away behind a wall.
    Largest: the corridor holds at most :data:`MAX_STATIC_ROBOTS` static robots (the goal and two relays per
    gate); its centre line is ``lanes`` x (side - W) + (lanes - 1) x W long for a lane width W."""
    d, r = platform.diameter, platform.radius
    W = LANE_DIAMETERS * d
    low = lanes * MIN_LANE_DIAMETERS * d
    if lanes == 1:
        low = max(low, 1.5 * W + (ARRIVAL_RADII - START_INSET_RADII) * r)
    # gates stand at W/2 + k spacing (k = 1, 2, ..) up to the centre line's length minus one spacing: fewer
    # than G + 1 gates while the length is below W/2 + (G + 2) spacing
    gates, spacing = (MAX_STATIC_ROBOTS - 1) // 2, gate_spacing(platform)
    length = W / 2 + (gates + 2) * spacing
    high = (length + W) / lanes
    return math.ceil(low * 1000 - 1e-9) / 1000, math.floor(high * 1000 - 1e-6) / 1000


@dataclass(frozen=True)
class Corridor:
    """The corridor layout of one env (m, arena frame): walls, centre line, gates, goal and start square.

    Attributes:
        lane_width: width W of a lane.
        walls: (lanes - 1, 2, 2) wall segments between neighbouring lanes.
        centre_line: (P, 2) polyline from the start square's centre to the goal.
        relays: (R, 2) nominal relay positions (gate pairs, centre-line order).
        goal: (2,) goal robot position.
        start_centre: (2,) centre of the start square (side ``lane_width``).
        nodes: (K, 2) the walls' free ends, one robot radius beyond (shortest-path waypoints).
        node_distance: (K,) shortest distance from each node to the goal.
    """

    lane_width: float
    walls: np.ndarray
    centre_line: np.ndarray
    relays: np.ndarray
    goal: np.ndarray
    start_centre: np.ndarray
    nodes: np.ndarray
    node_distance: np.ndarray

    def distance_to_goal(self, points: np.ndarray) -> np.ndarray:
        """(...,) shortest distance (m) from ``points`` (..., 2) to the goal's centre around the walls:
        straight if the goal is in sight, else via the visible wall ends (:attr:`nodes`)."""
        points = np.asarray(points, dtype=float)
        targets = np.concatenate([self.goal[None], self.nodes])  # (K + 1, 2)
        rest = np.concatenate([[0.0], self.node_distance])
        seen = ~segments_crossed(np.broadcast_to(points[..., None, :], points.shape[:-1] + targets.shape), targets, self.walls)
        length = np.linalg.norm(points[..., None, :] - targets, axis=-1) + rest
        return np.where(seen, length, np.inf).min(axis=-1)


def _size_ranges_text() -> dict[str, str]:
    """The one-lane arena bounds of the suite's platforms as text, for the settings table."""
    names = {"rone": "r-one", "epuck": "e-puck", "droplet": "Droplet"}
    bounds = {name: arena_size_range(get_platform(key), 1) for key, name in names.items()}
    return {end: ", ".join(f"{name} {b[i]:g} m" for name, b in bounds.items()) for i, end in enumerate(("low", "high"))}


_SIZE_RANGES = _size_ranges_text()


def corridor(size: float, lanes: int, platform: Platform) -> Corridor:
    """The corridor of ``lanes`` lanes in a square arena of side ``size`` (m) for ``platform``'s robots
    (module docstring). Lanes are 6 robot diameters wide (narrower, down to 4.5, when ``size`` is too
    small for that) and as long as the arena; they are stacked in a band across the arena's middle,
    walled off from the space above and below. Lane k (from the bottom) runs right for even k, left for
    odd k, and turns into the next at its end; a gate (two relays 2 diameters either side of the centre
    line) stands every 0.4 message ranges (at least 3 diameters) along the centre line, from one gate
    spacing past the start square to one before the goal."""
    half, d, r = size / 2, platform.diameter, platform.radius
    W = min(LANE_DIAMETERS * d, size / lanes)
    bottom = -lanes * W / 2
    ys = bottom + W * (np.arange(lanes) + 0.5)
    x_lo, x_hi = -half + W / 2, half - W / 2
    points, walls = [], []
    for k, y in enumerate(ys):
        a, b = (x_lo, x_hi) if k % 2 == 0 else (x_hi, x_lo)
        points += [(a, y), (b, y)]
        if k < lanes - 1:
            wall_y = bottom + W * (k + 1)
            walls.append([[-half, wall_y], [half - W, wall_y]] if k % 2 == 0 else [[-half + W, wall_y], [half, wall_y]])
    inner = len(walls)
    if -bottom < half - 1e-9:  # the band's outer walls, across the whole arena
        walls += [[[-half, bottom], [half, bottom]], [[-half, -bottom], [half, -bottom]]]
    line = np.array(points, dtype=float)
    walls_arr = np.array(walls, dtype=float).reshape(-1, 2, 2)
    # gates along the centre line
    seg = np.diff(line, axis=0)
    seg_len = np.linalg.norm(seg, axis=1)
    cum = np.concatenate([[0.0], np.cumsum(seg_len)])
    spacing, offset = gate_spacing(platform), GATE_OFFSET_DIAMETERS * d
    relays: list[np.ndarray] = []
    cell = 2.4 * r  # relays in cells two or more apart are farther than 2.4 radii from each other
    cells: dict[tuple[int, int], list[int]] = {}
    s = W / 2 + spacing
    while s <= cum[-1] - spacing + 1e-9:
        i = min(int(np.searchsorted(cum, s, side="right")) - 1, len(seg) - 1)
        if seg_len[i] > 0:
            direction = seg[i] / seg_len[i]
            centre = line[i] + (s - cum[i]) * direction
            normal = np.array([-direction[1], direction[0]])
            for side in (1.0, -1.0):
                p = centre + side * offset * normal
                cx, cy = int(math.floor(p[0] / cell)), int(math.floor(p[1] / cell))
                near = [relays[k] for nx in (cx - 1, cx, cx + 1) for ny in (cy - 1, cy, cy + 1) for k in cells.get((nx, ny), ())]
                # keep relays inside their lane, clear of the walls and of each other
                if np.all(np.abs(p) <= half - r * 1.2) and distance_to_segments(p, walls_arr) > 1.2 * r and all(
                    np.linalg.norm(p - q) > 2.4 * r for q in near
                ):
                    cells.setdefault((cx, cy), []).append(len(relays))
                    relays.append(p)
        s += spacing
    goal = line[-1].copy()
    # shortest-path waypoints: each wall's free end, one radius beyond it
    nodes = []
    for k, (a, b) in enumerate(walls_arr[:inner]):
        end = b if k % 2 == 0 else a
        nodes.append(end + np.array([r if k % 2 == 0 else -r, 0.0]))
    nodes_arr = np.array(nodes, dtype=float).reshape(-1, 2)
    node_distance = _dijkstra_to_goal(nodes_arr, goal, walls_arr)
    return Corridor(W, walls_arr, line, np.array(relays, dtype=float).reshape(-1, 2), goal, line[0].copy(), nodes_arr, node_distance)


def _dijkstra_to_goal(nodes: np.ndarray, goal: np.ndarray, walls: np.ndarray) -> np.ndarray:
    """(K,) shortest distance from each node to ``goal`` over straight hops between mutually visible points."""
    points = np.concatenate([goal[None], nodes])
    n = len(points)
    starts = np.repeat(points, n, axis=0).reshape(n, n, 2)
    ends = np.broadcast_to(points, (n, n, 2))
    visible = ~segments_crossed(starts, ends, walls)
    length = np.linalg.norm(starts - ends, axis=-1)
    best = np.full(n, np.inf)
    best[0] = 0.0
    queue = [(0.0, 0)]
    while queue:
        dist, i = heapq.heappop(queue)
        if dist > best[i]:
            continue
        for j in np.flatnonzero(visible[i]):
            if dist + length[i, j] < best[j]:
                best[j] = dist + length[i, j]
                heapq.heappush(queue, (best[j], j))
    return best[1:]


class MidAngleNavigationTask(Task):
    """Mid-angle navigation rewards, metrics, corridor and relay firmware over all env copies (module docstring)."""

    SETTINGS = {
        "n_robots": Default(1, help="number of seekers (agents)"),
        "platform": "rone",
        "observe_ids": True,
        "message_bits": Int(
            4, "payload bits; the static robots broadcast their hop count to the goal in them", low=1, high=MAX_HOP_BITS,
            why=f"at least 1: the relays' hop counts travel in the payload; at most {MAX_HOP_BITS}: a hop count, and 2**b - 1 "
            "for 'unknown', is a signed 64-bit integer",
            help="payload bits b of every robot's messages: the static robots' hop counts (1 to 63: a hop count is a 64-bit integer); a seeker sends its action's bits",
        ),
        "arena_size": Real(
            None, low=0.0, low_open=True, high=10_000.0, allow_none=True, unit="of metres",
            why="None: 2.5 message ranges (r-one 2.5 m), or lanes x 6 robot diameters if larger. Checked when the env is "
            "built (mid_angle_navigation_v0.arena_size_range): at least 10.2 robot diameters with one lane (the start "
            f"square beyond the goal's arrival radius; {_SIZE_RANGES['low']}), lanes x 4.5 diameters with more; at most "
            f"the side whose corridor holds {MAX_STATIC_ROBOTS:,} static robots ({_SIZE_RANGES['high']} with one lane; "
            "1/lanes of that with more), where make() + reset() take ~1-2 s and the relays' hop-count memory 96 MB per copy",
            help='side (m); ``None``: 2.5 message ranges (r-one 2.5 m), or ``lanes`` x 6 robot diameters if larger; only ``"square"`` arenas; at least 10.2 robot diameters with one lane (no seeker starts within the arrival radius), ``lanes`` x 4.5 diameters with more, and at most the side whose corridor holds 2,000 static robots (one lane: r-one 401 m; ``arena_size_range(platform, lanes)``)',
        ),
        "max_cycles": 600,
        "lanes": Int(1, "corridor lanes (1: a straight corridor)", low=1, high=12,
                     why="each lane is 6 robot diameters wide and the default arena grows with the lanes; 12 lanes already make a 7.9 m r-one arena",
                     help="corridor lanes: 1 a straight corridor, more a winding one (each lane turns into the next behind a wall)"),
        "arrival_bonus": reward_weight(1.0, "reward of a seeker's arrival at the goal", help="reward of a seeker's arrival"),
        "collision_penalty": reward_weight(0.01, "weight of a seeker's contact per step", help="reward subtracted per step a seeker is in contact"),
    }
    METRICS = {"success_rate": "final", "time_to_goal": "final", "path_ratio": "final", "collision_fraction": "mean"}
    HEADLINE = ("success_rate", +1)
    SCRIPTED_POLICY = "swarm_envs.agents.scripted:MidAngleNavigation"

    def __init__(self, config: dict[str, Any], platform: Platform, n_copies: int = 1) -> None:
        super().__init__(config, platform, n_copies)
        B, A = self.n_copies, self.n_agents
        self.hop_levels = 2 ** int(config["message_bits"])  # hop counts 0 .. 2**b - 2; 2**b - 1 is "unknown"
        # per static robot and static sender: the hop count last decoded from it, the last one two frames in a
        # row agreed on, and the step of that agreement
        self._last_hop = np.full((B, self.n_static, self.n_static), -1, dtype=np.int64)
        self._hop_of = np.zeros((B, self.n_static, self.n_static), dtype=np.int64)
        self._heard_at = np.full((B, self.n_static, self.n_static), -(10**9), dtype=np.int64)
        self._clock = np.zeros(B, dtype=np.int64)
        self._arrived = np.zeros((B, A), dtype=bool)
        self._arrival_time = np.zeros((B, A))
        self._travelled = np.zeros((B, A))
        self._path_at_arrival = np.zeros((B, A))
        self._previous = np.zeros((B, A, 2))
        self._previous_distance = np.zeros((B, A))
        self._shortest = np.ones((B, A))

    # -- layout -------------------------------------------------------------------------------------------
    def _size(self) -> float:
        size = self.config["arena_size"]
        if size is not None:
            return float(size)
        # lanes of 6 diameters, at least 2.5 message ranges long (the goal out of the start's sight), and at
        # least the smallest side the corridor is built for (a platform of your own with a short IR range)
        lanes, platform = self.config["lanes"], self.platform
        return max(lanes * LANE_DIAMETERS * platform.diameter, 2.5 * message_range(platform), arena_size_range(platform, lanes)[0])

    def _check_size(self, size: float) -> None:
        """:class:`SettingsError` naming ``arena_size`` when the corridor cannot be built for a side of ``size`` (m)."""
        lanes, platform = self.config["lanes"], self.platform
        low, high = arena_size_range(platform, lanes)
        if low <= size <= high:
            return
        if size < low:
            why = (
                f"lanes at least {MIN_LANE_DIAMETERS} robot diameters wide" if lanes > 1 else
                f"the start square must lie beyond the goal's arrival radius of {ARRIVAL_RADII} robot radii, and lanes at least "
                f"{MIN_LANE_DIAMETERS} diameters wide"
            )
        else:
            why = (
                f"the corridor holds at most {MAX_STATIC_ROBOTS:,} static robots, the goal and 2 relays per gate; make() time and "
                "the relays' hop-count memory grow with their number squared"
            )
        key = "arena_size" if self.config["arena_size"] is not None else "platform"
        raise SettingsError(
            key, f"arena_size={size:g} m is out of range for MidAngleNavigation with {lanes} lane(s) on {platform.name!r}: "
            f"allowed [{low:g}, {high:g}] m ({why})"
        )

    @property
    def corridor(self) -> Corridor:
        """The corridor of this env (built once from the settings, after checking that the arena fits it)."""
        if getattr(self, "_corridor", None) is None:
            size = self._size()
            self._check_size(size)
            self._corridor = corridor(size, self.config["lanes"], self.platform)
        return self._corridor

    def n_static_robots(self) -> int:
        return 1 + len(self.corridor.relays)  # the goal, then the relays

    def default_arena_size(self) -> float:
        return self._size()

    def obstacles(self) -> np.ndarray:
        return self.corridor.walls

    def start_square(self) -> Arena:
        """The square (side a lane width minus 0.2 radii, centred on :attr:`Corridor.start_centre`) the seekers start in."""
        return Arena("square", self.corridor.lane_width - 2 * START_INSET_RADII * self.platform.radius)

    def check_layout(self) -> None:
        if self.config["arena"] != "square":
            raise SettingsError("arena", "MidAngleNavigation's corridor needs arena='square'")
        region = self.start_square()
        try:
            check_capacity(self.n_agents, self.platform.radius, region)
        except ValueError:
            wider = " or a larger arena_size" if self.corridor.lane_width < LANE_DIAMETERS * self.platform.diameter else ""
            raise SettingsError(
                "n_robots", f"{self.n_agents} seekers do not fit in the start square of side {region.size:.3f} m; use fewer seekers{wider}"
            ) from None

    def spawn(self, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        c, r = self.corridor, self.platform.radius
        spacing = gate_spacing(self.platform)
        nominal = np.concatenate([c.goal[None], c.relays])
        static = nominal + np.concatenate([np.zeros((1, 2)), rng.uniform(-0.1, 0.1, c.relays.shape) * spacing])  # a little jitter
        # a jittered relay must stay clear of the walls, the arena and the others; else it stands where nominal
        ok = (distance_to_segments(static, c.walls) > 1.05 * r) & np.all(np.abs(static) <= self.arena.half - 1.05 * r, axis=1)
        static = np.where(ok[:, None], static, nominal)
        for _ in range(len(static)):  # nominal positions are 2.4 radii apart: revert close pairs until none is left
            pairs = cKDTree(static).query_pairs(2.2 * r * (1 + 1e-9), output_type="ndarray")  # a superset of the close pairs
            pairs = pairs[np.linalg.norm(static[pairs[:, 0]] - static[pairs[:, 1]], axis=-1) < 2.2 * r]
            close = np.zeros(len(static), dtype=bool)
            close[pairs.reshape(-1)] = True
            close &= np.any(static != nominal, axis=1)
            if not close.any():
                break
            static[close] = nominal[close]
        seekers = spawn_positions(rng, self.n_agents, r, self.start_square()) + c.start_centre
        return np.concatenate([static, seekers]), rng.uniform(-np.pi, np.pi, self.n_world)

    def markers(self, positions: np.ndarray) -> dict[str, np.ndarray]:
        return {"goal": positions[0], "centroid": positions[self.n_static :].mean(axis=0)}  # the seekers' centroid

    # -- the static robots' firmware: hop counts to the goal ----------------------------------------------
    def static_messages(self, observations: dict[str, np.ndarray], first: np.ndarray) -> np.ndarray:
        B, S, b = self.n_copies, self.n_static, self.config["message_bits"]
        self._heard_at[first] = -(10**9)
        self._last_hop[first] = -1
        self._clock[first] = 0
        self._clock[~first] += 1
        messages, ids = observations["messages"], observations["message_ids"]
        values = (messages[..., 2 : 2 + b] > 0.5).astype(np.int64) @ (1 << np.arange(b))  # (B, S, M)
        sender = np.rint(ids[..., 1] * max(self.n_world - 1, 1)).astype(np.int64)
        good = (messages[..., 0] > 0.5) & (ids[..., 0] > 0.5) & (sender < S) & ((sender == 0) == (values == 0))
        for m in range(messages.shape[2]):  # rows in turn: one frame per sender and row
            bb, ss = np.nonzero(good[:, :, m])
            who, value = sender[bb, ss, m], values[bb, ss, m]
            agreed = self._last_hop[bb, ss, who] == value  # two frames in a row with this value: accepted
            self._hop_of[bb[agreed], ss[agreed], who[agreed]] = value[agreed]
            self._heard_at[bb[agreed], ss[agreed], who[agreed]] = self._clock[bb[agreed]]
            self._last_hop[bb, ss, who] = value
        fresh = self._clock[:, None, None] - self._heard_at <= HOP_MEMORY_STEPS  # (B, S, senders)
        lowest = np.where(fresh, self._hop_of, self.hop_levels - 1).min(axis=2)
        hops = np.minimum(lowest, self.hop_levels - 2) + 1  # at most 2**b - 1, without overflowing at b = 63
        hops[:, 0] = 0  # the goal
        return ((hops[..., None] >> np.arange(b)) & 1).astype(bool)

    # -- rewards and metrics --------------------------------------------------------------------------------
    def rewards(self, state: BatchState, first: np.ndarray):
        B, A = self.n_copies, self.n_agents
        c, r = self.corridor, self.platform.radius
        pos = self.agents_of(state.positions)
        goal = state.positions[:, 0]
        reach = ARRIVAL_RADII * r
        distance = c.distance_to_goal(pos)  # (B, A) around the walls
        if first.any():
            self._arrived[first] = False
            self._arrival_time[first] = 0.0
            self._travelled[first] = 0.0
            self._path_at_arrival[first] = 0.0
            self._previous[first] = pos[first]
            self._previous_distance[first] = distance[first]
            self._shortest[first] = np.maximum(distance[first] - 2 * r, 1e-9)
        self._travelled += np.linalg.norm(pos - self._previous, axis=-1)
        self._previous = pos.copy()
        elapsed = (state.num_cycles * DT)[:, None]
        there = np.linalg.norm(pos - goal[:, None], axis=-1) <= reach
        new = there & ~self._arrived
        self._arrived |= there
        self._arrival_time = np.where(new, elapsed, self._arrival_time)
        self._path_at_arrival = np.where(new, self._travelled, self._path_at_arrival)
        progress = (self._previous_distance - distance) / np.maximum(self._shortest, 1e-9)
        self._previous_distance = distance
        bumped = bump_any(self.agents_of(state.bumps))
        done = self._arrived & ~new  # after arrival a seeker's reward is 0
        own = np.where(done, 0.0, progress) + self.config["arrival_bonus"] * new - self.config["collision_penalty"] * bumped
        rewards = np.repeat(own.mean(axis=1)[:, None], A, axis=1) if self.reward_mode == "global" else own
        n_arrived = self._arrived.sum(axis=1)
        time_to_goal = np.where(self._arrived, self._arrival_time, elapsed).mean(axis=1)
        with np.errstate(invalid="ignore", divide="ignore"):
            path_ratio = np.where(n_arrived > 0, (self._path_at_arrival / self._shortest * self._arrived).sum(axis=1) / n_arrived, np.nan)
        metrics = {
            "success_rate": n_arrived / A,
            "time_to_goal": time_to_goal,
            "path_ratio": path_ratio,
            "collision_fraction": bumped.mean(axis=1),
        }
        terms = {"progress": progress, "arrived": self._arrived.astype(float), "collision": bumped.astype(float)}
        return rewards, terms, metrics


_DOC = """Create the mid-angle navigation environment (a native PettingZoo ``ParallelEnv``).

## Description

Mid-angle navigation ([L] Sec. 6.4.4, Algorithm 8, Fig. 6.10): ``n_robots`` seekers (the agents,
``robot_0`` ..) start at one end of a winding corridor of ``lanes`` lanes and should reach the goal
robot at the other end. The corridor's walls stop robots and block infrared light, so the goal is out
of sight at the start. Static relays stand in gates (pairs across the corridor) along its centre line
and broadcast their hop count to the goal over SwarmCom (goal 0, "unknown" = 2**b - 1); the goal is
static robot 0. Static robots are not agents.

## Rewards

Per seeker: its progress this step along the shortest path to the goal (around the walls' ends) over
that path's length at the start, ``arrival_bonus`` when it arrives (centre within 2.5 radii of the
goal's), nothing after that, minus ``collision_penalty`` while it is in contact. ``reward_mode="global"``:
the mean over seekers; ``"local"``: each its own. Terms in ``infos[agent]["reward_terms"][name]``:
``progress``, ``arrived``, ``collision``. Metrics in ``infos[agent]["metrics"][name]``:
``success_rate`` (headline: share of seekers that arrived), ``time_to_goal`` (s; the elapsed time for a
seeker not there yet), ``path_ratio`` (path driven until arrival over the shortest path; NaN while no
seeker arrived), ``collision_fraction``.

## Starting State

The relays stand at their gate positions with a uniform jitter of +-10 % of the gate spacing, the goal
at the corridor's end; the seekers are placed uniformly at random without overlap in the lane-wide
start square at the other end. Headings are uniform in [-pi, pi). ``reset(seed=..., options={"positions":
(n_world, 2) m, "headings": (n_world,) rad})`` places every robot exactly (static robots first).

## Episode End

No termination (an arrived seeker may stay or leave). Truncation: every agent is truncated after
``max_cycles`` steps (default 600 = 60 s); ``env.agents`` is then empty.

## Version History

- v0: initial release (swarm_envs 0.1.0).
"""

raw_env, parallel_env, env = task_module(MidAngleNavigationTask, _DOC, payload="payload bits (a static robot's hop count to the goal, LSB first)")
MidAngleNavigationEnv = raw_env
