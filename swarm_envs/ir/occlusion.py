"""Robots as occluders of each other's light: the robots near enough to a pair's rays to block them (neighbour
lists, per-pair occluder lists and frames) and the centre-to-centre line of sight (docs/design.md#infrared-physical-layer)."""

from __future__ import annotations
import numpy as np
from scipy.spatial import cKDTree
from swarm_envs.ir import occluder_kernels, pair_kernels
from swarm_envs.sim.platforms import Platform, get_platform

__all__ = ["occluder_width", "neighbour_csr", "pair_occluders", "occluder_lists", "occluder_frames", "line_of_sight"]


def occluder_width(platform: Platform | str) -> float:
    """Distance (m) from a pair's centre segment within which a third robot's centre can block a ray:
    ``radius + rho``, rho the largest emitter / detector distance from a robot's centre (every ray lies
    within rho of the centre segment, so a disc farther than ``radius + rho`` misses all of them)."""
    platform = get_platform(platform)
    rho = max(np.hypot(*platform.emitter_positions.T).max(), np.hypot(*platform.detector_positions.T).max())
    return float(platform.radius + rho)


def neighbour_csr(positions: np.ndarray, reach: float, tree: cKDTree) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Neighbour lists within ``reach`` (m) of every robot from one KD-tree ``query_pairs``, as CSR
    (starts, counts, neighbours)."""
    near = tree.query_pairs(reach, output_type="ndarray")
    N = positions.shape[0]
    src = np.concatenate([near[:, 0], near[:, 1]])
    dst = np.concatenate([near[:, 1], near[:, 0]])
    order = np.argsort(src, kind="stable")
    counts = np.bincount(src, minlength=N)
    starts = np.cumsum(counts) - counts
    return starts.astype(np.int64), counts.astype(np.int64), dst[order].astype(np.int64)


def pair_occluders(
    positions: np.ndarray,
    headings: np.ndarray,
    rx: np.ndarray,
    tx: np.ndarray,
    width: float,
    tree: cKDTree | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Candidate occluders of P (receiver, transmitter) pairs: third robots whose centre is closer than
    ``width`` (m) to the segment between the two centres.

    Vectorised over pairs: such a robot lies within ``sqrt(|rx tx|^2 / 4 + width^2)`` of one end, so the candidates
    are the neighbours of both ends within that distance (one KD-tree ``query_pairs`` in CSR form), tested
    by a compiled kernel (plain numpy reference: :func:`swarm_envs._compile.reference.occluder_lists` and
    :func:`swarm_envs._compile.reference.occluder_frames`).

    Returns:
        offsets (P + 1,) int, robots (K,) int, centres (K, 2) in the receiver's body frame (m): pair p's
        occluders are rows ``offsets[p]:offsets[p + 1]``, sorted by robot index.
    """
    positions = np.ascontiguousarray(positions, dtype=float).reshape(-1, 2)
    headings = np.ascontiguousarray(headings, dtype=float).reshape(-1)
    rx = np.ascontiguousarray(rx, dtype=np.int64).reshape(-1)
    tx = np.ascontiguousarray(tx, dtype=np.int64).reshape(-1)
    offsets, idx = occluder_lists(positions, rx, tx, width, tree)
    _, xy = occluder_frames(positions, headings, rx, np.arange(rx.shape[0]), offsets, idx)
    return offsets, idx, xy


def occluder_lists(
    positions: np.ndarray,
    a: np.ndarray,
    b: np.ndarray,
    width: float,
    tree: cKDTree | None,
    max_length: float | None = None,
    near_pairs: np.ndarray | None = None,
    near_range: float = 0.0,
    threads: int = 1,
) -> tuple[np.ndarray, np.ndarray]:
    """CSR (offsets (P + 1,), robots (K,)) of the third robots closer than ``width`` to segment a[p]-b[p].
    ``max_length``: the longest segment (m) if known (to within 1e-12 m), else computed. ``near_pairs``
    (U, 2): unordered pairs known to include every pair of robots closer than ``near_range`` (m) (e.g.
    the KD-tree's candidate pairs): the neighbour lists are taken from them instead of a second KD-tree
    query when the lists' reach is shorter (compiled path). ``threads`` > 1: the compiled search runs on that
    many threads (:func:`gain_threads`; same result bit for bit)."""
    P, N = a.shape[0], positions.shape[0]
    if P == 0 or N < 3:
        return np.zeros(P + 1, dtype=np.int64), np.zeros(0, dtype=np.int64)
    if tree is None:
        tree = cKDTree(positions)
    if max_length is None:
        seg = positions[b] - positions[a]
        max_length = float(np.hypot(seg[:, 0], seg[:, 1]).max())
    # a centre within width of a segment is within sqrt(length^2 / 4 + width^2) of the segment's nearer end
    # (foot point on that half, Pythagoras); + 2e-9 m^2 covers the kernel's own margin and rounding
    reach2 = 0.25 * float(max_length) ** 2 + float(width) ** 2 + 2e-9
    reach = float(np.sqrt(reach2))
    if near_pairs is not None and reach < near_range * (1.0 - 1e-9):  # lists from the pairs, no second query
        starts, counts, nbrs = pair_kernels.neighbour_csr_kernel(positions, np.ascontiguousarray(near_pairs, dtype=np.int64), reach2)
    else:
        starts, counts, nbrs = neighbour_csr(positions, reach, tree)
    if threads > 1:
        return occluder_kernels.occluders_kernel_threaded(positions, float(width), a, b, starts, counts, nbrs, int(threads))
    return occluder_kernels.occluders_kernel(positions, float(width), a, b, starts, counts, nbrs)


def occluder_frames(
    positions: np.ndarray, headings: np.ndarray, rx: np.ndarray, pair_of: np.ndarray, offsets: np.ndarray, idx: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """The occluders of pair ``pair_of[p]`` as centres in receiver ``rx[p]``'s frame: (offsets (P + 1,), (K, 2))."""
    rx = np.ascontiguousarray(rx, dtype=np.int64)
    pair_of = np.ascontiguousarray(pair_of, dtype=np.int64)
    return occluder_kernels.occluder_frames_kernel(positions, np.cos(headings), np.sin(headings), rx, pair_of, offsets, idx)


def line_of_sight(
    positions: np.ndarray,
    radius: float,
    i: np.ndarray,
    j: np.ndarray,
    tree: cKDTree | None = None,
) -> np.ndarray:
    """Centre-line rule (a coarser line of sight, for comparison): True where the segment
    between centres ``positions[i]`` and ``positions[j]`` crosses no third robot's disc (open disc of
    ``radius`` m around every other centre). The simulator itself decides line of sight per ray
    (:func:`compute_links`).

    Returns: (P,) bool mask.
    """
    positions = np.ascontiguousarray(positions, dtype=float).reshape(-1, 2)
    i = np.ascontiguousarray(i, dtype=np.int64).reshape(-1)
    j = np.ascontiguousarray(j, dtype=np.int64).reshape(-1)
    offsets, _ = occluder_lists(positions, i, j, radius, tree)
    return np.diff(offsets) == 0
