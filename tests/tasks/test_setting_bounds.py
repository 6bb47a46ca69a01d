"""Every accepted setting runs (issue #31, defect 4): for every built-in task and platform, the smallest and
largest accepted arena and message width reset, and the envs at the documented limits build in bounded time.
Settings a task cannot run are refused at make() with a one-line error naming the setting, the value and
the allowed range."""

from __future__ import annotations

import signal
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest

import swarm_envs
from swarm_envs import get_platform
import swarm_envs.tasks.mid_angle_navigation_v0 as mid
from swarm_envs.registry import task_class
from swarm_envs.tasks.settings import COMMON_SETTINGS, SettingsError

BUILT_IN = [env_id for env_id in swarm_envs.list_envs() if env_id.startswith("swarm_envs/")]
PLATFORMS = ["droplet", "epuck", "rone"]
MID = "swarm_envs/MidAngleNavigation-v0"
ROOT = Path(__file__).resolve().parents[2]
#: seconds make() + reset() may take at a documented limit (measured ~0.5-2 s on a busy 2-core machine)
TIME_BOUND = 20.0


@contextmanager
def time_limit(seconds: float) -> Iterator[None]:
    """Raise ``TimeoutError`` in the block once ``seconds`` (s) have passed (SIGALRM; main thread only)."""

    def fail(signum, frame):
        raise TimeoutError(f"did not return within {seconds} s")

    old = signal.signal(signal.SIGALRM, fail)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def accepted(env_id: str, **kwargs) -> swarm_envs.SwarmEnv | None:
    """The env if make() accepts ``kwargs``, None if it refuses them with a SettingsError."""
    try:
        return swarm_envs.make(env_id, **kwargs)
    except SettingsError:
        return None


def smallest_arena(env_id: str, platform: str, shape: str) -> float:
    """The smallest ``arena_size`` (m, to 0.4 mm) make() accepts, by bisection between a refused and an accepted side."""
    refused, ok = 0.0, 4.0
    assert accepted(env_id, platform=platform, arena=shape, arena_size=ok) is not None
    while ok - refused > 4e-4:
        mid = 0.5 * (refused + ok)
        if accepted(env_id, platform=platform, arena=shape, arena_size=mid) is None:
            refused = mid
        else:
            ok = mid
    return ok


def check_resets(env: swarm_envs.SwarmEnv, seeds: range = range(5)) -> None:
    """Every seed resets with the robots inside the walls and apart, and the env steps."""
    r = env.platform.radius
    for seed in seeds:
        env.reset(seed=seed)
        pos = env.world.positions
        assert env.arena.wall_depth(pos, r).max() <= 1e-9, "a robot starts past a wall"
        gaps = np.linalg.norm(pos[:, None] - pos[None], axis=-1) + np.eye(len(pos)) * 1e9
        assert gaps.min() >= 2 * r - 1e-9, "robots start overlapping"
        env.step({a: np.ones(env.action_space(a).shape) for a in env.agents})


def shapes(env_id: str) -> list[str]:
    return ["square"] if env_id == MID else ["square", "circle"]


# -- arena_size --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("env_id, shape", [(e, s) for e in BUILT_IN for s in shapes(e)])
@pytest.mark.parametrize("platform", PLATFORMS)
def test_the_smallest_accepted_arena_resets(env_id, platform, shape):
    size = smallest_arena(env_id, platform, shape)
    env = swarm_envs.make(env_id, platform=platform, arena=shape, arena_size=size)
    check_resets(env)
    if env_id == MID:  # the documented bound, and no seeker starts (or arrives after one step) at the goal
        assert size == pytest.approx(mid.arena_size_range(get_platform(platform), 1)[0], abs=5e-4)
        env.reset(seed=0)
        pos = env.world.positions
        assert np.linalg.norm(pos[env.n_static :] - pos[0], axis=1).min() > mid.ARRIVAL_RADII * env.platform.radius
        _, _, _, _, infos = env.step({a: np.r_[1.0, 0.0, np.ones(env.layout.message_bits)] for a in env.agents})
        assert infos["robot_0"]["metrics"]["success_rate"] == 0.0


@pytest.mark.parametrize("env_id, shape", [(e, s) for e in BUILT_IN if e != MID for s in shapes(e)])
@pytest.mark.parametrize("platform", PLATFORMS)
def test_the_largest_accepted_arena_resets(env_id, platform, shape):
    high = COMMON_SETTINGS["arena_size"].high
    with time_limit(TIME_BOUND):
        env = swarm_envs.make(env_id, platform=platform, arena=shape, arena_size=high)
        check_resets(env, range(2))
    assert accepted(env_id, platform=platform, arena=shape, arena_size=high * (1 + 1e-9)) is None


@pytest.mark.parametrize("platform", ["rone", "epuck", "droplet"])
@pytest.mark.parametrize("size", [0.4, 0.45, 0.5, 0.6, 0.7, 0.8])
def test_mid_angle_arenas_too_small_for_its_corridor_are_refused_at_make(platform, size):
    """A side below the corridor's minimum is refused at make (otherwise every reset would fail with "robots
    overlap", the seeker on the goal, or the seeker would start within the arrival radius: success 1.0 after
    one step); a side at or above it resets."""
    low, high = mid.arena_size_range(get_platform(platform), 1)
    if size >= low:
        env = swarm_envs.make(MID, platform=platform, arena_size=size)
        check_resets(env, range(2))
        return
    with pytest.raises(SettingsError) as err:
        swarm_envs.make(MID, platform=platform, arena_size=size)
    message = str(err.value)
    assert err.value.key == "arena_size" and "\n" not in message
    assert f"arena_size={size:g} m" in message and f"allowed [{low:g}, {high:g}] m" in message and "arrival radius" in message


@pytest.mark.parametrize("platform", PLATFORMS)
@pytest.mark.parametrize("lanes", [1, 2, 12])
def test_mid_angle_arena_range_is_what_the_corridor_builds(platform, lanes):
    """Below the range and above it make() refuses at once; at its top the corridor holds at most (and
    nearly) MAX_STATIC_ROBOTS static robots."""
    p = get_platform(platform)
    low, high = mid.arena_size_range(p, lanes)
    for size in (low - 1e-3, high + 1e-3, 10_000.0):
        with time_limit(5.0), pytest.raises(SettingsError, match=r"allowed \[") as err:
            swarm_envs.make(MID, platform=platform, lanes=lanes, arena_size=size)
        assert err.value.key == "arena_size" and "\n" not in str(err.value)
    assert 0.98 * mid.MAX_STATIC_ROBOTS <= 1 + len(mid.corridor(high, lanes, p).relays) <= mid.MAX_STATIC_ROBOTS  # and no looser
    # the smallest side resets (every seed: a layout of walls and relays of its own)
    check_resets(swarm_envs.make(MID, platform=platform, lanes=lanes, arena_size=low, sensing="ideal"), range(3))


@pytest.mark.parametrize("platform", PLATFORMS)
def test_mid_angle_at_the_common_arena_bound_is_refused_at_once(platform):
    """arena_size=10000 (the common rule's bound) is refused within seconds by the task's own, tighter bound
    (building such an arena would not return for minutes)."""
    with time_limit(10.0), pytest.raises(SettingsError, match=r"arena_size=10000 m is out of range .* allowed \[") as err:
        swarm_envs.make(MID, platform=platform, arena_size=10_000.0)
    assert err.value.key == "arena_size" and "\n" not in str(err.value)


def _timed_make_reset(platform: str, lanes: int, sensing: str) -> tuple[swarm_envs.SwarmEnv, float]:
    swarm_envs.make(MID, platform=platform, lanes=lanes, sensing=sensing).reset(seed=0)  # compiled kernels, not timed
    high = mid.arena_size_range(get_platform(platform), lanes)[1]
    start = time.perf_counter()
    with time_limit(3 * TIME_BOUND):
        env = swarm_envs.make(MID, platform=platform, lanes=lanes, arena_size=high, sensing=sensing)
        env.reset(seed=0)
    return env, time.perf_counter() - start


def test_mid_angle_at_its_largest_arena_builds_and_resets_in_bounded_time():
    """The cheap case of the next test: the r-one's one-lane corridor at its largest side, ideal sensing."""
    env, seconds = _timed_make_reset("rone", 1, "ideal")
    assert seconds < TIME_BOUND and env.n_static <= mid.MAX_STATIC_ROBOTS
    env.step({a: np.zeros(env.action_space(a).shape) for a in env.agents})


@pytest.mark.slow
@pytest.mark.parametrize("platform", PLATFORMS)
@pytest.mark.parametrize("lanes", [1, 2, 12])
def test_mid_angle_at_its_largest_arena_builds_and_resets_in_bounded_time_everywhere(platform, lanes):
    env, seconds = _timed_make_reset(platform, lanes, "full")
    assert seconds < TIME_BOUND and env.n_static <= mid.MAX_STATIC_ROBOTS
    check_resets(env, range(2))


# -- message_bits ------------------------------------------------------------------------------------------
def message_rule(env_id: str):
    return task_class(env_id).settings().get("message_bits", COMMON_SETTINGS["message_bits"])


@pytest.mark.parametrize("env_id", BUILT_IN)
@pytest.mark.parametrize("platform", PLATFORMS)
def test_the_narrowest_and_widest_accepted_messages_run(env_id, platform):
    """Both ends of each task's message_bits range build, reset and step (a range wider than the payload a
    task can hold would fail at reset with OverflowError)."""
    rule = message_rule(env_id)
    for bits in (rule.low, rule.high):
        env = swarm_envs.make(env_id, platform=platform, message_bits=bits)
        env.reset(seed=0)
        for _ in range(3):
            env.step({a: np.ones(env.action_space(a).shape) for a in env.agents})
    with pytest.raises(SettingsError) as err:
        swarm_envs.make(env_id, platform=platform, message_bits=rule.high + 1)
    assert err.value.key == "message_bits" and f"[{rule.low}, {rule.high}]" in str(err.value) and "\n" not in str(err.value)


@pytest.mark.parametrize("bits", [64, 255])
def test_mid_angle_refuses_messages_wider_than_a_hop_count(bits):
    with pytest.raises(SettingsError, match=rf"message_bits must be an integer in \[1, {mid.MAX_HOP_BITS}\] .*hop count.*got {bits}"):
        swarm_envs.make(MID, message_bits=bits)


def test_hop_counts_fill_the_widest_message():
    """At 63 bits the goal sends 0, its neighbours 1, and a relay that knows no route 2**63 - 1 ("unknown")."""
    env = swarm_envs.make(MID, sensing="ideal", lanes=3, message_bits=mid.MAX_HOP_BITS)
    env.reset(seed=1)
    for _ in range(60):
        env.step({a: np.zeros(env.layout.action_size) for a in env.agents})
    bits = env.core._static_payloads[: env.n_static]
    sent = [sum(1 << i for i in np.flatnonzero(row)) for row in bits]  # Python integers: no overflow
    assert sent[0] == 0 and 1 in sent
    assert all(0 < value < env.n_static or value == 2**mid.MAX_HOP_BITS - 1 for value in sent[1:])


# -- train.py's up-front check -----------------------------------------------------------------------------
@pytest.mark.parametrize("override, key", [("env.message_bits=64", "message_bits"), ("env.arena_size=0.6", "arena_size"), ("env.arena_size=10000", "arena_size")])
def test_train_config_refuses_what_the_env_cannot_run(override, key):
    from swarm_envs.agents.config import ConfigError, load_config

    with time_limit(TIME_BOUND), pytest.raises(ConfigError, match=f"config key 'env.{key}'"):
        load_config(ROOT / "configs" / "mid_angle_navigation.yaml", [override])
