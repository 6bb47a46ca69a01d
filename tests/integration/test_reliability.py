"""Reliability (issue 9): reproducible resets, a spawner that scales, settings checked up front, clear errors."""

from __future__ import annotations

import math
import os
import subprocess
import sys
import textwrap
import warnings
from pathlib import Path

import numpy as np
import pytest


import swarm_envs
from swarm_envs import aggregation_v0, centroid_seeking_v0, flocking_v0
from swarm_envs.sim.platforms import PLATFORMS
from swarm_envs.sim.spawning import _best_lattice, spawn_positions
from swarm_envs.sim.arena import Arena
from tests.conftest import assert_tree_equal

ROOT = Path(__file__).resolve().parents[2]


# -- 1. a reused env after reset(seed=s) is the same as a fresh one ----------------------------------------
def dense_kwargs(env_id: str, platform: str, n: int) -> dict:
    """``n`` robots as crowded as 30 e-pucks in a 0.5 m arena (many contacts), scaled to the platform
    (CentroidSeeking: extra room, for its 4 anchors and the wider gap its seekers spawn with;
    MidAngleNavigation: its own corridor, the seekers crowded in its start square)."""
    if "MidAngle" in env_id:  # a fixed corridor: up to 10 seekers crowd its start square (contacts), relays as laid out
        return {"n_robots": min(n, 10), "platform": platform, "max_cycles": 1000}
    n_world = n + (10 if "Centroid" in env_id else 0)
    size = 0.5 * math.sqrt(n_world / 30) * PLATFORMS[platform].diameter / PLATFORMS["epuck"].diameter
    return {"n_robots": n, "arena_size": size, "platform": platform, "max_cycles": 1000}


def rollout(env, seed: int, steps: int) -> list:
    record = [env.reset(seed=seed)]
    rng = np.random.default_rng(seed + 1)
    env.contact_steps = 0
    for _ in range(steps):
        record.append(env.step({a: rng.uniform(-1, 1, env.action_space(a).shape) for a in env.agents}))
        env.contact_steps += bool(env.world.bumps.any())
    return record


def check_reused_equals_fresh(env_id: str, kwargs: dict, steps: int = 300, dirty_steps: int = 30) -> None:
    reused = swarm_envs.make(env_id, **kwargs)
    rollout(reused, 11, dirty_steps)  # an earlier episode: contacts, velocities, sensor and channel state
    contacts = reused.contact_steps
    again = rollout(reused, 5, steps)
    fresh = rollout(swarm_envs.make(env_id, **kwargs), 5, steps)
    assert contacts > 0 and reused.contact_steps > 0, "the test arena must be dense enough for contacts"
    assert_tree_equal(again, fresh)


@pytest.mark.parametrize(
    "env_id, platform",
    [
        (e, p) if p == "epuck" or e == "swarm_envs/Aggregation-v0" else pytest.param(e, p, marks=pytest.mark.slow)
        for e in swarm_envs.list_envs() for p in sorted(PLATFORMS)
    ],
)
def test_reused_env_equals_fresh_env(env_id, platform):
    """Every task on the e-puck and aggregation on every platform; the other pairs with `-m slow`."""
    check_reused_equals_fresh(env_id, {**dense_kwargs(env_id, platform, 10), "sensing": "ideal"})


def test_reused_env_equals_fresh_env_full_sensing():
    check_reused_equals_fresh("swarm_envs/Flocking-v0", {**dense_kwargs("flocking", "epuck", 6), "sensing": "full"}, dirty_steps=20)


@pytest.mark.slow
@pytest.mark.parametrize("platform", sorted(PLATFORMS))
@pytest.mark.parametrize("env_id", swarm_envs.list_envs())
def test_reused_env_equals_fresh_env_full_sensing_all(env_id, platform):
    check_reused_equals_fresh(env_id, {**dense_kwargs(env_id, platform, 30), "sensing": "full"})


# -- 2. explicit positions: no spawner -----------------------------------------------------------------------
def hex_packing(n_side: int, pitch: float) -> np.ndarray:
    i, j = np.meshgrid(np.arange(n_side), np.arange(n_side))
    pts = np.stack([(i + 0.5 * (j % 2)) * pitch, j * pitch * np.sqrt(3) / 2], -1).reshape(-1, 2)
    return pts - 0.5 * (pts.max(axis=0) + pts.min(axis=0))


def test_perfect_hex_packing_is_accepted_and_the_spawner_does_not_run(monkeypatch):
    d = PLATFORMS["epuck"].diameter
    pos = hex_packing(7, d)  # 49 robots touching their neighbours
    env = aggregation_v0.parallel_env(n_robots=49, sensing="ideal", arena_size=7.6 * d)

    def no_spawn(rng):
        raise AssertionError("the spawner ran although positions were given")

    monkeypatch.setattr(env.task, "spawn", no_spawn)
    env.reset(seed=0, options={"positions": pos})
    np.testing.assert_array_equal(env.world.positions, pos)
    assert np.all(np.abs(env.world.headings) <= np.pi)  # positions alone: headings from the spawn stream
    env.step({a: np.zeros(2) for a in env.agents})
    # far away in a big arena too (a spawner that enumerated the 30 m arena first would take seconds)
    big = flocking_v0.parallel_env(n_robots=3, sensing="ideal", arena_size=30.0)
    monkeypatch.setattr(big.task, "spawn", no_spawn)
    far = np.array([[-14.0, -14.0], [0.0, 0.0], [14.0, 14.0]])
    big.reset(seed=1, options={"positions": far, "headings": np.array([0.1, 0.2, 0.3])})
    np.testing.assert_array_equal(big.world.positions, far)
    np.testing.assert_allclose(big.world.headings, [0.1, 0.2, 0.3])


def test_headings_alone_keep_the_task_spawn_and_positions_alone_are_seeded():
    env = aggregation_v0.parallel_env(n_robots=5, sensing="ideal")
    env.reset(seed=4)
    spawned = env.world.positions.copy()
    env.reset(seed=4, options={"headings": np.full(5, 0.5)})
    np.testing.assert_array_equal(env.world.positions, spawned)
    np.testing.assert_allclose(env.world.headings, 0.5)
    pos = spawned[::-1].copy()
    env.reset(seed=4, options={"positions": pos})
    first = env.world.headings.copy()
    env.reset(seed=4, options={"positions": pos})
    np.testing.assert_array_equal(env.world.headings, first)


# -- 3. spawner cost O(robots) --------------------------------------------------------------------------------
@pytest.mark.parametrize("shape", Arena.SHAPES)
@pytest.mark.parametrize("size", [0.05, 0.1, 0.2, 0.33, 0.75, 1.5, 3.0])
def test_capacity_lower_bound_is_a_lower_bound(shape, size):
    from swarm_envs.sim.spawning import lattice_lower_bound

    arena = Arena(shape, size)
    for radius, gap in ((0.035, 0.0035), (0.022, 0.0), (0.055, 0.011)):
        assert lattice_lower_bound(arena, radius, gap) <= len(_best_lattice(arena, radius, gap))


def test_spawner_does_not_enumerate_a_roomy_arena(monkeypatch):
    import swarm_envs.sim.spawning as spawning

    def enumerate_lattice(*args, **kwargs):
        raise AssertionError("the spawner enumerated the whole arena")

    monkeypatch.setattr(spawning, "_best_lattice", enumerate_lattice)
    for size in (100.0, 1e4):
        for shape in Arena.SHAPES:
            pos = spawn_positions(np.random.default_rng(0), 10, 0.035, Arena(shape, size))
            assert pos.shape == (10, 2) and np.all(Arena(shape, size).contains(pos, 0.035))
    env = aggregation_v0.parallel_env(n_robots=10, arena_size=1e4, sensing="ideal")
    env.reset(seed=0)
    env.step({a: np.ones(2) for a in env.agents})


# -- 4./5. settings checked up front, finite, for every sensing mode ---------------------------------------
BAD_SETTINGS = [
    ("relative_threshold", math.nan),
    ("relative_threshold", math.inf),
    ("relative_threshold", True),
    ("rb_noise", math.nan),
    ("rb_noise", math.inf),
    ("rb_noise", True),
    ("rb_noise", -1.0),
    ("arena_size", math.inf),
    ("code", (15, 9)),
    ("code", (15, 0)),
    ("code", (15, 16)),
    ("code", (15.0, 15)),
    ("message_bits", 256),
    ("n_neighbours", 2.0),
    ("max_cycles", -1),
    ("bitrate", True),
]


@pytest.mark.parametrize("sensing", ["ideal", "full"])
@pytest.mark.parametrize("key,value", BAD_SETTINGS)
def test_bad_setting_fails_in_the_constructor(key, value, sensing):
    with pytest.raises(ValueError, match=key):
        flocking_v0.parallel_env(n_robots=3, sensing=sensing, **{key: value})


@pytest.mark.parametrize("value", [math.nan, math.inf, True, -0.1])
def test_bad_collision_penalty(value):
    with pytest.raises(ValueError, match="collision_penalty"):
        flocking_v0.parallel_env(sensing="ideal", collision_penalty=value)


@pytest.mark.parametrize("sensing", ["ideal", "full"])
def test_too_many_anchors_is_a_capacity_error(sensing):
    with pytest.raises(ValueError, match=r"n_anchors=200 .*at most \d+ fit"):
        centroid_seeking_v0.parallel_env(n_anchors=200, sensing=sensing)
    env = centroid_seeking_v0.parallel_env(n_anchors=20, sensing="ideal")  # many, but they fit
    env.reset(seed=0)


def test_good_settings_still_pass_and_resolve():
    from swarm_envs.registry import task_class
    from swarm_envs.tasks.settings import validate_settings

    cfg = validate_settings(task_class("swarm_envs/Flocking-v0"), {"code": [15, 7], "message_bits": 255, "rb_noise": 0})
    assert cfg["code"] == (15, 7) and cfg["collision_penalty"] == 0.1 and cfg["n_robots"] == 10
    with pytest.raises(TypeError, match="unknown keyword"):
        validate_settings(task_class("swarm_envs/Flocking-v0"), {"n_anchors": 4})


@pytest.mark.parametrize(
    "override,key",
    [
        ("env.code=[15,9]", "env.code"),
        ("env.code=[15,0]", "env.code"),
        ("env.message_bits=256", "env.message_bits"),
        ("env.relative_threshold=.nan", "env.relative_threshold"),
        ("env.rb_noise=.inf", "env.rb_noise"),
        ("env.rb_noise=true", "env.rb_noise"),
    ],
)
def test_config_check_runs_the_env_validator(override, key):
    from swarm_envs.agents.config import ConfigError, load_config

    with pytest.raises(ConfigError, match=f"config key '{key}'") as err:
        load_config(None, [override])  # sensing='full' (the default) stays 'full', never swapped for 'ideal'
    assert "\n" not in str(err.value)


def test_config_check_catches_anchor_capacity():
    from swarm_envs.agents.config import ConfigError, load_config

    with pytest.raises(ConfigError, match="env.n_anchors"):
        load_config(None, ["task=centroid_seeking", "env.n_anchors=200"])


# -- 6. make keeps max_cycles --------------------------------------------------------------------------------
@pytest.mark.parametrize("env_id", swarm_envs.list_envs())
def test_make_rejects_max_cycles_minus_one(env_id):
    with pytest.raises(ValueError, match="max_cycles"):
        swarm_envs.make(env_id, max_cycles=-1, sensing="ideal")
    env = swarm_envs.make(env_id, max_cycles=2, sensing="ideal")
    env.reset(seed=0)
    still = np.zeros(env.layout.action_size)  # (linear, angular) and the task's default message bits
    env.step({a: still for a in env.agents})
    _, _, _, trunc, _ = env.step({a: still for a in env.agents})
    assert all(trunc.values()) and env.agents == []


# -- 9. clear messages -------------------------------------------------------------------------------------------
@pytest.fixture
def env():
    e = aggregation_v0.parallel_env(n_robots=3, sensing="ideal")
    e.reset(seed=0)
    return e


@pytest.mark.parametrize("options", ["positions", [("positions", 1)], 3])
def test_non_dict_reset_options(env, options):
    with pytest.raises(TypeError, match="reset options must be a dict"):
        env.reset(options=options)


@pytest.mark.parametrize("seed,error", [(-1, ValueError), (1.5, TypeError), (True, TypeError), ("3", TypeError)])
def test_bad_seed(env, seed, error):
    with pytest.raises(error, match="seed must be a non-negative integer"):
        env.reset(seed=seed)


@pytest.mark.parametrize("action", [["1", "0"], np.array(["1", "0"]), np.array([1 + 0j, 0j]), [True, False], [None, 1.0]])
def test_non_real_actions_are_rejected(env, action):
    actions = {a: np.zeros(2) for a in env.agents}
    actions["robot_1"] = action
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no ComplexWarning: a clear error instead
        with pytest.raises(TypeError, match="real-valued numeric array"):
            env.step(actions)


def test_centroid_metric_is_never_nan_and_is_the_second_half_so_far():
    env = centroid_seeking_v0.parallel_env(sensing="ideal", max_cycles=9)
    _, infos = env.reset(seed=2)
    distances = [infos["robot_0"]["metrics"]["mean_distance_to_centroid"]]
    assert infos["robot_0"]["metrics"]["mean_distance_second_half"] == pytest.approx(distances[0])
    for t in range(1, 10):
        _, _, _, _, infos = env.step({"robot_0": np.array([1.0, 0.4])})
        m = infos["robot_0"]["metrics"]
        distances.append(m["mean_distance_to_centroid"])
        assert np.isfinite(m["mean_distance_second_half"])
        assert m["mean_distance_second_half"] == pytest.approx(np.mean(distances[math.ceil(t / 2):]))


# -- 10. a corrupted numba cache is recompiled with a warning --------------------------------------------------
def _run(code: str, cache_dir: Path, cwd: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache_dir), "PYTHONPATH": f"{cwd}{os.pathsep}{ROOT}"}
    return subprocess.run([sys.executable, "-c", code], cwd=cwd, env=env, capture_output=True, text=True, timeout=600)


def _corrupt(cache_dir: Path) -> int:
    files = sorted(cache_dir.rglob("*.nbi")) + sorted(cache_dir.rglob("*.nbc"))
    for i, f in enumerate(files):
        f.write_bytes(b"garbage" if i % 2 else b"\x80\x04garbage")  # not a pickle / a broken one
    return len(files)


def test_guarded_numba_cache_recovers(tmp_path):
    (tmp_path / "kern.py").write_text(
        textwrap.dedent(
            """
            from swarm_envs._compile._numba import njit

            @njit(cache=True)
            def twice(x):
                return 2.0 * x
            """
        )
    )
    code = "import warnings; warnings.simplefilter('always'); import kern; print(kern.twice(2.0))"
    first = _run(code, tmp_path / "cache", tmp_path)
    assert first.returncode == 0 and first.stdout.strip() == "4.0", first.stderr
    assert _corrupt(tmp_path / "cache") >= 2
    second = _run(code, tmp_path / "cache", tmp_path)
    assert second.returncode == 0 and second.stdout.strip() == "4.0", second.stderr
    assert "NumbaCacheWarning" in second.stderr and "recompiling" in second.stderr
    third = _run(code, tmp_path / "cache", tmp_path)  # the rewritten cache is good again
    assert third.returncode == 0 and "NumbaCacheWarning" not in third.stderr, third.stderr


@pytest.mark.slow
def test_env_reset_recovers_from_a_corrupted_ir_kernel_cache(tmp_path):
    code = (
        "import warnings; warnings.simplefilter('always'); from swarm_envs import flocking_v0;"
        "e = flocking_v0.parallel_env(n_robots=4); e.reset(seed=0); print('ok')"
    )
    assert _run(code, tmp_path / "cache", ROOT).returncode == 0
    assert _corrupt(tmp_path / "cache") >= 2
    again = _run(code, tmp_path / "cache", ROOT)
    assert again.returncode == 0 and again.stdout.strip() == "ok", again.stderr
    assert "NumbaCacheWarning" in again.stderr
