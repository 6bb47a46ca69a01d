"""Parity clustering: even ids gather with even ids, odd with odd, from bearings alone [L Sec. 6.4.3, Alg. 7].

Every robot moves towards the average bearing of the neighbours whose decoded id has its own parity and,
as on the r-one, never stops: without range it cannot tell it has arrived, and collisions with its
cluster make it turn away (Fig. 6.9). Robot ``robot_i`` has id ``i``; the robots read the ids their
sensing decoded (``observe_ids``, on by default).

Metrics (ground truth): ``segregation`` = the mean over robots of the share of its neighbours within
``cluster_radius`` (default 1.5 diameters: robots touching within a cluster) that have its parity, 0 for a
robot without such neighbours (1 when every robot is in a cluster of its own parity, about 4/9 when
neighbours are mixed at random (10 robots), 0 when all are apart); ``parity_cluster_fraction`` = the mean over the two parities of the largest
same-parity cluster's share of that parity (clusters: same-parity robots whose centres are within 1.5
diameters, chained); ``n_parity_clusters`` = the number of same-parity clusters (single robots count; 2
when each parity is one cluster); ``collision_fraction`` = share of robots in contact.
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
from pettingzoo import AECEnv
from pettingzoo.utils.conversions import parallel_to_aec

from swarm_envs.env import DT, SwarmEnv
from swarm_envs.factories import reports_unknown_kwargs
from swarm_envs.platforms import Platform
from swarm_envs.task import BatchState, Choice, Real, Task, bump_any, largest_component_fraction, pairs_within

__all__ = ["ParityClusteringTask", "ParityClusteringEnv", "raw_env", "parallel_env", "env"]

#: same-parity robots whose centres are within this many diameters are one cluster (chained)
CLUSTER_LINK_DIAMETERS = 1.5


class ParityClusteringTask(Task):
    """Parity-clustering rewards and metrics over all env copies (module docstring)."""

    SETTINGS = {
        "platform": "rone",
        "observe_ids": True,
        "message_bits": 1,
        "cluster_radius": Real(None, "pair distance counted by the segregation index; None: 1.5 robot diameters", low=0.0, low_open=True,
                               high=100.0, allow_none=True, unit="m",
                               why="at most 100 m: a distance beyond every arena the defaults build; larger values only count more pairs"),
        "collision_penalty": Real(0.0, "weight of the fraction of robots bumping (Alg. 7 clusters by bumping)", low=0.0, high=1000.0,
                                  why="a reward weight; rewards stay within +-1000 per step"),
        "reward_term": Choice("separation", "what a robot is rewarded for: 'separation' (mean distance to the other parity - "
                              "to its own, over the arena size) or 'segregation' (its own share of same-parity neighbours "
                              "within cluster_radius, the per-robot term of the headline metric, plus the step's gain in "
                              "that distance difference over one step's drive)",
                              choices=("separation", "segregation")),
    }
    METRICS = {"segregation": "mean", "parity_cluster_fraction": "final", "n_parity_clusters": "final", "collision_fraction": "mean"}
    HEADLINE = ("segregation", +1)
    SCRIPTED_POLICY = "swarm_envs.agents.scripted:ParityClustering"

    def __init__(self, config: dict[str, Any], platform: Platform, n_copies: int = 1) -> None:
        super().__init__(config, platform, n_copies)
        given = config["cluster_radius"]
        #: pair distance (m) the segregation index counts
        self.cluster_radius = CLUSTER_LINK_DIAMETERS * platform.diameter if given is None else float(given)
        self.parity = np.arange(self.n_world)[self.n_static :] % 2  # agent ids' parities
        self._prev_potential = np.zeros((self.n_copies, self.n_agents))  # reward_term="segregation" shaping

    def robot_groups(self) -> tuple[np.ndarray, tuple[str, str]]:
        """Even ids in one colour, odd ids in the other (drawing only)."""
        return np.arange(self.n_world) % 2, ("even id", "odd id")

    def rewards(self, state: BatchState, first: np.ndarray):
        B, A = self.n_copies, self.n_agents
        pos = self.agents_of(state.positions)
        even, odd = self.parity == 0, self.parity == 1
        # segregation: per robot the same-parity share of its neighbours within the cluster radius (0 without
        # any), averaged over the robots (pairs never cross copies; row b * A + i is robot i of copy b)
        pairs = pairs_within(pos, self.cluster_radius)
        same = (self.parity[pairs[:, 0] % A] == self.parity[pairs[:, 1] % A]).astype(float)
        ends = pairs.reshape(-1)
        neighbours = np.bincount(ends, minlength=B * A)
        same_parity = np.bincount(ends, np.repeat(same, 2), minlength=B * A)
        own_segregation = (same_parity / np.maximum(neighbours, 1)).reshape(B, A)
        segregation = own_segregation.mean(axis=1)
        # same-parity clusters
        link = CLUSTER_LINK_DIAMETERS * self.platform.diameter
        fractions, counts = [], np.zeros(B)
        for members in (even, odd):
            if members.any():
                largest, count = largest_component_fraction(pos[:, members], link)
                fractions.append(largest)
                counts += count
        parity_cluster_fraction = np.mean(fractions, axis=0)
        # reward: each robot's mean distance to the other parity minus that to its own, over the arena size
        gaps = np.linalg.norm(pos[:, :, None, :] - pos[:, None, :, :], axis=-1) if A <= 256 else None
        if gaps is not None:
            same_mask = (self.parity[:, None] == self.parity[None, :]) & ~np.eye(A, dtype=bool)
            other_mask = self.parity[:, None] != self.parity[None, :]
            d_same = (gaps * same_mask).sum(axis=2) / np.maximum(same_mask.sum(axis=1), 1)
            d_other = (gaps * other_mask).sum(axis=2) / np.maximum(other_mask.sum(axis=1), 1)
        else:  # many robots: distances to the parities' centroids
            c_same = np.where(even[None, :, None], pos[:, even].mean(axis=1, keepdims=True), pos[:, odd].mean(axis=1, keepdims=True))
            c_other = np.where(even[None, :, None], pos[:, odd].mean(axis=1, keepdims=True), pos[:, even].mean(axis=1, keepdims=True))
            d_same, d_other = np.linalg.norm(pos - c_same, axis=-1), np.linalg.norm(pos - c_other, axis=-1)
        if not (even.any() and odd.any()):  # one parity only: nothing to keep apart
            d_other = np.zeros_like(d_same)
        own = (d_other - d_same) / self.arena.size
        separation = own
        if self.config["reward_term"] == "segregation":
            # the headline metric's per-robot term, plus potential-based shaping (Ng et al., ICML 1999) on the
            # separation in units of one step's drive: the step's gain in (distance to the other parity -
            # distance to the own); it sums to the episode's net gain, so it guides without changing the optimum
            potential = separation * self.arena.size / (self.platform.max_speed * DT)
            self._prev_potential[first] = potential[first]
            own = own_segregation + (potential - self._prev_potential)
            self._prev_potential = potential
        bumped = bump_any(self.agents_of(state.bumps)).astype(float)
        c = self.config["collision_penalty"]
        local_reward = own - c * bumped
        global_reward = own.mean(axis=1) - c * bumped.mean(axis=1)
        rewards = np.repeat(global_reward[:, None], A, axis=1) if self.reward_mode == "global" else local_reward
        terms = {"separation": separation, "segregation": own_segregation, "collision": bumped}
        metrics = {
            "segregation": segregation,
            "parity_cluster_fraction": parity_cluster_fraction,
            "n_parity_clusters": counts,
            "collision_fraction": bumped.mean(axis=1),
        }
        return rewards, terms, metrics

    def markers(self, positions: np.ndarray) -> dict[str, np.ndarray]:
        return {"centroid": positions[self.n_static :].mean(axis=0)}


class ParityClusteringEnv(SwarmEnv):
    """Parity-clustering task; see the module docstring and :func:`parallel_env` for the kwargs."""

    metadata = {**SwarmEnv.metadata, "name": "parity_clustering_v0"}
    TASK = ParityClusteringTask


raw_env = ParityClusteringEnv


@reports_unknown_kwargs
def parallel_env(
    *,
    n_robots: int = 10,
    cluster_radius: float | None = None,
    collision_penalty: float = 0.0,
    reward_term: Literal["separation", "segregation"] = "separation",
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
) -> ParityClusteringEnv:
    """Create the parity-clustering environment (a native PettingZoo ``ParallelEnv``).

    ## Description

    Parity clustering ([L] Sec. 6.4.3, Algorithm 7, Fig. 6.9): ``n_robots`` robots with ids 0 .. N-1
    (``robot_i`` has id i) should gather even ids with even ids and odd with odd, sensing only bearings
    and the ids they decode. Without range there is no stopping condition: the thesis's robots keep
    colliding within their cluster.

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

    ``reward_mode="global"``: the mean over robots of (mean distance to the robots of the other parity -
    mean distance to the other robots of its own parity) / arena size, minus ``collision_penalty`` x the
    fraction of robots bumping (default 0: Algorithm 7 clusters by bumping). ``"local"``: each robot its own
    term and bump. ``reward_term="segregation"`` rewards each robot instead with its own share of same-parity
    neighbours within ``cluster_radius`` (the per-robot term of the headline metric; the separation term alone
    rewards moving away from the other parity without joining the own) plus the step's gain in its
    separation, in units of one step's drive (``max_speed`` x 0.1 s): potential-based shaping, which sums to
    the episode's net gain and leaves the best policy unchanged. Terms in
    ``infos[agent]["reward_terms"][name]``: ``separation``, ``segregation``, ``collision``. Metrics
    in ``infos[agent]["metrics"][name]``: ``segregation`` (headline: the mean over robots of the
    same-parity share of its neighbours within ``cluster_radius``, 0 without any), ``parity_cluster_fraction`` (mean over
    the parities of the largest same-parity cluster's share, clusters chained at 1.5 diameters),
    ``n_parity_clusters`` (same-parity clusters, single robots included; 2 at best), ``collision_fraction``.

    ## Starting State

    Robots are placed uniformly at random in the arena without overlap (random sequential placement with
    a gap of 0.1 radius). Headings are uniform in [-pi, pi). ``reset(seed=..., options={"positions": (N, 2)
    m, "headings": (N,) rad})`` places the robots exactly instead.

    ## Episode End

    No termination. Truncation: every agent is truncated after ``max_cycles`` steps (default 500 = 50 s);
    ``env.agents`` is then empty.

    ## Arguments

    Keyword-only, SI units. Unknown names raise ``TypeError``; bad values raise ``ValueError``.

    | argument | default | meaning |
    |---|---|---|
    | ``n_robots`` | 10 | number of agents (ids 0 .. N-1: five even, five odd) |
    | ``cluster_radius`` | ``None`` | pair distance (m) the segregation index counts; ``None``: 1.5 robot diameters (robots in contact within a cluster) |
    | ``collision_penalty`` | 0.0 | weight of the fraction of robots bumping, subtracted from the reward |
    | ``reward_term`` | ``"separation"`` | ``"separation"`` or ``"segregation"`` (each robot's own same-parity share of its neighbours within ``cluster_radius``, plus the step's gain in separation) |
    | ``platform`` | ``"rone"`` | ``"droplet"`` (4.4 cm, 6 IR channels), ``"epuck"`` (7 cm, 8 sensors), ``"rone"`` (11 cm, 8 RX + 8 TX), or a ``Platform`` |
    | ``sensing`` | ``"full"`` | ``"full"``: the modelled IR stack; ``"ideal"``: exact, noiseless, lossless values (true ids) in the same layout |
    | ``max_cycles`` | 500 | control steps of 0.1 s per episode |
    | ``render_mode`` | ``None`` | ``"rgb_array"`` (headless) or ``"human"`` (window) |
    | ``arena`` | ``"square"`` | ``"square"`` or ``"circle"`` |
    | ``arena_size`` | ``None`` | side or diameter (m); ``None``: the platform's spacing x sqrt(robots) (r-one 0.45 m x sqrt(N)) |
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
    return ParityClusteringEnv(**locals())  # every argument above, by name


def env(**kwargs: Any) -> AECEnv:
    """The AEC (turn-based) view of :func:`parallel_env` (PettingZoo ``parallel_to_aec``); same keyword arguments."""
    return parallel_to_aec(parallel_env(**kwargs))
