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

__all__ = ["CopyRandom", "CopyStream", "copy_counts", "normal_noise"]


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


class CopyStream:
    """Per-copy buffered draws of one distribution (``"normal"``: N(0, 1); ``"uniform"``: U[0, 1)).

    Drawing row by row from B generators costs one Generator call per copy and request (microseconds
    each, several per copy and step). Here each copy's generator is read in large chunks into a buffer
    row and requests are served from the buffers with one vectorised gather. Each generator must serve
    only this stream: numpy's ``standard_normal`` (ziggurat) and ``random`` keep no state between calls,
    so ``g.standard_normal(a)`` then ``g.standard_normal(b)`` equals ``g.standard_normal(a + b)`` and the
    values copy ``b`` receives are the first ones of its own generator's stream, whatever the chunking
    or the other copies' demand: copy ``b`` of a batch equals a single env (``tests/sim/test_copies.py``).

    Args:
        generators: one generator per copy (used for this stream only).
        kind: ``"normal"`` or ``"uniform"``.
        chunk: initial buffer length per copy (values); grows to the largest single request.
    """

    def __init__(self, generators: Sequence[np.random.Generator] | np.random.Generator, kind: str = "normal", chunk: int = 2048) -> None:
        if isinstance(generators, np.random.Generator):
            generators = [generators]
        if kind not in ("normal", "uniform"):
            raise ValueError(f"kind must be 'normal' or 'uniform', got {kind!r}")
        self.generators = list(generators)
        self.kind = kind
        self._buf = np.empty((len(self.generators), max(int(chunk), 1)))
        self._pos = np.zeros(len(self.generators), dtype=np.int64)  # next unread value of each copy
        self._end = np.zeros(len(self.generators), dtype=np.int64)  # end of each copy's valid values

    @property
    def n_copies(self) -> int:
        return len(self.generators)

    def set_generator(self, copy: int, generator: np.random.Generator) -> None:
        """Give copy ``copy`` a new generator and drop its buffered values."""
        self.generators[copy] = generator
        self._pos[copy] = self._end[copy] = 0

    def _refill(self, copies: np.ndarray, need: np.ndarray) -> None:
        cap = self._buf.shape[1]
        if need.max() > cap:  # a request larger than a buffer row: widen every row (values kept)
            wide = np.empty((self.n_copies, max(2 * cap, int(need.max()))))
            wide[:, :cap] = self._buf
            self._buf, cap = wide, wide.shape[1]
        for b in copies:
            b = int(b)
            rem = int(self._end[b] - self._pos[b])
            row = self._buf[b]
            row[:rem] = row[self._pos[b] : self._end[b]]
            g = self.generators[b]
            if self.kind == "normal":  # written in place (out=): the same values as a new array, no copy
                g.standard_normal(out=row[rem:])
            else:
                g.random(out=row[rem:])
            self._pos[b], self._end[b] = 0, cap

    def draw(self, row_copy: np.ndarray, tail: tuple[int, ...] = (), scale: float | None = None) -> np.ndarray:
        """(R, *tail) draws; rows of copy b are the next values of copy b's stream (``row_copy`` sorted).
        ``scale``: return ``scale * draws`` (computed while copying out of the buffer)."""
        row_copy = np.asarray(row_copy, dtype=np.int64).reshape(-1)
        t = int(np.prod(tail, dtype=np.int64))
        R = row_copy.size
        if R == 0 or t == 0:
            return np.zeros((R, *tail))
        mul = None if scale is None else float(scale)
        rows = copy_counts(row_copy, self.n_copies)
        need = rows * t
        short = np.flatnonzero(self._pos + need > self._end)
        if short.size:
            self._refill(short, need[short])
        # each copy's values are consecutive in its buffer row and in the output: one gather of runs
        used = np.flatnonzero(need)
        n_used = need[used]
        total = int(n_used.sum())
        cap = self._buf.shape[1]
        if used.size == 1:  # one copy: a slice, copied (or scaled) out
            b = used[0]
            run = self._buf[b, self._pos[b] : self._pos[b] + total]
            out, mul = (run.copy() if mul is None else np.multiply(run, mul)), None
        elif used.size <= 8:  # few copies: slices
            out = np.concatenate([self._buf[b, self._pos[b] : self._pos[b] + n] for b, n in zip(used, n_used)])
        else:
            shift = used * cap + self._pos[used] - (np.cumsum(n_used) - n_used)
            out = np.take(self._buf.reshape(-1), np.repeat(shift, n_used) + np.arange(total))
        if mul is not None:
            out *= mul
        self._pos += need
        return out.reshape(R, *tail)


def normal_noise(
    rng: np.random.Generator | CopyRandom | CopyStream, sigma: float, shape: tuple[int, ...], row_copy: np.ndarray | None
) -> np.ndarray:
    """N(0, sigma^2) noise of ``shape``; rows from each copy's stream when ``rng`` is a CopyRandom or a
    normal :class:`CopyStream`."""
    rows = np.zeros(shape[0], dtype=np.int64) if row_copy is None else row_copy
    if isinstance(rng, CopyStream):
        if rng.kind != "normal":
            raise ValueError("noise needs a 'normal' CopyStream")
        return rng.draw(rows, shape[1:], scale=sigma)
    if isinstance(rng, CopyRandom):
        return rng.normal(sigma, rows, shape[1:])
    return rng.normal(0.0, sigma, shape)
