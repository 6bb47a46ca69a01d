"""make_vec refuses copies that would not fit in memory (issue #31, defect 6): ~320 KB per copy of one robot
at reset (more over an episode), so the accepted 100,000 copies would need tens of GB; an OOM kill instead of
an error before. The available-memory reader is replaced here, so the tests build nothing large."""

from __future__ import annotations

import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import swarm_envs
import swarm_envs.adapters.memory as memory
from swarm_envs.tasks.settings import SettingsError

ROOT = Path(__file__).resolve().parents[2]
GIB = 2**30


def test_make_vec_refuses_copies_beyond_the_available_memory(monkeypatch):
    monkeypatch.setattr(memory, "available_memory", lambda: 16 * GIB)
    with pytest.raises(SettingsError) as err:
        swarm_envs.make_vec("swarm_envs/Aggregation-v0", 100_000, n_robots=1)
    message = str(err.value)
    assert err.value.key == "num_envs" and "\n" not in message
    assert "num_envs=100000 copies of 1 robot(s) would need ~" in message and "the machine has 16.00 GiB available" in message


def _mem_available() -> int | None:
    try:
        return next(int(line.split()[1]) * 1024 for line in open("/proc/meminfo") if line.startswith("MemAvailable:"))
    except (OSError, StopIteration):
        return None


def _timeout(signum, frame):
    raise TimeoutError("make_vec kept building copies for 10 s instead of refusing them")


@pytest.mark.skipif((_mem_available() or 1 << 62) > 50 * GIB, reason="needs a machine with less than 50 GiB available")
def test_the_accepted_maximum_of_copies_is_refused_up_front_on_this_machine():
    """100,000 copies of one robot need ~60 GiB over an episode: refused at once, nothing allocated (before,
    make_vec built them until the machine ran out of memory)."""
    old = signal.signal(signal.SIGALRM, _timeout)
    signal.setitimer(signal.ITIMER_REAL, 10.0)
    try:
        with pytest.raises(SettingsError, match="num_envs=100000 copies .* GiB available"):
            swarm_envs.make_vec("swarm_envs/Aggregation-v0", 100_000, n_robots=1)
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def test_the_copies_the_memory_holds_build(monkeypatch):
    """The estimate decides: as many copies as it fits build, one more is refused."""
    per_copy = memory.copy_memory(swarm_envs.make("swarm_envs/Flocking-v0").task)
    monkeypatch.setattr(memory, "available_memory", lambda: 3 * per_copy)
    vec = swarm_envs.make_vec("swarm_envs/Flocking-v0", 3)
    vec.reset(seed=0)
    with pytest.raises(SettingsError, match="use at most 3 copies"):
        swarm_envs.make_vec("swarm_envs/Flocking-v0", 4)


def test_an_unknown_available_memory_checks_nothing(monkeypatch):
    monkeypatch.setattr(memory, "available_memory", lambda: None)
    assert swarm_envs.make_vec("swarm_envs/Aggregation-v0", 2).num_envs == 2


def test_the_estimate_grows_with_copies_robots_walls_episode_and_the_tasks_own_arrays():
    one = swarm_envs.make("swarm_envs/Aggregation-v0", n_robots=1).task
    ten = swarm_envs.make("swarm_envs/Aggregation-v0", n_robots=10).task
    circle = swarm_envs.make("swarm_envs/Aggregation-v0", n_robots=1, arena="circle").task
    long = swarm_envs.make("swarm_envs/Aggregation-v0", n_robots=1, max_cycles=5000).task
    assert memory.copy_memory(ten) - memory.copy_memory(one) >= 9 * memory.ROBOT_BYTES
    assert memory.copy_memory(circle) - memory.copy_memory(one) == 60 * memory.WALL_BYTES  # 64 segments instead of 4
    assert memory.copy_memory(long) > memory.copy_memory(one) + 4000 * memory.LOG_STEP_BYTES
    # MidAngleNavigation's relays remember a hop count per pair of static robots: 24 bytes per pair
    mid = swarm_envs.make("swarm_envs/MidAngleNavigation-v0", arena_size=40.0).task
    assert memory.copy_memory(mid) > 24 * mid.n_static**2 + mid.n_world * memory.ROBOT_BYTES


def test_available_memory_reads_the_machine():
    available = memory.available_memory()
    if sys.platform.startswith("linux"):
        total = next(int(line.split()[1]) * 1024 for line in open("/proc/meminfo") if line.startswith("MemTotal:"))
        assert 0 < available <= total


def test_train_config_refuses_more_copies_than_the_memory_holds(monkeypatch):
    from swarm_envs.agents.config import ConfigError, load_config

    monkeypatch.setattr(memory, "available_memory", lambda: 1 * GIB)
    with pytest.raises(ConfigError, match=r"config key 'train.n_envs': 100000 env copies .* the machine has 1.00 GiB available"):
        load_config(ROOT / "configs" / "aggregation.yaml", ["train.n_envs=100000", "env.n_robots=1"])
    load_config(ROOT / "configs" / "aggregation.yaml", ["train.n_envs=8"])


MEASURE = textwrap.dedent(
    """
    import gc, sys, numpy as np, swarm_envs
    from swarm_envs.adapters.memory import copy_memory
    def rss():
        return next(int(l.split()[1]) * 1024 for l in open("/proc/self/status") if l.startswith("VmHWM:"))
    B, n, steps = (int(a) for a in sys.argv[1:4])
    kw = dict(n_robots=n, max_cycles=steps)
    warm = swarm_envs.make_vec("swarm_envs/Aggregation-v0", 2, **kw)
    warm.reset(seed=0); warm.step(np.zeros(warm.action_space.shape)); del warm; gc.collect()
    before = rss()
    vec = swarm_envs.make_vec("swarm_envs/Aggregation-v0", B, **kw)
    vec.reset(seed=0)
    action = np.random.default_rng(0).uniform(-1, 1, vec.action_space.shape)
    for _ in range(steps):
        vec.step(action)
    print((rss() - before) / B, copy_memory(swarm_envs.make("swarm_envs/Aggregation-v0", **kw).task))
    """
)


@pytest.mark.slow
@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc/self/status")
@pytest.mark.parametrize("copies, robots, steps", [(1000, 1, 200), (200, 10, 200), (20, 100, 100), (4, 1000, 20)])
def test_the_estimate_covers_the_measured_peak_memory(copies, robots, steps):
    """Peak resident memory (VmHWM) per copy, measured in a fresh process, within the estimate and above a third of it."""
    out = subprocess.run([sys.executable, "-c", MEASURE, str(copies), str(robots), str(steps)], capture_output=True, text=True, cwd=ROOT, check=True)
    measured, estimate = (float(x) for x in out.stdout.split()[-2:])
    assert estimate / 3 < measured <= estimate, (measured, estimate)
