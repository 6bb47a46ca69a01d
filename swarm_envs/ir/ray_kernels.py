"""Compiled geometry of light rays and robot bodies: whether a segment (a ray from an emitter to a detector)
crosses a disc (a robot's body) [F14 Sec. IV], with the tolerance that gives the numpy reference's verdict on
rays that graze a disc. Used by the gain and the occluder kernels."""

from __future__ import annotations
from swarm_envs._compile._numba import njit  # numba.njit whose cache recovers from corrupted files

__all__ = ["segment_hits_disc", "DISC_TOL", "hits_disc"]


@njit(cache=True, inline="always", error_model="numpy")
def segment_hits_disc(x0: float, y0: float, x1: float, y1: float, cx: float, cy: float, r2: float) -> bool:
    """Whether the segment (x0, y0)-(x1, y1) passes closer than sqrt(r2) to (cx, cy) (open disc)."""
    sx, sy = x1 - x0, y1 - y0
    px, py = cx - x0, cy - y0
    L2 = sx * sx + sy * sy
    t = (px * sx + py * sy) / L2 if L2 > 0.0 else 0.0
    t = min(1.0, max(0.0, t))
    qx, qy = px - t * sx, py - t * sy
    return qx * qx + qy * qy < r2

DISC_TOL = 1e-6  # relative: a ray's line this far outside / inside the disc radius gets the reference's verdict


@njit(cache=True, inline="always", error_model="numpy")
def hits_disc(
    x0: float, y0: float, x1: float, y1: float, dx: float, dy: float, L2: float, cx: float, cy: float, r2: float, r2_hi: float, r2_lo: float
) -> bool:
    """:func:`segment_hits_disc` for a segment with ``dx = x1 - x0``, ``dy = y1 - y0``, ``L2 = dx * dx + dy * dy``
    computed so by the caller, and ``r2_hi, r2_lo = r2 (1 +- DISC_TOL)``: the same verdict, without the
    division except within a relative 1e-6 of the radius (there it decides). When the nearest point is an
    end (t clamped to 0 or 1) the arithmetic is the same; otherwise the squared distance of the centre
    from the segment's line is ``cr^2 / L2`` (cr the cross product), compared with r2 with a margin far
    above rounding (~1e-14 relative)."""
    px, py = cx - x0, cy - y0
    dot = px * dx + py * dy
    if dot <= 0.0:  # t clamps to 0: nearest point is the start
        return px * px + py * py < r2
    if dot >= L2:  # t clamps to 1: nearest point is the end
        qx, qy = px - dx, py - dy
        return qx * qx + qy * qy < r2
    cr = px * dy - py * dx
    cr2 = cr * cr
    if cr2 >= r2_hi * L2:
        return False
    return cr2 <= r2_lo * L2 or segment_hits_disc(x0, y0, x1, y1, cx, cy, r2)
