"""Centroid seeking: seekers move to the centroid of static anchor robots ([L] Sec. 6.2).

``n_anchors`` static robots (default 4) stand at the corners of a random convex polygon; they are not
agents but still emit infrared and talk, so seekers can sense them. The agents are the ``n_robots``
seekers (default 1). Reward = -distance of the seeker to the anchors' centroid / arena size.
Metric ``mean_distance_second_half`` = mean seeker-centroid distance (m) over the second half of the
episode so far, i.e. over steps ceil(t/2) .. t at step t (just the current distance at reset; never NaN),
which at the last step is the mean over the episode's second half (compare [L] 14.03 cm with
d_step = 11 cm).
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
from pettingzoo import AECEnv
from pettingzoo.utils.conversions import parallel_to_aec

from swarm_envs.env import SwarmEnv
from swarm_envs.factories import reports_unknown_kwargs
from swarm_envs.platforms import Platform
from swarm_envs.task import BatchState, Int, SettingsError, Task, lattice_positions, spawn_positions

__all__ = ["CentroidSeekingTask", "CentroidSeekingEnv", "raw_env", "parallel_env", "env"]

#: gap (fraction of the radius) random placement keeps between seekers and from the anchors
SEEKER_GAP = 0.2
#: random anchor polygons a reset tries before it takes the fallback layout (crowded arenas only)
ANCHOR_DRAWS = 10


class CentroidSeekingTask(Task):
    """Centroid-seeking rewards and metrics over all env copies; extra kwarg ``n_anchors`` (default 4, >= 3)."""

    SETTINGS = {
        "n_robots": 1,
        "n_anchors": Int(
            4, "static robots on a convex polygon", low=3, high=1000,
            why="at least 3 corners for a polygon around the centroid; at most 1,000 static robots (they must also fit on "
            "their circle, checked when the env is built)",
        ),
    }
    METRICS = {"mean_distance_second_half": "final", "mean_distance_to_centroid": "final"}
    HEADLINE = ("mean_distance_second_half", -1)
    SCRIPTED_POLICY = "swarm_envs.agents.scripted:CentroidSeeker"

    def __init__(self, config: dict[str, Any], platform, n_copies: int = 1) -> None:
        super().__init__(config, platform, n_copies)
        # per copy, the cumulative sum of the mean seeker distance over steps 0 .. t (index t + 1); grown
        # as episodes run (memory follows the steps taken, not max_cycles)
        self._distance_cumsum = np.zeros((self.n_copies, 64))

    def n_static_robots(self) -> int:
        return self.config["n_anchors"]

    def default_arena_size(self) -> float:
        # room for an anchor polygon of radius ~0.3 IR ranges plus seekers around it
        return max(super().default_arena_size(), 0.9 * self.platform.ir_range)

    def _anchor_min_angle(self) -> float:
        """Smallest angle (rad) between neighbouring anchors on their circle: a chord of 2.1 radii."""
        ratio = 1.05 * self.platform.radius / self.polygon_radius
        return 2 * float(np.arcsin(ratio)) if ratio < 1 else np.inf

    def check_layout(self) -> None:
        """The anchors fit on their circle and inside the arena, and the seekers beside them for every
        seed: the spawner's last resort (:meth:`fallback_layout`) holds them."""
        n_a, angle = self.n_static, self._anchor_min_angle()
        if n_a * angle >= 2 * np.pi:
            fit = int(np.ceil(2 * np.pi / angle)) - 1 if np.isfinite(angle) else 0
            raise SettingsError(
                "n_anchors",
                f"n_anchors={n_a} anchors of diameter {2 * self.platform.radius:.3f} m do not fit on the anchor circle "
                f"of radius {self.polygon_radius:.3f} m (0.3 x min(IR range, arena size)): at most {fit} fit; "
                "use fewer anchors",
            )
        if self.polygon_radius + self.platform.radius > self.arena.half:
            raise SettingsError(
                self.size_key,
                f"the anchors (diameter {self.platform.diameter:.3f} m) on their circle of radius {self.polygon_radius:.3f} m "
                f"(0.3 x arena size) reach past the walls of the {self.arena.size:.4g} m arena: use arena_size >= "
                f"{5 * self.platform.radius:.4g} m",
            )
        fit = len(self.fallback_layout()[1])
        if fit < self.n_agents:
            raise SettingsError(
                self.size_key,
                f"n_robots={self.n_agents} seekers of diameter {self.platform.diameter:.3f} m do not fit beside "
                f"{n_a} anchors in a {self.arena.shape} arena of size {self.arena.size:.4g} m: at most {fit} fit for sure "
                "(a lattice around evenly spaced anchors); use fewer robots or a larger arena_size",
            )

    @property
    def polygon_radius(self) -> float:
        """Radius (m) of the circle the anchors stand on: within IR range of each other."""
        return min(0.3 * self.platform.ir_range, 0.3 * self.arena.size)

    def fallback_layout(self) -> tuple[np.ndarray, np.ndarray]:
        """The spawner's last resort, fixed when the env is built: (anchors (n_anchors, 2) m evenly spaced
        on their circle, seeker spots (k, 2) m on a lattice, touching neighbours and at least a diameter from
        every anchor). A reset that cannot draw a random layout takes these anchors and a random choice of
        ``n_robots`` of the spots."""
        if getattr(self, "_fallback", None) is None:
            n_a, radius = self.n_static, self.platform.radius
            best = None
            for offset in (0.0, np.pi / n_a):  # two rotations of the regular polygon
                angles = offset + 2 * np.pi * np.arange(n_a) / n_a
                anchors = self.polygon_radius * np.stack([np.cos(angles), np.sin(angles)], -1)
                spots = lattice_positions(self.arena, radius, n=self.n_agents, avoid=anchors, avoid_distance=2 * radius)
                if best is None or len(spots) > len(best[1]):
                    best = (anchors, spots)
            self._fallback = best
        return self._fallback

    def _draw_anchors(self, rng: np.random.Generator) -> np.ndarray | None:
        """Anchors (n_anchors, 2) m at random angles on their circle, corners apart by at least a diameter
        and a margin and no gap wider than 0.95 pi (a convex polygon around the centre); None if the draws fail."""
        n_a = self.n_static
        min_gap = max(2 * np.pi / n_a * 0.4, self._anchor_min_angle())
        for _ in range(1000):
            angles = np.sort(rng.uniform(-np.pi, np.pi, n_a))
            gaps = np.diff(np.concatenate([angles, angles[:1] + 2 * np.pi]))
            if gaps.min() > min_gap and gaps.max() < np.pi * 0.95:
                break
        else:  # many anchors: rejection rarely succeeds, so draw the gaps directly (min_gap + a random share)
            for _ in range(1000):
                gaps = min_gap + (2 * np.pi - n_a * min_gap) * rng.dirichlet(np.ones(n_a))
                if gaps.max() < np.pi * 0.95:
                    break
            else:
                return None
            angles = np.sort((rng.uniform(-np.pi, np.pi) + np.cumsum(gaps) + np.pi) % (2 * np.pi) - np.pi)
        return self.polygon_radius * np.stack([np.cos(angles), np.sin(angles)], -1)

    def spawn(self, rng: np.random.Generator):
        radius = self.platform.radius
        for _ in range(ANCHOR_DRAWS):
            anchors = self._draw_anchors(rng)
            if anchors is None:
                break
            try:  # seekers uniformly at random, SEEKER_GAP apart and from the anchors
                seekers = spawn_positions(
                    rng, self.n_agents, radius, self.arena, gap=SEEKER_GAP * radius, max_tries=50,
                    avoid=anchors, avoid_distance=(2 + SEEKER_GAP) * radius,
                )
            except ValueError:  # crowded: draw another polygon
                continue
            return np.concatenate([anchors, seekers]), rng.uniform(-np.pi, np.pi, self.n_world)
        anchors, spots = self.fallback_layout()  # holds the seekers (checked when the env was built)
        seekers = spots[np.sort(rng.choice(len(spots), self.n_agents, replace=False))]
        return np.concatenate([anchors, seekers]), rng.uniform(-np.pi, np.pi, self.n_world)

    def centroids(self, positions: np.ndarray) -> np.ndarray:
        """The anchors' centroid (..., 2) m of positions (..., n_world, 2), ground truth."""
        return positions[..., : self.n_static, :].mean(axis=-2)

    def rewards(self, state: BatchState, first: np.ndarray):
        seekers = self.agents_of(state.positions)  # (B, A, 2)
        dist = np.linalg.norm(seekers - self.centroids(state.positions)[:, None, :], axis=2)  # (B, A)
        mean_dist = dist.mean(axis=1)
        copies = np.arange(self.n_copies)
        t = np.minimum(state.num_cycles, self.max_cycles)
        if t.max() + 2 > self._distance_cumsum.shape[1]:
            grown = np.zeros((self.n_copies, max(2 * self._distance_cumsum.shape[1], int(t.max()) + 2)))
            grown[:, : self._distance_cumsum.shape[1]] = self._distance_cumsum
            self._distance_cumsum = grown
        self._distance_cumsum[first, 0] = 0.0
        self._distance_cumsum[copies, t + 1] = self._distance_cumsum[copies, t] + mean_dist
        # steps ceil(t/2) .. t: at the end of an episode, its second half (never NaN)
        start = -(-t // 2)
        second = (self._distance_cumsum[copies, t + 1] - self._distance_cumsum[copies, start]) / (t + 1 - start)
        rewards = -dist / self.arena.size
        if self.reward_mode == "global":
            rewards = np.repeat(rewards.mean(axis=1)[:, None], self.n_agents, axis=1)
        metrics = {"mean_distance_to_centroid": mean_dist, "mean_distance_second_half": second}
        return rewards, {"distance_to_centroid": dist}, metrics

    def markers(self, positions: np.ndarray) -> dict[str, np.ndarray]:
        return {"centroid": self.centroids(positions)}


class CentroidSeekingEnv(SwarmEnv):
    """Centroid-seeking task; extra kwarg ``n_anchors`` (default 4, at least 3)."""

    metadata = {**SwarmEnv.metadata, "name": "centroid_seeking_v0"}
    TASK = CentroidSeekingTask

    @property
    def centroid(self) -> np.ndarray:
        """The anchors' centroid (m), ground truth."""
        return self.task.centroids(self.world.positions)


raw_env = CentroidSeekingEnv


@reports_unknown_kwargs
def parallel_env(
    *,
    n_robots: int = 1,
    n_anchors: int = 4,
    platform: Literal["droplet", "epuck", "rone"] | Platform = "epuck",
    sensing: Literal["full", "ideal"] = "full",
    max_cycles: int = 500,
    render_mode: Literal["rgb_array", "human"] | None = None,
    arena: Literal["square", "circle"] = "square",
    arena_size: float | None = None,
    reward_mode: Literal["global", "local"] = "global",
    flatten: bool = False,
    n_neighbours: int = 8,
    n_messages: int = 8,
    message_bits: int = 0,
    observe_ids: bool = False,
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
) -> CentroidSeekingEnv:
    """Create the centroid-seeking environment (a native PettingZoo ``ParallelEnv``).

    ## Description

    Centroid seeking ([L] Sec. 6.2): ``n_anchors`` static robots stand at the corners of a
    random convex polygon; the ``n_robots`` seekers (the agents, ``robot_0`` ..) should reach the
    anchors' centroid. Anchors are not agents, but they emit infrared and talk, so seekers sense them
    like any robot (for example through scale-free coordinates).

    ## Action Space

    Per agent ``Box(-1, 1, (2 + message_bits,), float32)``: linear and angular velocity as fractions of
    the platform's maxima (``Platform.max_speed`` m/s and ``Platform.max_angular_speed`` rad/s; the
    wheel speeds are then limited to ``max_speed`` and carry the platform's motion error, ``motion_noise``),
    followed by ``message_bits`` payload bits (each entry above 0 is a 1-bit),
    broadcast over SwarmCom whenever the robot's transmit queue is empty.
    Finite values outside [-1, 1] are clipped; NaN/inf, wrong shapes and actions for unknown or missing
    agents raise. Zero actions keep a robot still (also with the motion error).

    ## Observation Space

    Per agent a ``Dict`` of ``float32`` boxes, built only from the modelled infrared sensing stack
    (never from ground truth), with K = ``n_neighbours``, M = ``n_messages``, b = ``message_bits``:

    | key | shape | columns |
    |---|---|---|
    | ``range_bearing`` | (K, 7) | valid, range (m), cos bearing, sin bearing, cos heading, sin heading, age (steps) [F14] |
    | ``messages`` | (M, 2 + b) | valid, sender bearing / pi, payload bits: SwarmCom messages decoded since the last step [T20] |
    | ``scale_free`` | (K, 3) | valid, x, y of neighbours in the robot's frame, mean neighbour distance 1, clipped to +-10 [L] |
    | ``rigid`` | (1,) | 1 when the scale-free coordinates are determined [L Sec. 5.5.1] |
    | ``proprio`` | (8 + 2 + b,) | bump flags of 8 45-degree sectors (sector 0 ahead, counter-clockwise), last action |

    Rows are sorted nearest first by *estimated* range; empty rows are all zero. ``observe_ids=True`` adds
    ``own_id`` (2,) and, per row of ``range_bearing``, ``messages`` and ``scale_free``, the id the sensing
    decoded (``range_bearing_ids``, ``message_ids``, ``scale_free_ids``; see ``docs/observations.md``).
    ``flatten=True`` gives one ``Box`` instead (keys in sorted order; ``env.layout.unflatten(flat)`` gives
    the parts back).

    ## Rewards

    Each seeker gets ``-d / L``, its distance d (m) to the anchors' centroid over the arena size L (m);
    ``reward_mode="global"`` gives every seeker the mean over seekers. Term in
    ``infos[agent]["reward_terms"][name]``: ``distance_to_centroid`` (m). Metrics in
    ``infos[agent]["metrics"][name]``: ``mean_distance_to_centroid`` and ``mean_distance_second_half`` (m, the
    mean over the second half of the episode so far; compare [L]'s 14.03 cm).

    ## Starting State

    Anchors stand at random angles on a circle around the arena centre of radius
    ``min(0.3 ir_range, 0.3 arena_size)`` (corners kept apart, so the polygon is convex); seekers are
    placed uniformly at random at least 2.2 robot radii from every anchor. In an arena too crowded for
    random draws, a reset takes evenly spaced anchors and seekers on lattice spots instead; the env is only
    built if those hold the seekers, so every seed resets. The default ``arena_size`` is at least 0.9 ``ir_range``. In ``options["positions"]`` the anchors come first. Headings are uniform in [-pi, pi). ``reset(seed=..., options={"positions": (N, 2) m, "headings": (N,)
    rad})`` places the robots exactly instead; overlapping or out-of-arena placements raise. All
    randomness flows from the seed through independent child streams.

    ## Episode End

    No termination. Truncation: every agent is truncated after ``max_cycles`` steps (default 500 = 50 s);
    ``env.agents`` is then empty.

    ## Arguments

    Keyword-only, SI units. Unknown names raise ``TypeError``; bad values raise ``ValueError``.

    | argument | default | meaning |
    |---|---|---|
    | ``n_robots`` | 1 | number of agents (seekers) |
    | ``n_anchors`` | 4 | static anchor robots (at least 3): they emit infrared and talk but are not agents |
    | ``platform`` | ``"epuck"`` | ``"droplet"`` (4.4 cm, 6 IR channels), ``"epuck"`` (7 cm, 8 sensors), ``"rone"`` (11 cm, 8 RX + 8 TX), or a ``Platform`` |
    | ``sensing`` | ``"full"`` | ``"full"``: the modelled IR stack; ``"ideal"``: exact, noiseless, lossless values in the same layout |
    | ``max_cycles`` | 500 | control steps of 0.1 s per episode |
    | ``render_mode`` | ``None`` | ``"rgb_array"`` (headless) or ``"human"`` (window) |
    | ``arena`` | ``"square"`` | ``"square"`` or ``"circle"`` |
    | ``arena_size`` | ``None`` | side or diameter (m); ``None``: the platform's spacing x sqrt(robots) |
    | ``reward_mode`` | ``"global"`` | ``"global"`` (one team reward) or ``"local"`` (each robot its own term) |
    | ``flatten`` | ``False`` | one flat ``Box`` observation instead of the ``Dict`` |
    | ``n_neighbours`` | 8 | rows K of ``range_bearing`` and ``scale_free`` |
    | ``n_messages`` | 8 | rows M of ``messages`` |
    | ``message_bits`` | 0 | payload bits b an agent sends through its action (0: no message action) |
    | ``observe_ids`` | ``False`` | add the robot's own id and the neighbour and sender ids its sensing decoded (``own_id``, ``*_ids`` parts) |
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
    return CentroidSeekingEnv(**locals())  # every argument above, by name


def env(**kwargs: Any) -> AECEnv:
    """The AEC (turn-based) view of :func:`parallel_env` (PettingZoo ``parallel_to_aec``); same keyword arguments."""
    return parallel_to_aec(parallel_env(**kwargs))
