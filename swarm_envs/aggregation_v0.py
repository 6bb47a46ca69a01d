"""Aggregation: robots start spread out and should gather into one cluster (docs/design.md#tasks).

Reward (global, default) = decrease of the swarm's spread (mean distance to the centroid) this step,
normalised by the arena size; ``reward_mode="local"`` rewards each robot for the decrease of its own
distance to the centroid. Metrics in ``infos[agent]["metrics"][name]``: largest-cluster fraction (clusters =
robots whose centres are within 1.5 diameters, chained), number of clusters, mean distance to centroid (m).
"""

from __future__ import annotations

from typing import Any, Literal

import numpy as np
from pettingzoo import AECEnv
from pettingzoo.utils.conversions import parallel_to_aec

from swarm_envs.env import SwarmEnv
from swarm_envs.factories import reports_unknown_kwargs
from swarm_envs.platforms import Platform
from swarm_envs.task import BatchState, Task, largest_component_fraction

__all__ = ["AggregationTask", "AggregationEnv", "raw_env", "parallel_env", "env"]

CLUSTER_LINK_DIAMETERS = 1.5


class AggregationTask(Task):
    """Aggregation rewards and metrics over all env copies (module docstring)."""

    METRICS = {"largest_cluster_fraction": "final", "n_clusters": "final", "mean_distance_to_centroid": "final"}
    HEADLINE = ("largest_cluster_fraction", +1)
    SCRIPTED_POLICY = "swarm_envs.agents.scripted:BearingAggregation"

    def __init__(self, config: dict[str, Any], platform, n_copies: int = 1) -> None:
        super().__init__(config, platform, n_copies)
        self._prev_own = np.zeros((self.n_copies, self.n_agents))

    def rewards(self, state: BatchState, first: np.ndarray):
        pos = self.agents_of(state.positions)  # (B, A, 2)
        own = np.linalg.norm(pos - pos.mean(axis=1, keepdims=True), axis=2)  # (B, A)
        spread = own.mean(axis=1)
        self._prev_own[first] = own[first]
        size = self.arena.size
        global_term = (self._prev_own.mean(axis=1) - spread) / size  # (B,)
        local_term = (self._prev_own - own) / size
        self._prev_own = own
        global_rows = np.repeat(global_term[:, None], self.n_agents, axis=1)
        rewards = global_rows if self.reward_mode == "global" else local_term
        link = CLUSTER_LINK_DIAMETERS * self.platform.diameter
        largest, n_clusters = largest_component_fraction(pos, link)
        metrics = {
            "largest_cluster_fraction": largest,
            "n_clusters": n_clusters.astype(float),
            "mean_distance_to_centroid": spread,
        }
        terms = {"spread_decrease": global_rows, "own_distance_decrease": local_term}
        return rewards, terms, metrics

    def markers(self, positions: np.ndarray) -> dict[str, np.ndarray]:
        return {"centroid": positions[self.n_static :].mean(axis=0)}


class AggregationEnv(SwarmEnv):
    """Aggregation task; see the module docstring and :class:`swarm_envs.env.SwarmEnv` for kwargs."""

    metadata = {**SwarmEnv.metadata, "name": "aggregation_v0"}
    TASK = AggregationTask


raw_env = AggregationEnv


@reports_unknown_kwargs
def parallel_env(
    *,
    n_robots: int = 10,
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
) -> AggregationEnv:
    """Create the aggregation environment (a native PettingZoo ``ParallelEnv``).

    ## Description

    Aggregation (docs/design.md#tasks): ``n_robots`` robots start spread over the arena and should gather into one
    cluster, sensing each other only through infrared. Two robots are in one cluster when their centres
    are within 1.5 diameters (chained). Agents are named ``robot_0`` .. ``robot_{N-1}``.

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

    With ``D_t`` the robots' mean distance (m) to their centroid and ``L`` the arena size (m):
    ``reward_mode="global"`` gives every agent ``(D_{t-1} - D_t) / L``, the decrease of the swarm's
    spread this step; ``"local"`` gives each robot the decrease of its own distance to the centroid, / L.
    Both terms are in ``infos[agent]["reward_terms"][name]`` (``spread_decrease``, ``own_distance_decrease``).
    Metrics in ``infos[agent]["metrics"][name]``: ``largest_cluster_fraction``, ``n_clusters``,
    ``mean_distance_to_centroid`` (m).

    ## Starting State

    Robots are placed uniformly at random in the arena without overlap (random sequential placement with
    a gap of 0.1 radius). Headings are uniform in [-pi, pi). ``reset(seed=..., options={"positions": (N, 2) m, "headings": (N,)
    rad})`` places the robots exactly instead; overlapping or out-of-arena placements raise. All
    randomness flows from the seed through independent child streams.

    ## Episode End

    No termination. Truncation: every agent is truncated after ``max_cycles`` steps (default 500 = 50 s);
    ``env.agents`` is then empty.

    ## Arguments

    Keyword-only, SI units. Unknown names raise ``TypeError``; bad values raise ``ValueError``.

    | argument | default | meaning |
    |---|---|---|
    | ``n_robots`` | 10 | number of agents |
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
    return AggregationEnv(**locals())  # every argument above, by name


def env(**kwargs: Any) -> AECEnv:
    """The AEC (turn-based) view of :func:`parallel_env` (PettingZoo ``parallel_to_aec``); same keyword arguments."""
    return parallel_to_aec(parallel_env(**kwargs))
