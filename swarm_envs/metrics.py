"""Swarm-level task metrics computed from ground truth (they feed rewards and ``infos``, never observations)."""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

__all__ = ["components", "cluster_stats", "largest_component_fraction", "mean_distance_to_centroid", "polarisation"]


def components(positions: np.ndarray, link_distance: float) -> np.ndarray:
    """Connected-component label per robot, linking centres closer than ``link_distance`` (m), chained."""
    n = len(positions)
    pairs = cKDTree(positions).query_pairs(link_distance, output_type="ndarray")
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n)) if len(pairs) else coo_matrix((n, n))
    return connected_components(graph, directed=False)[1]


def largest_component_fraction(
    positions: np.ndarray, link_distance: float, pairs: np.ndarray | None = None
) -> tuple[np.ndarray, np.ndarray]:
    """For (B, N, 2) positions of B env copies: (largest-component fraction (B,), number of components
    (B,)), linking centres of one copy closer than ``link_distance`` (m), chained. One graph for all copies
    (pairs never cross copies), so one connected-components call per step instead of one per copy.
    ``pairs``: those links if the caller already has them (``copy_pairs`` over the B x N rows)."""
    from swarm_envs.sensing.ideal import copy_pairs

    B, N = positions.shape[:2]
    copy = np.repeat(np.arange(B), N)
    if pairs is None:
        pairs = copy_pairs(positions.reshape(B * N, 2), link_distance, N)
    n = B * N
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    labels = connected_components(graph, directed=False)[1]
    sizes = np.bincount(labels, minlength=n)
    # components never span copies: each label belongs to the copy of its robots
    label_copy = np.full(sizes.size, -1)
    label_copy[labels] = copy
    present = sizes > 0
    largest = np.zeros(B)
    np.maximum.at(largest, label_copy[present], sizes[present])
    count = np.bincount(label_copy[present], minlength=B)
    return largest / N, count


def cluster_stats(positions: np.ndarray, link_distance: float) -> tuple[float, int]:
    """(largest-cluster fraction, number of clusters) for clusters chained at ``link_distance`` (m)."""
    labels = components(positions, link_distance)
    sizes = np.bincount(labels)
    return float(sizes.max() / len(positions)), int(len(sizes))


def mean_distance_to_centroid(positions: np.ndarray) -> float:
    """Mean distance (m) of the robots to their centroid (the swarm's spread)."""
    return float(np.linalg.norm(positions - positions.mean(axis=0), axis=1).mean())


def polarisation(headings: np.ndarray, speeds: np.ndarray, max_speed: float) -> float:
    """Norm of the mean unit heading weighted by speed / max speed, in [0, 1]."""
    weight = np.clip(speeds / max_speed, 0.0, 1.0)
    vec = np.stack([np.cos(headings), np.sin(headings)], -1) * weight[:, None]
    return float(np.linalg.norm(vec.mean(axis=0)))
