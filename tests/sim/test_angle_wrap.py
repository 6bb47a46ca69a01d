"""One angle wrap, swarm_envs.sim.geometry.wrap_angle ((-pi, pi]); the scripted baselines' [-pi, pi) is its mirror."""

from __future__ import annotations

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from swarm_envs.agents.scripted_base import wrap_below_pi
from swarm_envs.sim.geometry import wrap_angle

EDGES = np.array([np.pi, -np.pi, 0.0, -0.0, 3 * np.pi, -3 * np.pi, 2 * np.pi, 1e-300, -1e-300, np.nextafter(np.pi, 0), np.nextafter(-np.pi, 0)])


def _modulo_wrap(a):  # the baselines' former formula, which their recorded results used
    return np.mod(np.asarray(a) + np.pi, 2 * np.pi) - np.pi


def test_edges():
    assert wrap_angle(np.pi) == np.pi and wrap_angle(-np.pi) == np.pi
    assert wrap_below_pi(np.pi) == -np.pi and wrap_below_pi(-np.pi) == -np.pi
    np.testing.assert_array_equal(wrap_below_pi(EDGES).view(np.int64), _modulo_wrap(EDGES).view(np.int64))


@given(st.lists(st.floats(min_value=-1e6, max_value=1e6, allow_nan=False), min_size=1, max_size=50))
def test_mirror_is_the_former_formula_bit_for_bit(values):
    x = np.array(values)
    np.testing.assert_array_equal(wrap_below_pi(x).view(np.int64), _modulo_wrap(x).view(np.int64))
