"""Light taken out of IR links after the gains: static obstacle segments (walls) that block rays, and robots
switched off as emitters, detectors or both (a numpy pass that leaves the compiled kernels alone)."""

from __future__ import annotations
import numpy as np
from swarm_envs.sim.platforms import Platform, get_platform
from swarm_envs.ir.links import IRLinks, emitter_sums

__all__ = ["no_obstacles", "rays_blocked", "block_links"]


def no_obstacles() -> np.ndarray:
    """An empty (0, 2, 2) array of obstacle segments."""
    return np.zeros((0, 2, 2))


def _cross(ax: np.ndarray, ay: np.ndarray, bx: np.ndarray, by: np.ndarray) -> np.ndarray:
    return ax * by - ay * bx


def rays_blocked(starts: np.ndarray, ends: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """(...,) bool: the ray from ``starts`` (..., 2) to ``ends`` (..., 2) (m) crosses or touches one of
    ``segments`` (S, 2, 2) (m); a ray lying on a segment's line counts as clear. Orientation tests,
    vectorised over rays and segments."""
    p, q = np.asarray(starts, float)[..., None, :], np.asarray(ends, float)[..., None, :]
    return _crosses(p, q, segments[:, 0], segments[:, 1]).any(axis=-1)


def _crosses(p: np.ndarray, q: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Elementwise (broadcast) whether segment p-q crosses or touches segment a-b (points (..., 2));
    collinear pairs count as not crossing."""
    ab, pq = b - a, q - p
    d1 = _cross(ab[..., 0], ab[..., 1], p[..., 0] - a[..., 0], p[..., 1] - a[..., 1])
    d2 = _cross(ab[..., 0], ab[..., 1], q[..., 0] - a[..., 0], q[..., 1] - a[..., 1])
    d3 = _cross(pq[..., 0], pq[..., 1], a[..., 0] - p[..., 0], a[..., 1] - p[..., 1])
    d4 = _cross(pq[..., 0], pq[..., 1], b[..., 0] - p[..., 0], b[..., 1] - p[..., 1])
    return (d1 * d2 <= 0) & (d3 * d4 <= 0) & ~((d1 == 0) & (d2 == 0))


def block_links(
    links: IRLinks,
    positions: np.ndarray,
    headings: np.ndarray,
    platform: Platform | str,
    obstacles: np.ndarray | None = None,
    silent: np.ndarray | None = None,
    drop_zero: bool = True,
    emit_off: np.ndarray | None = None,
    detect_off: np.ndarray | None = None,
) -> IRLinks:
    """``links`` with the light of static ``obstacles`` and switched-off robots taken out (a numpy pass
    after the gains).

    Args:
        links: the scene's links (gains gathered).
        positions: (N, 2) robot centres, world frame (m); headings (N,) (rad).
        platform: the robots' platform (emitter and detector positions).
        obstacles: (S, 2, 2) segments (m). A link's rays are tested against each segment its centre
            segment passes within the rays' reach (emitter / detector offsets) of (:func:`rays_blocked`);
            a blocked ray's gain becomes 0 and the link's ``emitter_sums`` are summed again (in emitter
            order, as the kernel sums them).
        silent: (N,) bool robots that neither emit nor detect: their links are dropped.
        drop_zero: drop links left without light.
        emit_off: (N,) bool robots that do not emit: the links from them are dropped.
        detect_off: (N,) bool robots that do not detect: the links to them are dropped.

    Returns: the new :class:`IRLinks` (``obstacle_clear`` set when a ray was tested), or ``links`` itself
    when nothing changes.
    """
    platform = get_platform(platform)
    n_links = len(links)
    keep = np.ones(n_links, dtype=bool)
    if silent is not None:
        silent = np.asarray(silent, dtype=bool)
        keep &= ~(silent[links.rx] | silent[links.tx])
    if emit_off is not None:
        keep &= ~np.asarray(emit_off, dtype=bool)[links.tx]
    if detect_off is not None:
        keep &= ~np.asarray(detect_off, dtype=bool)[links.rx]
    obstacle_clear = None
    gains, sums = links.gains, links.emitter_sums
    segments = no_obstacles() if obstacles is None else np.asarray(obstacles, dtype=float).reshape(-1, 2, 2)
    if len(segments) and n_links:
        # (link, segment) pairs whose rays can meet: every ray lies within the rays' reach (the emitter and
        # detector offsets) of the link's centre segment, so the centre segment must pass that close
        reach = max(np.hypot(*platform.emitter_positions.T).max(), np.hypot(*platform.detector_positions.T).max())
        a, b = positions[links.rx], positions[links.tx]
        lo, hi = np.minimum(a, b) - reach, np.maximum(a, b) + reach
        s_lo, s_hi = segments.min(axis=1), segments.max(axis=1)
        link, seg = np.nonzero(((lo[:, None, :] <= s_hi[None]) & (hi[:, None, :] >= s_lo[None])).all(axis=-1) & keep[:, None])
        close = _segment_distance(a[link], b[link], segments[seg, 0], segments[seg, 1]) <= reach * (1 + 1e-9)
        link, seg = link[close], seg[close]
        rows, pair_row = np.unique(link, return_inverse=True)
        if rows.size:
            detectors = _world_points(positions[links.rx[rows]], headings[links.rx[rows]], platform.detector_positions)
            emitters = _world_points(positions[links.tx[rows]], headings[links.tx[rows]], platform.emitter_positions)
            # each pair's rays against its one segment, then or-ed per link: (R, n_d, n_e)
            a_end, b_end = segments[seg, 0][:, None, None, :], segments[seg, 1][:, None, None, :]
            hit = _crosses(emitters[pair_row][:, None, :, :], detectors[pair_row][:, :, None, :], a_end, b_end)
            blocked = np.zeros((rows.size,) + hit.shape[1:], dtype=bool)
            np.logical_or.at(blocked, pair_row, hit)
            if blocked.any():
                obstacle_clear = np.ones(gains.shape, dtype=bool)
                obstacle_clear[rows] = ~blocked
                gains = gains.copy()
                gains[rows] = np.where(blocked, 0.0, gains[rows])
                if sums is not None:
                    sums = sums.copy()
                    sums[rows] = emitter_sums(gains[rows])
                if drop_zero:
                    keep[rows] &= gains[rows].reshape(rows.size, -1).max(axis=1) > 0
    if keep.all() and obstacle_clear is None:
        return links
    occluders = None if links.occluders is None else (*links.occluders[:2], links.occluders[2][keep])
    return IRLinks(
        links.rx[keep], links.tx[keep], links.distance[keep], links.rel_position[keep], links.rel_heading[keep], gains[keep],
        links.n_robots, occluders, None if sums is None else sums[keep], None if obstacle_clear is None else obstacle_clear[keep],
    )


def _segment_distance(p: np.ndarray, q: np.ndarray, a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(K,) distance (m) between segments p-q and a-b, each (K, 2): 0 where they cross, else the smallest
    of the four end-point-to-segment distances."""

    def point_to_segment(x: np.ndarray, s0: np.ndarray, s1: np.ndarray) -> np.ndarray:
        d = s1 - s0
        t = np.clip(((x - s0) * d).sum(-1) / np.maximum((d * d).sum(-1), 1e-300), 0.0, 1.0)
        return np.linalg.norm(x - s0 - t[:, None] * d, axis=-1)

    ends = np.minimum(np.minimum(point_to_segment(p, a, b), point_to_segment(q, a, b)), np.minimum(point_to_segment(a, p, q), point_to_segment(b, p, q)))
    d1 = _cross(*(b - a).T, *(p - a).T)
    d2 = _cross(*(b - a).T, *(q - a).T)
    d3 = _cross(*(q - p).T, *(a - p).T)
    d4 = _cross(*(q - p).T, *(b - p).T)
    return np.where((d1 * d2 <= 0) & (d3 * d4 <= 0), 0.0, ends)


def _world_points(centres: np.ndarray, headings: np.ndarray, body_points: np.ndarray) -> np.ndarray:
    """(R, K, 2) world positions (m) of body-frame points ``body_points`` (K, 2) of R robots."""
    c, s = np.cos(headings)[:, None], np.sin(headings)[:, None]
    x, y = body_points[None, :, 0], body_points[None, :, 1]
    return np.stack([centres[:, 0:1] + c * x - s * y, centres[:, 1:2] + s * x + c * y], axis=-1)
