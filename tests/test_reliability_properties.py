"""Property test (hypothesis): random sequences of valid and invalid calls.

A rejected call (bad action, reset argument or setting) raises its documented exception type and leaves
the env unchanged and usable: afterwards the env steps exactly like a twin that never saw the bad call.
Documented types: ``TypeError`` (wrong type), ``ValueError`` (bad value), ``KeyError`` (unknown or missing
agent), ``RuntimeError`` (step on a finished episode).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from swarm_envs import flocking_v0  # noqa: E402
from tests.conftest import assert_tree_equal  # noqa: E402

CONFIGS = [
    {"n_robots": 3, "sensing": "ideal", "max_cycles": 8},
    {"n_robots": 2, "sensing": "ideal", "message_bits": 2, "max_cycles": 8, "arena": "circle"},
    {"n_robots": 3, "sensing": "full", "max_cycles": 8},
]


def bad_step(env, k: int):
    """(actions, expected exception) for bad variant ``k``."""
    size = env.layout.action_size
    good = {a: np.zeros(size) for a in env.agents}
    first = env.agents[0]
    variants = [
        ({**good, first: np.full(size, np.nan)}, ValueError),
        ({**good, first: np.zeros(size + 1)}, ValueError),
        ({**good, first: ["1"] * size}, TypeError),
        ({**good, first: np.ones(size, complex)}, TypeError),
        ({**good, first: [True] * size}, TypeError),
        ({a: v for a, v in good.items() if a != first}, KeyError),
        ({**good, "robot_99": np.zeros(size)}, KeyError),
        (list(good.values()), TypeError),
    ]
    return variants[k % len(variants)]


def bad_reset(env, k: int):
    """(reset kwargs, expected exception) for bad variant ``k``."""
    n = env.n_world
    variants = [
        ({"seed": -1}, ValueError),
        ({"seed": 2.5}, TypeError),
        ({"options": "positions"}, TypeError),
        ({"options": {"positions": np.zeros((n, 2))}}, ValueError),  # all on one spot: overlap
        ({"options": {"positions": np.full((n, 2), 1e3)}}, ValueError),  # outside
        ({"options": {"headings": np.zeros(n + 1)}}, ValueError),
        ({"options": {"positions": [["0", "1"]] * n}}, ValueError),
        ({"seed": 3, "options": {"headings": np.full(n, np.inf)}}, ValueError),
    ]
    return variants[k % len(variants)]


BAD_SETTINGS = [
    ({"rb_noise": math.nan}, ValueError),
    ({"relative_threshold": math.inf}, ValueError),
    ({"code": (15, 9)}, ValueError),
    ({"message_bits": 256}, ValueError),
    ({"n_robots": True}, ValueError),
    ({"n_robot": 3}, TypeError),
    ({"n_robots": 500, "arena_size": 0.3}, ValueError),
]


def snapshot(env) -> dict:
    w = env.world
    snap = {
        "world": [w.positions.copy(), w.headings.copy(), w.velocities.copy(), w.angular_velocities.copy(), w.bumps.copy()],
        "cycles": env.num_cycles,
        "agents": list(env.agents),
        "last_actions": env.core.last_actions.copy(),
        "rng": repr(env.core.generators[0].bit_generator.state),
    }
    if env._frame is not None:
        snap["obs"] = env.batched_observations()
    return snap


OPS = st.lists(
    st.tuples(st.sampled_from(["step", "step", "reset", "bad_step", "bad_reset", "bad_settings"]), st.integers(0, 40)),
    min_size=1,
    max_size=12,
)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True, database=None)
@given(config=st.sampled_from([0, 0, 0, 1, 1, 2]), ops=OPS)
def test_rejected_calls_change_nothing(config, ops):
    kwargs = CONFIGS[config]
    env, twin = flocking_v0.parallel_env(**kwargs), flocking_v0.parallel_env(**kwargs)
    assert_tree_equal(env.reset(seed=0), twin.reset(seed=0))
    for kind, k in ops:
        if kind == "step":
            if not env.agents:
                for e in (env, twin):
                    with pytest.raises(RuntimeError, match="reset"):
                        e.step({})
                continue
            rng = np.random.default_rng(k)
            actions = {a: rng.uniform(-1.5, 1.5, env.layout.action_size) for a in env.agents}
            assert_tree_equal(env.step(actions), twin.step(actions))
        elif kind == "reset":
            seed = None if k % 4 == 0 else k
            assert_tree_equal(env.reset(seed=seed), twin.reset(seed=seed))
        elif kind == "bad_settings":
            bad, error = BAD_SETTINGS[k % len(BAD_SETTINGS)]
            with pytest.raises(error):
                flocking_v0.parallel_env(**{**kwargs, **bad})
        else:
            before = snapshot(env)
            if kind == "bad_step":
                if env.agents:
                    actions, error = bad_step(env, k)
                else:
                    actions, error = {}, RuntimeError
                with pytest.raises(error):
                    env.step(actions)
            else:
                call, error = bad_reset(env, k)
                with pytest.raises(error):
                    env.reset(**call)
            assert_tree_equal(snapshot(env), before)
    # still usable, and still the twin of the env that never saw a bad call
    if not env.agents:
        assert_tree_equal(env.reset(), twin.reset())
    actions = {a: np.full(env.layout.action_size, 0.7) for a in env.agents}
    assert_tree_equal(env.step(actions), twin.step(actions))
