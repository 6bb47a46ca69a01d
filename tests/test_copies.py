"""Per-copy random streams (swarm_envs.copies): buffered draws equal each copy's own generator stream."""

import numpy as np
import pytest

from swarm_envs.copies import CopyStream


@pytest.mark.parametrize("kind", ["normal", "uniform"])
@pytest.mark.parametrize("n_copies", [3, 12])  # few copies (gathered by slices) and many (one indexed take)
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
