"""Env copies in one array program: robot indexing and per-copy random streams.

The batched engine steps ``B`` independent copies of a task at once. Every per-robot array covers all
``B x N`` robots, robot ``g = b * N + i`` being robot ``i`` of copy ``b`` (copies are contiguous blocks).
Nothing may cross copies: no IR link, collision or message, and no random draw. :class:`CopyRandom`
holds one :class:`numpy.random.Generator` per copy and draws for the rows of each copy from that copy's
generator only, in the same order and sizes a single env (``B = 1``) would, so copy ``b`` of a batch
seeded with ``s_b`` reproduces a single env seeded with ``s_b`` bit for bit.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = ["CopyRandom", "copy_counts"]


def copy_counts(row_copy: np.ndarray, n_copies: int) -> np.ndarray:
    """(B,) number of rows of each copy; ``row_copy`` must be sorted ascending (copies contiguous)."""
    row_copy = np.asarray(row_copy, dtype=np.int64).reshape(-1)
    if row_copy.size > 1 and np.any(row_copy[1:] < row_copy[:-1]):
        raise ValueError("rows must be grouped by copy (row_copy sorted ascending)")
    return np.bincount(row_copy, minlength=n_copies)


class CopyRandom:
    """One random generator per env copy; draws for rows grouped by copy.

    Args:
        generators: one :class:`numpy.random.Generator` per copy.
    """

    def __init__(self, generators: Sequence[np.random.Generator] | np.random.Generator) -> None:
        if isinstance(generators, np.random.Generator):
            generators = [generators]
        self.generators = list(generators)

    @property
    def n_copies(self) -> int:
        return len(self.generators)

    def spawn(self, n_children: int) -> list["CopyRandom"]:
        """``n_children`` independent :class:`CopyRandom` (child k of every copy's generator)."""
        kids = [g.spawn(n_children) for g in self.generators]
        return [CopyRandom([k[j] for k in kids]) for j in range(n_children)]

    def _draw(self, counts: np.ndarray, draw) -> list[np.ndarray]:
        return [draw(g, int(c)) for g, c in zip(self.generators, counts) if c > 0]

    def normal(self, scale: float, row_copy: np.ndarray, tail: tuple[int, ...] = ()) -> np.ndarray:
        """(R, *tail) N(0, scale^2) draws; rows of copy b from generator b (``row_copy`` sorted)."""
        counts = copy_counts(row_copy, self.n_copies)
        parts = self._draw(counts, lambda g, c: g.normal(0.0, scale, (c, *tail)))
        return np.concatenate(parts, axis=0) if parts else np.zeros((0, *tail))

    def random(self, row_copy: np.ndarray, tail: tuple[int, ...] = ()) -> np.ndarray:
        """(R, *tail) uniform [0, 1) draws; rows of copy b from generator b (``row_copy`` sorted)."""
        counts = copy_counts(row_copy, self.n_copies)
        parts = self._draw(counts, lambda g, c: g.random((c, *tail)))
        return np.concatenate(parts, axis=0) if parts else np.zeros((0, *tail))

    def integers(self, low: int, high: int, row_copy: np.ndarray, tail: tuple[int, ...] = ()) -> np.ndarray:
        """(R, *tail) integers in [low, high); rows of copy b from generator b (``row_copy`` sorted)."""
        counts = copy_counts(row_copy, self.n_copies)
        parts = self._draw(counts, lambda g, c: g.integers(low, high, (c, *tail)))
        return np.concatenate(parts, axis=0) if parts else np.zeros((0, *tail), dtype=np.int64)
