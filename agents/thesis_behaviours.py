"""The scripted r-one behaviours of Lynch's thesis [L Sec. 6.4]: sorted following (Alg. 6), parity clustering
(Alg. 7) and mid-angle navigation (Alg. 8), on decoded ids, hop counts and bearings, with the departures
docs/design.md lists."""

from __future__ import annotations
import numpy as np
from swarm_envs.sensing.observation import ObservationLayout
from swarm_envs.sim.platforms import Platform
from swarm_envs.sim.control import DT
from swarm_envs.agents.scripted_base import ScriptedPolicy, circular_mean, decoded_ids, require_ids

__all__ = ["SortedFollowing", "ParityClustering", "MidAngleNavigation"]


class SortedFollowing(ScriptedPolicy):
    """[L] Alg. 6 sorted following on the decoded ids (``observe_ids=True``).

    For each neighbour v of the robot's ``range_bearing`` rows (its decoded id ``id(v)``): the first with
    ``id(v) < id(u)`` is followed -- ``PoseSet(tv = speed, heading = theta(v))`` -- and a bump turns the
    robot away; with no lower id in sight the robot is the leader: it drives straight at ``leader_speed``
    and ``AvoidIRObstacle``s (turns away from a neighbour ahead within ``avoid_range`` m, or, without
    range as on the r-one, within a 30-degree cone, and from bumps). Alg. 6 breaks at the first lower id
    of N(u) without saying in which order N(u) is read; ``pick="next_lower"`` (default) reads it from the
    highest id down, so the first lower id is the next lower one and the robots line up in id order as
    the thesis describes ("the second lowest ID robot will follow the lowest ID robot ... in sorted
    order"); ``pick="nearest"`` reads the rows nearest first. ``odometry`` (default on) turns each bearing
    back by the robot's own rotation since the reading was measured (``_current_bearings``).
    """

    name = "sorted_following"

    def __init__(self, platform: Platform, layout: ObservationLayout, rng: np.random.Generator | None = None,
                 speed: float = 0.3, leader_speed: float = 0.2, gain: float = 0.5, avoid_range: float = 0.15,
                 pick: str = "next_lower", odometry: bool = True, t_m: float = 2.0) -> None:
        if pick not in ("next_lower", "nearest"):
            raise ValueError(f"pick must be 'next_lower' or 'nearest', got {pick!r}")
        self.speed, self.leader_speed, self.gain, self.avoid_range, self.pick = float(speed), float(leader_speed), float(gain), float(avoid_range), pick
        self.odometry = bool(odometry)
        super().__init__(platform, layout, rng, t_m)

    def act_batch(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        require_ids(obs, "SortedFollowing")
        rb = obs["range_bearing"]
        n = len(rb)
        self._ensure(n)
        n_world = self.layout.n_world
        own = np.rint(obs["own_id"][:, 0] * max(n_world - 1, 1)).astype(np.int64)
        ids = decoded_ids(obs["range_bearing_ids"], n_world)
        valid = (rb[..., 0] > 0.5) & (ids >= 0)
        lower = valid & (ids < own[:, None])
        following = lower.any(axis=1)
        if self.pick == "next_lower":
            row = np.where(lower, ids, -1).argmax(axis=1)
        else:
            row = lower.argmax(axis=1)  # the first lower id, nearest first
        current = self._current_bearings(rb, self._rotation_since(obs)) if self.odometry else np.arctan2(rb[..., 3], rb[..., 2])
        theta = current[np.arange(n), row]
        lin = np.where(following, self.speed, self.leader_speed)
        ang = np.where(following, self.turn_towards(theta, self.gain), 0.0)
        # the leader's AvoidIRObstacle: turn away from a neighbour ahead (closer than avoid_range where the
        # readings have a range), and from bumps below
        bearing = np.arctan2(rb[..., 3], rb[..., 2])
        has_range = rb[..., 1] > 0
        ahead = valid & (np.abs(bearing) < np.pi / 6) & (~has_range | (rb[..., 1] < self.avoid_range))
        away, has_ahead = circular_mean(rb[..., 2], rb[..., 3], ahead)
        avoid = ~following & has_ahead
        ang = np.where(avoid, -np.sign(away + 1e-12), ang)
        escaping, e_lin, e_ang = self._bump_escape(obs["proprio"])
        lin, ang = np.where(escaping, e_lin, lin), np.where(escaping, e_ang, ang)
        return self.compose(lin, ang)


class ParityClustering(ScriptedPolicy):
    """[L] Alg. 7 clustering by id parity on the decoded ids (``observe_ids=True``).

    ``theta_avg`` = circular mean of the bearings of the ``range_bearing`` neighbours whose decoded id has
    the robot's parity (the id parts' "same parity" column); ``PoseSet(tv = speed, heading = theta_avg)``;
    bump -> turn away; the robot never stops ([L]: "the robots never stop in the cluster"). With no
    same-parity neighbour Alg. 7 sets no pose (the robot keeps its last one); here it random-walks
    ([T20] Alg. 1) to find one, as the suite's other controllers do. ``odometry`` (default on) turns each
    bearing back by the robot's own rotation since the reading was measured (``_current_bearings``).
    """

    name = "parity_clustering"

    def __init__(self, platform: Platform, layout: ObservationLayout, rng: np.random.Generator | None = None,
                 speed: float = 0.6, gain: float = 0.5, odometry: bool = True, t_m: float = 2.0) -> None:
        self.speed, self.gain, self.odometry = float(speed), float(gain), bool(odometry)
        super().__init__(platform, layout, rng, t_m)

    def act_batch(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        require_ids(obs, "ParityClustering")
        rb, id_rows = obs["range_bearing"], obs["range_bearing_ids"]
        n = len(rb)
        self._ensure(n)
        same = (rb[..., 0] > 0.5) & (id_rows[..., 0] > 0.5) & (id_rows[..., 3] > 0.5)
        bearing = self._current_bearings(rb, self._rotation_since(obs)) if self.odometry else np.arctan2(rb[..., 3], rb[..., 2])
        theta, follow = circular_mean(np.cos(bearing), np.sin(bearing), same)
        lin = np.full(n, self.speed)
        ang = self.turn_towards(theta, self.gain)
        escaping, e_lin, e_ang = self._bump_escape(obs["proprio"])
        lin, ang = np.where(escaping, e_lin, lin), np.where(escaping, e_ang, ang)
        rw_lin, rw_ang = self._random_walk(~follow)
        return self.compose(np.where(follow, lin, rw_lin), np.where(follow, ang, rw_ang))


class MidAngleNavigation(ScriptedPolicy):
    """[L] Alg. 8 mid-angle navigation of a seeker on decoded ids and hop counts (``observe_ids=True``).

    The static robots broadcast their hop count to the goal in their message bits (LSB first; the goal 0,
    ``2**b - 1`` unknown). The seeker keeps, per decoded sender id, the lowest hop count two of its frames
    in a row agreed on within the last ``memory`` steps (Alg. 8's ``LowestHopsToGoal(id(v))``: a static
    relay's count rises only while it has lost its own links, and a rise would make the seeker turn back;
    the sender is forgotten ``memory`` steps after its last agreed frame; frames naming the seeker itself
    are corrupted ones) and takes each neighbour's bearing from its ``range_bearing`` row
    (the message's coarse bearing when it has none), turned back by the seeker's own rotation since the
    reading was measured (odometry from its last actions: an r-one reading refreshes only when a frame
    arrives, and a stale body-frame bearing is wrong once the robot has turned). Then, as Alg. 8: a neighbour with hop 0 is the goal
    robot -- steer to it; otherwise take the neighbours with the lowest known hop count and steer through
    the mid-angle (circular mean) of the two of them farthest apart in bearing. Ours, where Alg. 8 says
    nothing: when those two are more than ``passing_angle`` rad apart (2.5, 143 degrees: either side of the
    seeker, which is passing between them) it keeps its heading instead of turning to their mid-angle,
    which then flips between ahead and behind; with only one such neighbour in sight the seeker steers to it.
    Ours too: the seeker goes *through* the gap it steers to. It keeps the direction of its steering target
    (that pair's mid-angle, or that one neighbour) in its odometry frame (its own rotation summed since the
    reset); when the direction to the same relays reverses (turns by more than 90 degrees), the seeker has
    crossed their line (turning on the spot does not move an odometry-frame direction), and from then on
    it steers directly away from them, on through the gap, until it hears a lower hop count, crosses back
    (the direction reverses again), or has driven one infrared range (``platform.ir_range`` at its speed)
    without hearing one. Steering to the mid-angle of relays already passed would take it back through the
    gap: with relays heard right behind it (the r-one hears a neighbour at contact range), it would cross
    and re-cross the gap until a lower hop count came in. With no hop count heard it
    random-walks ([T20] Alg. 1); a bump turns it away and it drives straight for ``evade_steps`` before
    steering again; and it does not stop at a bump with the goal ahead (Alg. 8's CheckBumpGoal), since
    without range (the r-one) a bump of a relay in front of the goal looks the same.
    """

    name = "mid_angle_navigation"

    def __init__(self, platform: Platform, layout: ObservationLayout, rng: np.random.Generator | None = None,
                 speed: float = 0.5, gain: float = 0.5, memory: int = 300, evade_steps: int = 5, passing_angle: float = 2.5,
                 t_m: float = 2.0) -> None:
        if layout.message_bits < 1:
            raise ValueError("MidAngleNavigation reads hop counts from the message bits: the env needs message_bits >= 1")
        self.speed, self.gain, self.memory, self.evade_steps = float(speed), float(gain), int(memory), int(evade_steps)
        self.passing_angle = float(passing_angle)
        super().__init__(platform, layout, rng, t_m)

    def reset(self, n: int, rng: np.random.Generator | None = None) -> None:
        super().reset(n, rng)
        n_world = self.layout.n_world
        self._hop = np.full((n, n_world), -1, dtype=np.int64)  # lowest hop count two frames in a row agreed on
        self._last_hop = np.full((n, n_world), -1, dtype=np.int64)  # the last one decoded
        self._heard_at = np.full((n, n_world), -(10**9), dtype=np.int64)  # the step a value of that sender was confirmed
        self._low_at = np.full((n, n_world), -(10**9), dtype=np.int64)  # the step its lowest value was
        self._clock = 0
        self._evade = np.zeros(n, dtype=np.int64)  # steps left of driving straight after an escape turn
        self._odometry = np.zeros(n)  # own rotation (rad) since the reset, from the last actions
        self._target = np.zeros(n)  # odometry-frame direction (rad) of the last relays steered to ...
        self._target_ids = np.full((n, 2), -1, dtype=np.int64)  # ... and their ids (a pair, or one twice; -1: none yet)
        self._passed_hop = np.full(n, -1, dtype=np.int64)  # the hop count whose robots' line the seeker crossed ...
        self._passed_at = np.full(n, -(10**9), dtype=np.int64)  # ... and the step it did

    def act_batch(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        require_ids(obs, "MidAngleNavigation")
        rb, msg = obs["range_bearing"], obs["messages"]
        n, b, n_world = len(rb), self.layout.message_bits, self.layout.n_world
        self._ensure(n)
        self._clock += 1
        unknown = 2**b - 1
        # hop counts from this step's messages, by decoded sender id (the robot's own id is a corrupted header);
        # a value counts once two frames of that sender in a row carried it (one corrupted frame changes nothing),
        # and the lowest one counted in the last `memory` steps is the sender's (Alg. 8's LowestHopsToGoal)
        own = np.rint(obs["own_id"][:, 0] * max(n_world - 1, 1)).astype(np.int64)
        senders = decoded_ids(obs["message_ids"], n_world)
        heard = (msg[..., 0] > 0.5) & (senders >= 0) & (senders != own[:, None])
        values = (msg[..., 2 : 2 + b] > 0.5).astype(np.int64) @ (1 << np.arange(b))
        rows, slots = np.nonzero(heard)
        for row, slot in zip(rows, slots):  # in row order: the frames of one step one after the other
            who, value = senders[row, slot], values[row, slot]
            if self._last_hop[row, who] == value:
                hop = self._hop[row, who]
                if hop < 0 or value <= hop or self._clock - self._low_at[row, who] > self.memory:  # its lowest
                    self._hop[row, who], self._low_at[row, who] = value, self._clock
                self._heard_at[row, who] = self._clock
            self._last_hop[row, who] = value
        # a bearing per id: range & bearing rows (turned back by the own rotation since), else this step's
        # message bearing
        current = self._current_bearings(rb, self._rotation_since(obs))
        self._odometry += self._turned[:, 0]  # this step's own rotation (_rotation_since)
        bearing = np.full((n, n_world), np.nan)
        bearing[rows, senders[rows, slots]] = msg[rows, slots, 1] * np.pi
        ids = decoded_ids(obs["range_bearing_ids"], n_world)
        seen = (rb[..., 0] > 0.5) & (ids >= 0)
        r_rows, r_slots = np.nonzero(seen)
        bearing[r_rows, ids[r_rows, r_slots]] = current[r_rows, r_slots]
        fresh = self._clock - self._heard_at <= self.memory
        known = fresh & np.isfinite(bearing) & (self._hop >= 0) & (self._hop < unknown)
        hop = np.where(known, self._hop, unknown + 1)
        lowest = hop.min(axis=1)
        goal_in_sight = known.any(axis=1) & (lowest == 0)
        candidates = known & (hop == lowest[:, None])
        theta = np.zeros(n)
        target = np.full((n, 2), -1, dtype=np.int64)  # ids of the relays steered to (a pair, or one twice); -1: none
        for r in np.flatnonzero(known.any(axis=1)):
            who = np.flatnonzero(candidates[r])
            angles = bearing[r, who]
            if goal_in_sight[r] or len(angles) == 1:
                theta[r] = angles[0]
                target[r] = -1 if goal_in_sight[r] else who[0]
                continue
            gaps = np.abs(np.angle(np.exp(1j * (angles[:, None] - angles[None, :]))))  # pairwise separation
            i, j = np.unravel_index(np.argmax(gaps), gaps.shape)
            if gaps[i, j] > self.passing_angle:  # the two stand either side of the seeker: it is passing between
                theta[r] = 0.0  # them, so it keeps going rather than turning to their (ill-defined) mid-angle
            else:
                theta[r] = np.angle(np.exp(1j * angles[i]) + np.exp(1j * angles[j]))  # the mid-angle
                target[r] = sorted((who[i], who[j]))
        self._through_the_gap(theta, target, lowest)
        steering = known.any(axis=1)
        lin = np.where(steering, self.speed, 0.0)
        ang = np.where(steering, self.turn_towards(theta, self.gain), 0.0)
        rw_lin, rw_ang = self._random_walk(~steering)
        lin, ang = np.where(steering, lin, rw_lin), np.where(steering, ang, rw_ang)
        # a bump: turn away, then drive straight for evade_steps before steering again
        escaping, e_lin, e_ang = self._bump_escape(obs["proprio"])
        turn_done = escaping & (np.abs(self._escape) < 1e-9)  # this step ends the escape turn
        self._evade[turn_done] = self.evade_steps
        evading = ~escaping & (self._evade > 0)
        self._evade[evading] -= 1
        lin = np.where(escaping, e_lin, np.where(evading, self.speed, lin))
        ang = np.where(escaping, e_ang, np.where(evading, 0.0, ang))
        return self.compose(lin, ang)

    def _through_the_gap(self, theta: np.ndarray, target: np.ndarray, lowest: np.ndarray) -> None:
        """Turn ``theta`` (N,) (rad, body frame, the Alg. 8 steering target) around, in place, while the seeker
        is past the relays of hop count ``lowest`` (N,): it crossed their line when the odometry-frame
        direction of the same target relays ``target`` (N, 2) ids (-1: none, e.g. the goal) reversed
        (class docstring)."""
        limit = self.platform.ir_range / max(self.speed * self.platform.max_speed * DT, 1e-9)  # steps to drive one IR range
        for r in np.flatnonzero(target[:, 0] >= 0):
            direction = self._odometry[r] + theta[r]
            past = self._passed_hop[r] == lowest[r] and self._clock - self._passed_at[r] <= limit
            if np.array_equal(self._target_ids[r], target[r]) and np.cos(direction - self._target[r]) < 0:
                past = not past  # the direction to the same relays reversed: the seeker crossed their line (or back)
                self._passed_hop[r], self._passed_at[r] = (lowest[r], self._clock) if past else (-1, -(10**9))
            self._target[r], self._target_ids[r] = direction, target[r]
            if past:
                theta[r] = np.angle(-np.exp(1j * theta[r]))  # directly away from them: on through the gap
