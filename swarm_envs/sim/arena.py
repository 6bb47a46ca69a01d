"""The arena and the obstacles: walls as segments, the room robots are spawned in, and the checks of user-given
obstacle segments and arrays (m)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["WALL_SEGMENTS", "Arena", "check_obstacles", "distance_to_segments", "obstacle_points", "as_real_array"]

#: straight walls of a circular arena (a regular polygon around the circle)
WALL_SEGMENTS = 64


@dataclass(frozen=True)
class Arena:
    """A walled arena centred on the origin.

    Attributes:
        shape: ``"square"`` (side ``size``) or ``"circle"`` (diameter ``size``).
        size: side length or diameter (m).
    """

    shape: str
    size: float

    SHAPES = ("square", "circle")

    def __post_init__(self) -> None:
        if self.shape not in self.SHAPES:
            raise ValueError(f"unknown arena shape {self.shape!r}; allowed values: {list(self.SHAPES)}")
        if not np.isfinite(self.size) or self.size <= 0:
            raise ValueError(f"arena size must be a positive number of metres, got {self.size!r}")

    @property
    def half(self) -> float:
        return 0.5 * self.size

    @property
    def area(self) -> float:
        return self.size**2 if self.shape == "square" else np.pi * self.half**2

    def contains(self, points: np.ndarray, margin: float = 0.0) -> np.ndarray:
        """True where a disc of radius ``margin`` at ``points`` (..., 2) lies inside the walls."""
        points = np.asarray(points, dtype=float)
        if self.shape == "square":
            return np.all(np.abs(points) <= self.half - margin + 1e-12, axis=-1)
        return np.linalg.norm(points, axis=-1) <= self.half - margin + 1e-12

    def wall_depth(self, points: np.ndarray, radius: float) -> np.ndarray:
        """How far (m) discs of ``radius`` at ``points`` (..., 2) reach past the physical walls (<= 0 inside);
        for a circle the walls are the polygon of :meth:`wall_segments`, whose corners lie a little outside
        the circle."""
        points = np.asarray(points, dtype=float)
        if self.shape == "square":
            return np.abs(points).max(axis=-1) + radius - self.half
        sides = WALL_SEGMENTS
        normals = (2 * np.arange(sides) + 1) * np.pi / sides  # side k faces the middle of corners k and k + 1
        reach = points[..., 0, None] * np.cos(normals) + points[..., 1, None] * np.sin(normals)
        return reach.max(axis=-1) + radius - self.half

    def wall_segments(self, n_circle_segments: int | None = None) -> np.ndarray:
        """Wall segments (S, 2, 2) in metres; a circle is a regular polygon circumscribing it."""
        if self.shape == "square":
            h = self.half
            corners = np.array([[-h, -h], [h, -h], [h, h], [-h, h]])
        else:
            # circumscribed polygon: its inscribed circle is the arena, so a disc placed in the circle is
            # inside the walls (a pushed robot can reach a little past the circle, into a corner)
            n_circle_segments = n_circle_segments or WALL_SEGMENTS
            rad = self.half / np.cos(np.pi / n_circle_segments)
            ang = 2 * np.pi * np.arange(n_circle_segments) / n_circle_segments
            corners = rad * np.stack([np.cos(ang), np.sin(ang)], -1)
        return np.stack([corners, np.roll(corners, -1, axis=0)], axis=1)

    def sample(self, rng: np.random.Generator, n: int, margin: float) -> np.ndarray:
        """Uniform random points (n, 2) whose discs of radius ``margin`` lie inside."""
        inner = self.half - margin
        if self.shape == "square":
            return rng.uniform(-inner, inner, size=(n, 2))
        r = inner * np.sqrt(rng.uniform(0, 1, n))
        a = rng.uniform(-np.pi, np.pi, n)
        return np.stack([r * np.cos(a), r * np.sin(a)], -1)


def check_obstacles(segments: object, arena: Arena, name: str = "obstacles") -> np.ndarray:
    """``segments`` as a float (S, 2, 2) array of obstacle segments (m) whose end points lie inside
    ``arena``; ``ValueError`` naming ``name`` otherwise."""
    arr = as_real_array(segments, name)
    if arr.size == 0:
        return np.zeros((0, 2, 2))
    if arr.ndim != 3 or arr.shape[1:] != (2, 2):
        raise ValueError(f"{name} must be segments of shape (S, 2, 2) metres, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be finite")
    if not np.all(arena.contains(arr.reshape(-1, 2))):
        raise ValueError(f"{name}: every end point must lie inside the {arena.shape} arena of size {arena.size} m")
    return arr


def distance_to_segments(points: np.ndarray, segments: np.ndarray) -> np.ndarray:
    """(...,) distance (m) from each of ``points`` (..., 2) to the nearest of ``segments`` (S, 2, 2) (inf
    without segments)."""
    points = np.asarray(points, dtype=float)
    if len(segments) == 0:
        return np.full(points.shape[:-1], np.inf)
    a, b = segments[:, 0], segments[:, 1]
    ab = b - a
    length2 = np.maximum((ab * ab).sum(-1), 1e-300)
    rel = points[..., None, :] - a
    t = np.clip((rel * ab).sum(-1) / length2, 0.0, 1.0)
    gap = rel - t[..., None] * ab
    return np.sqrt((gap * gap).sum(-1)).min(axis=-1)


def obstacle_points(segments: np.ndarray, radius: float) -> tuple[np.ndarray, float]:
    """Points along ``segments`` (S, 2, 2) m every radius / 2, and the distance (m) a robot centre of
    ``radius`` keeps from all of them to stay clear of the segments with a tenth of a radius to spare:
    ``avoid`` and ``avoid_distance`` for :func:`swarm_envs.sim.spawning.spawn_positions` ((0, 2) points without segments)."""
    if len(segments) == 0:
        return np.zeros((0, 2)), 0.0
    spacing = 0.5 * radius
    points = []
    for a, b in np.asarray(segments, dtype=float):
        n = max(1, int(np.ceil(np.linalg.norm(b - a) / spacing)))
        points.append(a + np.linspace(0.0, 1.0, n + 1)[:, None] * (b - a))
    # a centre farther than r' from every point of a segment sampled every s is >= sqrt(r'^2 - s^2/4) from it
    return np.concatenate(points), float(np.hypot(1.1 * radius, 0.5 * spacing))


def as_real_array(values: object, name: str) -> np.ndarray:
    """``values`` as a float array; raises ``ValueError`` for non-real (string, complex, object) input."""
    try:
        arr = np.asarray(values)
    except (TypeError, ValueError) as err:
        raise ValueError(f"{name} must be a real-valued array, got {values!r}") from err
    if arr.dtype.kind not in "iuf":
        raise ValueError(f"{name} must be a real-valued (int or float) array, got dtype {arr.dtype}")
    return arr.astype(float)
