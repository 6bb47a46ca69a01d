"""Observation packing: the compiled nearest-k selection equals the numpy reference."""

import numpy as np
import pytest

from swarm_envs._compile import reference
from swarm_envs.sensing.observation import pack_nearest


@pytest.mark.parametrize("P,n_rows,k", [(5000, 600, 8), (400, 10, 3), (50, 200, 1), (1, 1, 4)])
def test_pack_nearest_equals_numpy_reference(P, n_rows, k):
    rng = np.random.default_rng(P)
    row = rng.integers(0, n_rows, P)
    key = rng.uniform(0, 1, P)
    key[rng.uniform(size=P) < 0.2] = 0.5  # ties: kept in link order
    key[rng.uniform(size=P) < 0.05] = np.nan  # NaN keys sort last
    values = rng.normal(size=(P, 5))
    packed, order = pack_nearest(n_rows, row, key, values, k)
    ref_packed, ref_order = reference.pack_nearest(n_rows, row, key, values, k)
    np.testing.assert_array_equal(order, ref_order)
    np.testing.assert_array_equal(packed, ref_packed)
    if P > 1:  # rows with more than k links are cut to the nearest k
        assert (np.bincount(row, minlength=n_rows) > k).any()
    if P < n_rows * k:
        assert (order == -1).any()


def test_pack_nearest_one_dimensional_values_and_empty_input():
    packed, order = pack_nearest(3, np.array([2, 2, 0]), np.array([0.3, 0.1, 0.2]), np.array([1.0, 2.0, 3.0]), 2)
    np.testing.assert_array_equal(order, [[2, -1], [-1, -1], [1, 0]])
    np.testing.assert_array_equal(packed[..., 0], [[3.0, 0.0], [0.0, 0.0], [2.0, 1.0]])
    packed, order = pack_nearest(4, np.zeros(0, int), np.zeros(0), np.zeros((0, 7)), 3)
    assert packed.shape == (4, 3, 7) and not packed.any() and (order == -1).all()


def test_pack_nearest_rejects_rows_out_of_range():
    with pytest.raises(ValueError, match="rows"):
        pack_nearest(3, np.array([0, 3]), np.array([0.1, 0.2]), np.ones((2, 1)), 2)
