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

from typing import Any

import numpy as np

from swarm_envs.tasks.factories import task_module
from swarm_envs.tasks.task import DT, BatchState, Choice, Default, Platform, Real, Task, bump_any, largest_component_fraction, pairs_within, reward_weight

__all__ = ["ParityClusteringTask", "ParityClusteringEnv", "raw_env", "parallel_env", "env"]

#: same-parity robots whose centres are within this many diameters are one cluster (chained)
CLUSTER_LINK_DIAMETERS = 1.5


class ParityClusteringTask(Task):
    """Parity-clustering rewards and metrics over all env copies (module docstring)."""

    SETTINGS = {
        "platform": "rone",
        "observe_ids": True,
        "n_robots": Default(10, help="number of agents (ids 0 .. N-1: five even, five odd)"),
        "message_bits": Default(1, help="payload bits b an agent sends through its action: with b > 0 every robot broadcasts "
                                "continuously, and each decoded frame refreshes its neighbours' bearing of it (0: only the 2.4 s bearing beacons)"),
        "arena_size": Default(None, help="side or diameter (m); ``None``: the platform's spacing x sqrt(robots) (r-one 0.45 m x sqrt(N))"),
        "cluster_radius": Real(None, "pair distance counted by the segregation index; None: 1.5 robot diameters", low=0.0, low_open=True,
                               high=100.0, allow_none=True, unit="m",
                               why="at most 100 m: a distance beyond every arena the defaults build; larger values only count more pairs",
                               help="pair distance (m) the segregation index counts; ``None``: 1.5 robot diameters (robots in contact within a cluster)"),
        "collision_penalty": reward_weight(0.0, "weight of the fraction of robots bumping (Alg. 7 clusters by bumping)",
                                           help="weight of the fraction of robots bumping, subtracted from the reward"),
        "reward_term": Choice("separation", "what a robot is rewarded for: 'separation' (mean distance to the other parity - "
                              "to its own, over the arena size) or 'segregation' (its own share of same-parity neighbours "
                              "within cluster_radius, the per-robot term of the headline metric, plus the step's gain in "
                              "that distance difference over one step's drive)",
                              choices=("separation", "segregation"),
                              help='``"separation"`` or ``"segregation"`` (each robot' "'s own same-parity share of its neighbours within "
                                   "``cluster_radius``, plus the step's gain in separation)"),
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


_DOC = """Create the parity-clustering environment (a native PettingZoo ``ParallelEnv``).

## Description

Parity clustering ([L] Sec. 6.4.3, Algorithm 7, Fig. 6.9): ``n_robots`` robots with ids 0 .. N-1
(``robot_i`` has id i) should gather even ids with even ids and odd with odd, sensing only bearings
and the ids they decode. Without range there is no stopping condition: the thesis's robots keep
colliding within their cluster.

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

## Version History

- v0: initial release (swarm_envs 0.1.0).
"""

raw_env, parallel_env, env = task_module(ParityClusteringTask, _DOC)
ParityClusteringEnv = raw_env
