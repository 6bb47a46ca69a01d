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

from typing import Any

import numpy as np

from swarm_envs.tasks.factories import task_module
from swarm_envs.tasks.task import Arena, BatchState, Default, Int, Platform, Real, Task, bump_any, message_range, spawn_positions, reward_weight

__all__ = ["SortedFollowingTask", "SortedFollowingEnv", "raw_env", "parallel_env", "env"]


class SortedFollowingTask(Task):
    """Sorted-following rewards and metrics over all env copies (module docstring)."""

    SETTINGS = {
        "n_robots": Default(5, help='number of agents (ids 0 .. N-1; the behaviour "typically works best with a group of 3-6 robots" '
                                    "[L Sec. 6.4.2])"),
        "platform": "rone",
        "observe_ids": True,
        "message_bits": Default(1, help="payload bits b an agent sends through its action: with b > 0 every robot broadcasts "
                                "continuously, and each decoded frame refreshes its neighbours' bearing of it (0: only the 2.4 s bearing beacons)"),
        "arena_size": Default(None, help="side or diameter (m); ``None``: three message ranges (r-one 3 m), or the platform's spacing x "
                                "sqrt(robots) if larger"),
        "follow_distance": Real(None, "predecessor distance that counts as following; None: half the message range", low=0.0,
                                low_open=True, high=100.0, allow_none=True, unit="m",
                                why="at most 100 m: a distance beyond every arena the defaults build; larger values only count more pairs",
                                help="predecessor distance (m) that counts as following; ``None``: half the platform's reliable message range (r-one 0.5 m)"),
        "remove_leader_at": Int(0, "control step at which the leader (id 0) is switched off; 0: never", low=0, high=10**9,
                                why="a control step, bounded like max_cycles",
                                help="control step at which the leader (id 0) is switched off; 0: never"),
        "speed_weight": reward_weight(0.5, "weight of the mean speed fraction in the reward", help="weight of the mean speed fraction in the reward"),
        "collision_penalty": reward_weight(0.1, "weight of the fraction of robots bumping", help="weight of the fraction of robots bumping, subtracted from the reward"),
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


_DOC = """Create the sorted-following environment (a native PettingZoo ``ParallelEnv``).

## Description

Sorted following ([L] Sec. 6.4.2, Algorithm 6, Fig. 6.8): ``n_robots`` robots with ids 0 .. N-1
(``robot_i`` has id i) should form a line sorted by id behind the lowest id, which leads and avoids
obstacles. ``remove_leader_at`` > 0 switches the leader off at that control step (it stops, emits and
detects no infrared, its body stays where it stopped): the next lowest id should take over.

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

## Version History

- v0: initial release (swarm_envs 0.1.0).
"""

raw_env, parallel_env, env = task_module(SortedFollowingTask, _DOC)
SortedFollowingEnv = raw_env
