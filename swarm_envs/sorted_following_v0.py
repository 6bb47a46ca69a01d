"""Sorted following: robots form a line in the order of their ids behind the lowest id [L Sec. 6.4.2, Alg. 6].

The robot with the lowest id in the swarm leads and avoids obstacles; every other robot follows a
neighbour with a lower id, so the swarm forms a line sorted by id (Fig. 6.8). When the leader is removed
(``remove_leader_at``: it is switched off -- it stops, emits and detects no infrared, its body stays) the
next lowest id leads. Robot ``robot_i`` has id ``i``; the robots read the ids their sensing decoded
(``observe_ids``, on by default).

Metrics (ground truth, over the robots that are switched on): a robot *follows* when the robot with the
next lower id (its predecessor) is within ``follow_distance`` of it and ahead of it (the predecessor's
centre lies in front of the robot's heading); ``following_fraction`` = followers / (robots - 1);
``line_order`` = the share of the robots after the leader that form an unbroken line from it (robot
k + 1 follows k for every k up to them); ``collision_fraction`` = share of robots in contact;
``mean_speed`` = mean speed / max speed.
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
from pettingzoo import AECEnv
from pettingzoo.utils.conversions import parallel_to_aec

from swarm_envs.env import SwarmEnv
from swarm_envs.factories import reports_unknown_kwargs
from swarm_envs.platforms import Platform
from swarm_envs.task import Arena, BatchState, Int, Real, Task, bump_any, message_range, spawn_positions

__all__ = ["SortedFollowingTask", "SortedFollowingEnv", "raw_env", "parallel_env", "env"]


class SortedFollowingTask(Task):
    """Sorted-following rewards and metrics over all env copies (module docstring)."""

    SETTINGS = {
        "n_robots": 5,
        "platform": "rone",
        "observe_ids": True,
        "message_bits": 1,
        "follow_distance": Real(None, "predecessor distance that counts as following; None: half the message range", low=0.0,
                                low_open=True, high=100.0, allow_none=True, unit="m",
                                why="at most 100 m: a distance beyond every arena the defaults build; larger values only count more pairs"),
        "remove_leader_at": Int(0, "control step at which the leader (id 0) is switched off; 0: never", low=0, high=10**9,
                                why="a control step, bounded like max_cycles"),
        "speed_weight": Real(0.5, "weight of the mean speed fraction in the reward", low=0.0, high=1000.0, why="a reward weight; rewards stay within +-1000 per step"),
        "collision_penalty": Real(0.1, "weight of the fraction of robots bumping", low=0.0, high=1000.0, why="a reward weight; rewards stay within +-1000 per step"),
    }
    METRICS = {"following_fraction": "mean", "line_order": "mean", "collision_fraction": "mean", "mean_speed": "mean"}
    HEADLINE = ("following_fraction", +1)
    SCRIPTED_POLICY = "swarm_envs.agents.scripted:SortedFollowing"

    def __init__(self, config: dict[str, Any], platform: Platform, n_copies: int = 1) -> None:
        super().__init__(config, platform, n_copies)
        given = config["follow_distance"]
        #: distance (m) within which a robot's predecessor counts as followed
        self.follow_distance = 0.5 * message_range(platform) if given is None else float(given)
        self.remove_leader_at = int(config["remove_leader_at"])

    def default_arena_size(self) -> float:
        # room for a line of robots to travel: three message ranges, or the platform spacing rule if larger
        return max(super().default_arena_size(), 3.0 * message_range(self.platform))

    def start_region(self) -> Arena:
        """The square (centred on the arena) the robots start in: half a message range, or more room for
        many robots, so that they start within sensing range of each other; the whole arena when that square
        would reach past its walls (a small arena, or a circle too small for the square inside it)."""
        side = min(max(0.5 * message_range(self.platform), 4.0 * self.platform.diameter * np.sqrt(self.n_world)), self.arena.size)
        r = self.platform.radius
        if self.arena.shape == "circle" and np.sqrt(2.0) * (side / 2 - r) > self.arena.half - r:
            return self.arena  # the build's fit test covers the whole arena
        return Arena("square", side)

    def spawn(self, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        positions = spawn_positions(rng, self.n_world, self.platform.radius, self.arena, region=self.start_region())
        return positions, rng.uniform(-np.pi, np.pi, self.n_world)

    def switched_off(self, num_cycles: np.ndarray) -> np.ndarray | None:
        if self.remove_leader_at <= 0:
            return None
        off = np.zeros((self.n_copies, self.n_world), dtype=bool)
        off[:, 0] = num_cycles >= self.remove_leader_at
        return off

    def alive(self, num_cycles: np.ndarray) -> np.ndarray:
        """(B, n_world) bool robots switched on at steps ``num_cycles`` (B,)."""
        off = self.switched_off(num_cycles)
        return np.ones((self.n_copies, self.n_world), dtype=bool) if off is None else ~off

    def following(self, positions: np.ndarray, headings: np.ndarray, alive: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(follows (B, N) bool, has_predecessor (B, N) bool): robot u's predecessor is the switched-on robot
        with the next lower id; u follows when it is within ``follow_distance`` and ahead of u."""
        B, N = alive.shape
        ids = np.broadcast_to(np.arange(N), (B, N))
        # the predecessor: the largest switched-on id below u (running maximum of the switched-on ids)
        last_alive = np.maximum.accumulate(np.where(alive, ids, -1), axis=1)
        pred = np.concatenate([np.full((B, 1), -1), last_alive[:, :-1]], axis=1)
        has = alive & (pred >= 0)
        p = np.take_along_axis(positions, np.maximum(pred, 0)[..., None], axis=1)
        delta = p - positions
        dist = np.linalg.norm(delta, axis=-1)
        ahead = delta[..., 0] * np.cos(headings) + delta[..., 1] * np.sin(headings) > 0
        return has & (dist <= self.follow_distance) & ahead, has

    def robot_groups(self) -> tuple[np.ndarray, tuple[str, str]]:
        """The lowest id (the first leader) in the second colour (drawing only)."""
        return (np.arange(self.n_world) == 0).astype(int), ("follower", "lowest id (leads)")

    def rewards(self, state: BatchState, first: np.ndarray):
        B, A = self.n_copies, self.n_agents
        pos, head = self.agents_of(state.positions), self.agents_of(state.headings)
        alive = self.agents_of(self.alive(state.num_cycles))
        follows, has = self.following(pos, head, alive)
        n_followers = np.maximum(has.sum(axis=1), 1)
        following_fraction = follows.sum(axis=1) / n_followers
        # the unbroken line from the leader: followers in id order until the first one that does not follow
        broken = np.cumsum(has & ~follows, axis=1) > 0
        line_order = (follows & ~broken).sum(axis=1) / n_followers
        bumped = bump_any(self.agents_of(state.bumps)) & alive
        n_alive = np.maximum(alive.sum(axis=1), 1)
        collision_fraction = bumped.sum(axis=1) / n_alive
        speed = np.clip(np.linalg.norm(self.agents_of(state.velocities), axis=2) / self.platform.max_speed, 0.0, 1.0) * alive
        mean_speed = speed.sum(axis=1) / n_alive
        w, c = self.config["speed_weight"], self.config["collision_penalty"]
        global_reward = following_fraction + w * mean_speed - c * collision_fraction
        # local: a follower is rewarded for following, the leader for moving; everyone for not bumping
        local_reward = np.where(has, follows.astype(float), w * speed) - c * bumped
        rewards = np.repeat(global_reward[:, None], A, axis=1) if self.reward_mode == "global" else local_reward
        terms = {"following": follows.astype(float), "speed": speed, "collision": bumped.astype(float)}
        metrics = {
            "following_fraction": following_fraction,
            "line_order": line_order,
            "collision_fraction": collision_fraction,
            "mean_speed": mean_speed,
        }
        return rewards * alive, terms, metrics

    def markers(self, positions: np.ndarray) -> dict[str, np.ndarray]:
        return {"centroid": positions[self.n_static :].mean(axis=0)}


class SortedFollowingEnv(SwarmEnv):
    """Sorted-following task; see the module docstring and :func:`parallel_env` for the kwargs."""

    metadata = {**SwarmEnv.metadata, "name": "sorted_following_v0"}
    TASK = SortedFollowingTask


raw_env = SortedFollowingEnv


@reports_unknown_kwargs
def parallel_env(
    *,
    n_robots: int = 5,
    follow_distance: float | None = None,
    remove_leader_at: int = 0,
    speed_weight: float = 0.5,
    collision_penalty: float = 0.1,
    platform: Literal["droplet", "epuck", "rone"] | Platform = "rone",
    sensing: Literal["full", "ideal"] = "full",
    max_cycles: int = 500,
    render_mode: Literal["rgb_array", "human"] | None = None,
    arena: Literal["square", "circle"] = "square",
    arena_size: float | None = None,
    reward_mode: Literal["global", "local"] = "global",
    flatten: bool = False,
    n_neighbours: int = 8,
    n_messages: int = 8,
    message_bits: int = 1,
    observe_ids: bool = True,
    bitrate: Literal[310, 650, 1080, 1160, 1250, 1670, 1800] | None = None,
    relative_threshold: float | None = None,
    code: tuple[int, int] = (15, 15),
    comm_mode: Literal["broadcast", "flooding"] = "broadcast",
    rb_schedule: Literal["timer", "contention", "every_step"] = "timer",
    rb_period: float = 1.0,
    rb_jitter: float = 0.2,
    rb_max_age: int | None = None,
    rb_noise: float | None = None,
    rb_near_model: bool = False,
    hw_variation: bool = True,
    hw_emitter_spread: float = 0.1,
    hw_detector_spread: float = 0.1,
    hw_angle_spread: float = 3.0,
    bearing_source: Literal["sectors", "range_bearing"] | None = None,
    bearing_noise: bool = True,
    exchange: Literal["network", "ideal"] = "network",
    scale_free_method: Literal["two_hop", "null_space"] = "two_hop",
    scale_free_k: int = 1,
    motion_noise: bool = True,
    physics_substeps: int | None = None,
) -> SortedFollowingEnv:
    """Create the sorted-following environment (a native PettingZoo ``ParallelEnv``).

    ## Description

    Sorted following ([L] Sec. 6.4.2, Algorithm 6, Fig. 6.8): ``n_robots`` robots with ids 0 .. N-1
    (``robot_i`` has id i) should form a line sorted by id behind the lowest id, which leads and avoids
    obstacles. ``remove_leader_at`` > 0 switches the leader off at that control step (it stops, emits and
    detects no infrared, its body stays where it stopped): the next lowest id should take over.

    ## Action Space

    Per agent ``Box(-1, 1, (2 + message_bits,), float32)``: linear and angular velocity as fractions of
    the platform's maxima (``Platform.max_speed`` m/s and ``Platform.max_angular_speed`` rad/s; the
    wheel speeds are then limited to ``max_speed`` and carry the platform's motion error, ``motion_noise``),
    followed by ``message_bits`` payload bits (each entry above 0 is a 1-bit),
    broadcast over SwarmCom whenever the robot's transmit queue is empty.
    Finite values outside [-1, 1] are clipped; NaN/inf, wrong shapes and actions for unknown or missing
    agents raise. Zero actions keep a robot still, also with the motion error (a switched-off robot ignores its actions).

    ## Observation Space

    Per agent a ``Dict`` of ``float32`` boxes, built only from the modelled infrared sensing stack
    (never from ground truth), with K = ``n_neighbours``, M = ``n_messages``, b = ``message_bits``:

    | key | shape | columns |
    |---|---|---|
    | ``range_bearing`` | (K, 7) | valid, range (m), cos bearing, sin bearing, cos heading, sin heading, age (steps) [F14] (r-one: sector bearings, range 0) |
    | ``messages`` | (M, 2 + b) | valid, sender bearing / pi, payload bits: SwarmCom messages decoded since the last step [T20] |
    | ``scale_free`` | (K, 3) | valid, x, y of neighbours in the robot's frame, mean neighbour distance 1, clipped to +-10 [L] |
    | ``rigid`` | (1,) | 1 when the scale-free coordinates are determined [L Sec. 5.5.1] |
    | ``proprio`` | (8 + 2 + b,) | bump flags of 8 45-degree sectors (sector 0 ahead, counter-clockwise), last action |
    | ``own_id`` | (2,) | own id / (N - 1), own id parity (``observe_ids``) |
    | ``range_bearing_ids``, ``scale_free_ids`` | (K, 4) | per row: an id was decoded, decoded id / (N - 1), id < own id, same parity |
    | ``message_ids`` | (M, 4) | the same per message row (the header's decoded origin) |

    Rows are sorted nearest first by *estimated* range; empty rows are all zero. The ids are those the
    sensing decoded (a corrupted frame names the wrong robot); ``observe_ids=False`` drops the id parts.
    ``flatten=True`` gives one ``Box`` instead (keys in sorted order; ``env.layout.unflatten(flat)`` gives
    the parts back).

    ## Rewards

    ``reward_mode="global"``: ``following_fraction + speed_weight x mean_speed - collision_penalty x
    collision_fraction``. A robot follows when its predecessor (the switched-on robot with the next lower
    id) is within ``follow_distance`` and ahead of it; ``following_fraction`` = followers / (robots - 1),
    ``mean_speed`` = mean speed / max speed, ``collision_fraction`` = share of robots in contact.
    ``"local"``: a follower gets 1 while it follows, the leader ``speed_weight x`` its speed fraction, each
    minus ``collision_penalty`` when it bumps. Switched-off robots get 0. Terms in
    ``infos[agent]["reward_terms"][name]``: ``following``, ``speed``, ``collision``. Metrics in
    ``infos[agent]["metrics"][name]``: ``following_fraction`` (headline), ``line_order`` (share of the
    followers in the unbroken sorted line from the leader), ``collision_fraction``, ``mean_speed``.

    ## Starting State

    Robots are placed uniformly at random without overlap in a square at the arena's centre of side half
    the platform's message range (more for many robots), so they start within sensing range of each
    other; in the whole arena when that square does not fit inside it (a small arena). Headings are uniform in [-pi, pi). ``reset(seed=..., options={"positions": (N, 2) m,
    "headings": (N,) rad})`` places the robots exactly instead.

    ## Episode End

    No termination. Truncation: every agent is truncated after ``max_cycles`` steps (default 500 = 50 s);
    ``env.agents`` is then empty.

    ## Arguments

    Keyword-only, SI units. Unknown names raise ``TypeError``; bad values raise ``ValueError``.

    | argument | default | meaning |
    |---|---|---|
    | ``n_robots`` | 5 | number of agents (ids 0 .. N-1; the behaviour "typically works best with a group of 3-6 robots" [L Sec. 6.4.2]) |
    | ``follow_distance`` | ``None`` | predecessor distance (m) that counts as following; ``None``: half the platform's reliable message range (r-one 0.5 m) |
    | ``remove_leader_at`` | 0 | control step at which the leader (id 0) is switched off; 0: never |
    | ``speed_weight`` | 0.5 | weight of the mean speed fraction in the reward |
    | ``collision_penalty`` | 0.1 | weight of the fraction of robots bumping, subtracted from the reward |
    | ``platform`` | ``"rone"`` | ``"droplet"`` (4.4 cm, 6 IR channels), ``"epuck"`` (7 cm, 8 sensors), ``"rone"`` (11 cm, 8 RX + 8 TX), or a ``Platform`` |
    | ``sensing`` | ``"full"`` | ``"full"``: the modelled IR stack; ``"ideal"``: exact, noiseless, lossless values (true ids) in the same layout |
    | ``max_cycles`` | 500 | control steps of 0.1 s per episode |
    | ``render_mode`` | ``None`` | ``"rgb_array"`` (headless) or ``"human"`` (window) |
    | ``arena`` | ``"square"`` | ``"square"`` or ``"circle"`` |
    | ``arena_size`` | ``None`` | side or diameter (m); ``None``: three message ranges (r-one 3 m), or the platform's spacing x sqrt(robots) if larger |
    | ``reward_mode`` | ``"global"`` | ``"global"`` (one team reward) or ``"local"`` (each robot its own term) |
    | ``flatten`` | ``False`` | one flat ``Box`` observation instead of the ``Dict`` |
    | ``n_neighbours`` | 8 | rows K of ``range_bearing`` and ``scale_free`` |
    | ``n_messages`` | 8 | rows M of ``messages`` |
    | ``message_bits`` | 1 | payload bits b an agent sends through its action: with b > 0 every robot broadcasts continuously, and each decoded frame refreshes its neighbours' bearing of it (0: only the 2.4 s bearing beacons) |
    | ``observe_ids`` | ``True`` | the robot's own id and the neighbour and sender ids its sensing decoded (``own_id``, ``*_ids`` parts) |
    | ``bitrate`` | ``None`` | SwarmCom bit rate (bps): ``None`` the platform's (e-puck 310 [T20], r-one 1250 [L Sec. 3.2.1], Droplet 310), or 310, 650, 1080, 1160, 1250, 1670, 1800 |
    | ``relative_threshold`` | ``None`` | detector threshold m_tr (ADC counts); ``None``: 5 on e-puck and r-one [T20], 8 on the Droplet |
    | ``code`` | ``(15, 15)`` | BCH code (n, k): ``(15, 15)`` uncoded, ``(15, 11)``, ``(15, 7)``, ``(15, 5)``, ``(15, 1)`` |
    | ``comm_mode`` | ``"broadcast"`` | ``"broadcast"`` or ``"flooding"`` [T20 Sec. 5] |
    | ``rb_schedule`` | ``"timer"`` | range & bearing firing: ``"timer"`` (each robot on its own timer, as the Droplet firmware: robots that see each other can collide), ``"contention"`` (oracle ablation: no two linked robots fire in one step) or ``"every_step"`` (idealised) |
    | ``rb_period`` | 1.0 | s between a robot's range & bearing firings (``"timer"``) |
    | ``rb_jitter`` | 0.2 | s, largest late start of a firing after its timer expires (uniform) |
    | ``rb_max_age`` | ``None`` | steps a range & bearing reading persists; ``None``: until the neighbour's next timer firing is due (13 at the defaults) |
    | ``rb_noise`` | ``None`` | ADC noise sigma (counts); ``None``: 2 on the Droplet, sqrt(2.5) on the e-puck |
    | ``rb_near_model`` | ``False`` | Droplet only: the firmware's low-power near-range fit instead of the power ladder |
    | ``hw_variation`` | ``True`` | droplet / epuck: each robot's emitter powers, detector gains and axis angles drawn at reset (the range & bearing estimator keeps the nominal calibration) |
    | ``hw_emitter_spread`` | 0.1 | standard deviation of ln(emitter power multiplier) (an assumption) |
    | ``hw_detector_spread`` | 0.1 | standard deviation of ln(detector gain multiplier) (an assumption) |
    | ``hw_angle_spread`` | 3.0 | degrees, standard deviation of each emitter's and detector's axis angle (an assumption) |
    | ``bearing_source`` | ``None`` | ``"sectors"`` (r-one) or ``"range_bearing"``; ``None``: sectors on the r-one, R&B elsewhere |
    | ``bearing_noise`` | ``True`` | r-one: sector readings with each robot's own receiver arcs, drawn at reset from the measured 63-74 degree spread, mean 68 [L Sec. 3.2.1] |
    | ``exchange`` | ``"network"`` | bearing lists for scale-free coordinates over SwarmCom (``"network"``) or ``"ideal"`` |
    | ``scale_free_method`` | ``"two_hop"`` | ``"two_hop"`` [L Algs. 1-4] or ``"null_space"`` [L Eq. (5.1)] (slow) |
    | ``scale_free_k`` | 1 | hops k of the null-space method |
    | ``motion_noise`` | ``True`` | the platform's motion error: per-wheel speed gains drawn per episode, per-step wheel-speed noise, the r-one's 15 mm/s dead zone [L Sec. 3.1] (``docs/design.md#motion-error``); ``False``: exact differential-drive kinematics |
    | ``physics_substeps`` | ``None`` | pymunk sub-steps per control step; ``None``: the platform's (8 Droplet, 21 e-puck, 32 r-one), at which robots overlap by at most 2 % of a diameter at the default arena size |

    ## Version History

    - v0: initial release (swarm_envs 0.1.0).
    """
    return SortedFollowingEnv(**locals())  # every argument above, by name


def env(**kwargs: Any) -> AECEnv:
    """The AEC (turn-based) view of :func:`parallel_env` (PettingZoo ``parallel_to_aec``); same keyword arguments."""
    return parallel_to_aec(parallel_env(**kwargs))
