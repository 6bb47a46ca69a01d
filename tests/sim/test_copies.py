"""Per-copy random streams (swarm_envs.sim.copies): buffered draws equal each copy's own generator stream."""

import numpy as np
import pytest

from swarm_envs.sim.copies import CopyStream


@pytest.mark.parametrize("kind", ["normal", "uniform"])
@pytest.mark.parametrize("n_copies", [1, 3, 12])  # one copy (a slice), few (slices) and many (one indexed take)
def test_copy_stream_serves_each_copy_its_own_stream_whatever_the_chunking(kind, n_copies):
    seeds = list(range(3, 3 + n_copies))
    stream = CopyStream([np.random.default_rng(s) for s in seeds], kind, chunk=7)
    rng = np.random.default_rng(0)
    got = [[] for _ in seeds]
    for _ in range(40):  # requests of varying sizes, some copies absent, some larger than a buffer row
        counts = rng.integers(0, 6, len(seeds)) * rng.integers(0, 2, len(seeds))
        tail = (int(rng.integers(1, 4)),)
        row_copy = np.repeat(np.arange(len(seeds)), counts)
        out = stream.draw(row_copy, tail)
        assert out.shape == (counts.sum(), *tail)
        for b in range(len(seeds)):
            got[b].append(out[row_copy == b].reshape(-1))
    for b, s in enumerate(seeds):
        flat = np.concatenate(got[b])
        g = np.random.default_rng(s)
        ref = g.standard_normal(flat.size) if kind == "normal" else g.random(flat.size)
        np.testing.assert_array_equal(flat, ref)


def test_copy_stream_new_generator_drops_the_buffer_and_rows_must_be_grouped():
    stream = CopyStream([np.random.default_rng(1), np.random.default_rng(2)], "normal", chunk=16)
    stream.draw(np.array([0, 1, 1]), (2,))
    stream.set_generator(1, np.random.default_rng(9))
    np.testing.assert_array_equal(stream.draw(np.array([1]), (3,))[0], np.random.default_rng(9).standard_normal(3))
    with pytest.raises(ValueError):
        stream.draw(np.array([1, 0]))
    with pytest.raises(ValueError):
        CopyStream([np.random.default_rng(0)], "poisson")


@pytest.mark.parametrize("n_copies", [1, 3, 12])
def test_copy_stream_scaled_draws_equal_scaled_values(n_copies):
    """draw(scale=s) gives exactly s * draw() of the same stream (the product computed while copying)."""
    a = CopyStream([np.random.default_rng(s) for s in range(n_copies)], "normal", chunk=5)
    b = CopyStream([np.random.default_rng(s) for s in range(n_copies)], "normal", chunk=5)
    rng = np.random.default_rng(1)
    for _ in range(30):
        row_copy = np.sort(rng.integers(0, n_copies, int(rng.integers(0, 9))))
        got = a.draw(row_copy, (3,), scale=1.58)
        ref = 1.58 * b.draw(row_copy, (3,))
        np.testing.assert_array_equal(got.view(np.int64), ref.view(np.int64))
        assert got.shape == (row_copy.size, 3)
