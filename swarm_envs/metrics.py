"""Swarm-level task metrics computed from ground truth (they feed rewards and ``infos``, never observations)."""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

__all__ = ["components", "cluster_stats", "mean_distance_to_centroid", "polarisation"]


def components(positions: np.ndarray, link_distance: float) -> np.ndarray:
    """Connected-component label per robot, linking centres closer than ``link_distance`` (m), chained."""
    n = len(positions)
    pairs = cKDTree(positions).query_pairs(link_distance, output_type="ndarray")
    graph = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])), shape=(n, n)) if len(pairs) else coo_matrix((n, n))
    return connected_components(graph, directed=False)[1]


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
