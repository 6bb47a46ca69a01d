"""Scenes that build reset for every seed: the build's fit test and the spawners agree exactly. If the build
passes, ``reset`` succeeds for every seed; if not, the build raises a ``SettingsError`` naming
``arena_size``, ``n_robots`` or ``n_anchors`` and saying how many fit -- and that many do build and reset."""

from __future__ import annotations

import re

import numpy as np
import pytest

pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, event, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

import swarm_envs  # noqa: E402
from swarm_envs.sim.platforms import PLATFORMS  # noqa: E402
from swarm_envs.tasks.settings import SettingsError  # noqa: E402
from swarm_envs.sim.spawning import check_capacity, fit_count, spawn_positions  # noqa: E402
from swarm_envs.sim.arena import Arena

FLOCKING, AGGREGATION, CENTROID = "swarm_envs/Flocking-v0", "swarm_envs/Aggregation-v0", "swarm_envs/CentroidSeeking-v0"


def resets(env_id: str, seeds, **kwargs) -> int:
    """Build the env and reset it with every seed; returns how many resets failed (an error is raised by
    the build itself)."""
    env = swarm_envs.make(env_id, sensing="ideal", **kwargs)
    failed = 0
    for seed in seeds:
        try:
            env.reset(seed=seed)
        except ValueError:
            failed += 1
            continue
        pos = env.world.positions
        assert np.all(env.arena.contains(pos, env.platform.radius)), "a spawned robot leaves the arena"
        d = np.linalg.norm(pos[:, None] - pos[None], axis=-1) + np.eye(len(pos))
        assert d.min() >= env.platform.diameter - 1e-9, "spawned robots overlap"
    return failed


@pytest.mark.parametrize(
    "env_id, kwargs",
    [
        (CENTROID, {"n_robots": 8, "arena_size": 0.35}),  # 19 of 100 seeds failed with the random spawner alone
        (FLOCKING, {"n_robots": 14, "arena_size": 0.28}),  # every seed failed
        (AGGREGATION, {"n_robots": 4, "arena_size": 0.1455}),  # a 2x2 grid needs 0.14 m; hexagonal lattices fit 3
        (AGGREGATION, {"n_robots": 16, "arena_size": 0.28}),  # a 4x4 grid exactly
        (FLOCKING, {"n_robots": 200, "arena_size": 1.2, "arena": "circle"}),
    ],
)
def test_issue_cases_reset_for_every_seed(env_id, kwargs):
    assert resets(env_id, range(100), **kwargs) == 0


@pytest.mark.parametrize(
    "env_id, kwargs, key, fit",
    [
        (AGGREGATION, {"n_robots": 5, "arena_size": 0.1455}, "arena_size", 4),
        (FLOCKING, {"n_robots": 17, "arena_size": 0.28}, "arena_size", 16),
        (FLOCKING, {"n_robots": 500}, None, None),  # the default arena always fits: no error
        (CENTROID, {"n_robots": 20, "arena_size": 0.35}, "arena_size", None),
        (CENTROID, {"n_robots": 1, "arena_size": 0.16}, "arena_size", None),  # anchors past the walls
        (CENTROID, {"n_anchors": 200}, "n_anchors", None),
    ],
)
def test_a_scene_that_does_not_fit_is_a_build_error_saying_how_many_fit(env_id, kwargs, key, fit):
    if key is None:
        assert resets(env_id, range(3), **kwargs) == 0
        return
    with pytest.raises(SettingsError) as err:
        swarm_envs.make(env_id, **kwargs)
    assert err.value.key == key and "\n" not in str(err.value)
    if fit is not None:
        assert f"at most {fit} fit" in str(err.value)
        assert resets(env_id, range(20), **{**kwargs, "n_robots": fit}) == 0


def test_fit_count_is_exact_for_grids():
    r = PLATFORMS["epuck"].radius
    assert fit_count(100, r, Arena("square", 4 * r)) == 4  # 2 x 2, touching the walls and each other
    assert fit_count(100, r, Arena("square", 4 * r - 1e-6)) < 4
    assert fit_count(100, r, Arena("square", 8 * r)) == 16
    with pytest.raises(ValueError, match="at most 4 fit"):
        check_capacity(5, r, Arena("square", 4 * r))


SHAPES = st.sampled_from(Arena.SHAPES)


@settings(max_examples=60, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True, database=None)
@given(
    env_id=st.sampled_from([AGGREGATION, FLOCKING, CENTROID]),
    platform=st.sampled_from(sorted(PLATFORMS)),
    shape=SHAPES,
    n=st.integers(1, 40),
    anchors=st.integers(3, 8),
    density=st.floats(0.05, 1.0),
)
def test_build_implies_every_seed_resets(env_id, platform, shape, n, anchors, density):
    """Arena sizes around the point where the robots stop fitting (density = robot area / arena area)."""
    p = PLATFORMS[platform]
    n_world = n + (anchors if env_id == CENTROID else 0)
    size = float(np.sqrt(n_world * np.pi * p.radius**2 / density))
    kwargs = {"n_robots": n, "platform": platform, "arena": shape, "arena_size": size}
    if env_id == CENTROID:
        kwargs["n_anchors"] = anchors
    try:
        swarm_envs.make(env_id, sensing="ideal", **kwargs)
    except SettingsError as err:
        event("build refused")
        assert err.key in ("arena_size", "n_robots", "n_anchors") and "fit" in str(err)
        found = re.search(r"at most (\d+) fit", str(err))
        # as many robots (seekers) as the message says do build and reset
        if found and err.key == "arena_size" and int(found.group(1)) >= 1 and (env_id != CENTROID or "seekers" in str(err)):
            assert resets(env_id, range(5), **{**kwargs, "n_robots": int(found.group(1))}) == 0
        return
    event("built")
    assert resets(env_id, range(10), **kwargs) == 0


@pytest.mark.slow
@settings(max_examples=400, deadline=None, suppress_health_check=list(HealthCheck), database=None)
@given(
    env_id=st.sampled_from([AGGREGATION, FLOCKING, CENTROID]),
    platform=st.sampled_from(sorted(PLATFORMS)),
    shape=SHAPES,
    n=st.integers(1, 120),
    anchors=st.integers(3, 12),
    density=st.floats(0.05, 1.0),
)
def test_build_implies_every_seed_resets_many(env_id, platform, shape, n, anchors, density):
    test_build_implies_every_seed_resets.hypothesis.inner_test(env_id, platform, shape, n, anchors, density)


@settings(max_examples=40, deadline=None, derandomize=True, database=None)
@given(n=st.integers(1, 60), radius=st.floats(0.01, 0.1), size=st.floats(0.02, 1.0), shape=SHAPES, seed=st.integers(0, 2**32))
def test_spawn_positions_succeeds_exactly_when_check_capacity_passes(n, radius, size, shape, seed):
    arena = Arena(shape, size)
    try:
        check_capacity(n, radius, arena)
    except ValueError:
        with pytest.raises(ValueError):
            spawn_positions(np.random.default_rng(seed), n, radius, arena)
        return
    pos = spawn_positions(np.random.default_rng(seed), n, radius, arena)
    assert pos.shape == (n, 2) and np.all(arena.contains(pos, radius))
    if n > 1:
        d = np.linalg.norm(pos[:, None] - pos[None], axis=-1) + np.eye(n)
        assert d.min() >= 2 * radius - 1e-9
