"""swarm_envs.sim._vecmath: the vectorisable log / exp / power used by the e-puck gain kernel."""

import math

import numpy as np
import pytest

from swarm_envs.sim import _vecmath


def _samples(rng):
    """Positive normal arguments: log-uniform over the gain kernel's squared ray lengths (1e-12 .. 1.2 m^2)
    and beyond, powers of two and their neighbours (exponent / mantissa boundaries), sqrt(2)/2 .. sqrt(2)."""
    x = [10.0 ** rng.uniform(-300, 300, 20000), 10.0 ** rng.uniform(-12, 0.1, 50000), rng.uniform(0.5, 1.5, 20000)]
    twos = 2.0 ** np.arange(-60, 61, dtype=float)
    x += [twos, np.nextafter(twos, 0), np.nextafter(twos, np.inf), np.array([1.0, math.sqrt(0.5), math.sqrt(2.0), 0.7071067811865476])]
    return np.concatenate(x)


def test_log_is_within_one_ulp_of_numpy():
    x = _samples(np.random.default_rng(0))
    ours = np.array([_vecmath.log_positive(v) for v in x])
    ref = np.log(x)
    assert _vecmath.log_positive(1.0) == 0.0
    ulp = np.abs(ours - ref) / np.spacing(np.abs(ref) + (ref == 0))
    assert ulp.max() <= 1.0, ulp.max()


def test_exp_is_within_one_ulp_of_numpy():
    x = np.concatenate([np.random.default_rng(1).uniform(-700, 700, 50000), [0.0, 1e-300, -1e-300, 0.5 * math.log(2), 700.0, -700.0]])
    ours = np.array([_vecmath.exp_moderate(v) for v in x])
    ref = np.exp(x)
    assert _vecmath.exp_moderate(0.0) == 1.0
    ulp = np.abs(ours - ref) / np.spacing(ref)
    assert ulp.max() <= 1.0, ulp.max()


@pytest.mark.parametrize("y", [0.5 * -1.54557 - 5.0, -1.0, 2.5, 0.0])
def test_power_agrees_with_the_library_path(y):
    """power_into (the vectorised loop) equals its scalar parts and agrees with math.exp(y * math.log(x))
    and math.pow to the rounding of y * log(x), over the e-puck kernel's range of squared lengths."""
    x = 10.0 ** np.random.default_rng(2).uniform(-12, 0.1, 100003)  # odd length: a scalar remainder too
    out = np.empty_like(x)
    _vecmath.power_into(x, y, out)
    scalar = np.array([_vecmath.exp_moderate(y * _vecmath.log_positive(v)) for v in x[:2000]])
    np.testing.assert_array_equal(out[:2000], scalar)
    library = np.array([math.exp(y * math.log(v)) for v in x])
    exact = np.array([math.pow(v, y) for v in x])
    bound = 4e-16 * (1.0 + np.abs(y * np.log(x)))  # 1 ulp of each step, the product's rounding amplified by exp
    assert np.all(np.abs(out / exact - 1.0) <= bound)
    assert np.all(np.abs(out / library - 1.0) <= 2.0 * bound)


def test_power_does_not_depend_on_the_position_in_the_array():
    """Each element's value is the same in any batch (vector body or scalar remainder)."""
    x = 10.0 ** np.random.default_rng(3).uniform(-12, 0.1, 1001)
    whole = np.empty_like(x)
    _vecmath.power_into(x, -5.77, whole)
    for start in range(8):
        part = np.empty(x.size - start)
        _vecmath.power_into(np.ascontiguousarray(x[start:]), -5.77, part)
        np.testing.assert_array_equal(part, whole[start:])


def test_numpy_exp_equals_the_compiled_exp_bit_for_bit():
    """exp_array (numpy operations, for numpy references) equals exp_moderate and exp_into exactly, and is
    within 1 ulp of numpy's exp, whatever the array's shape."""
    x = np.concatenate([np.random.default_rng(4).uniform(-700, 700, 30001), -(0.01 + np.linspace(0, 1, 2001)) * 244.4, [0.0, -0.0]])
    ours = _vecmath.exp_array(x)
    out = np.empty_like(x)
    _vecmath.exp_into(x, out)
    np.testing.assert_array_equal(ours, out)
    np.testing.assert_array_equal(ours[:3000], [_vecmath.exp_moderate(v) for v in x[:3000]])
    np.testing.assert_array_equal(_vecmath.exp_array(x[:3000].reshape(30, 100)), ours[:3000].reshape(30, 100))
    assert np.all(np.abs(ours - np.exp(x)) <= np.spacing(np.exp(x)))
