"""The batched core (swarm_envs.core.SwarmCore): reset steps, copy independence, static robots, the per-frame
observation cache, and the thread plan (overlapping sensing and rewards with physics) giving the same results."""

from __future__ import annotations

import numpy as np
import pytest

import swarm_envs
from swarm_envs.core import DT, SwarmCore
from tests.conftest import assert_tree_equal


def _vec(env_id: str = "swarm_envs/Aggregation-v0", num_envs: int = 2, **kwargs):
    vec = swarm_envs.make_vec(env_id, num_envs, n_robots=6, **kwargs)
    assert isinstance(vec.core, SwarmCore)
    return vec


def _part(obs, copy: int | None = None):
    """A copy of the observation (a dict of arrays or an array), of one env copy when given."""
    if isinstance(obs, dict):
        return {k: (v if copy is None else v[copy]).copy() for k, v in obs.items()}
    return (obs if copy is None else obs[copy]).copy()


def _actions(vec, seed: int) -> np.ndarray:
    return np.random.default_rng(seed).uniform(-1, 1, vec.action_space.shape)


def test_control_step_is_a_tenth_of_a_second():
    assert DT == pytest.approx(0.1)


def test_a_started_copy_does_not_move_in_its_reset_step_while_the_others_step():
    vec = _vec()
    vec.reset(seed=[1, 2])
    for k in range(3):
        vec.step(_actions(vec, k))
    core = vec.core
    before = core.state()
    core.start([1])
    core.step(np.ones((core.n_total, core.layout.action_size)))
    after = core.state()
    assert after.num_cycles.tolist() == [before.num_cycles[0] + 1, 0]
    assert not np.allclose(after.positions[0], before.positions[0])  # copy 0 drove forward
    # copy 1 was re-spawned and sensed where it was placed: the same spawn as a fresh reset of that copy
    assert np.isfinite(after.positions[1]).all()
    assert (core.last_actions[core.copy_of_robot == 1] == 0).all()


def test_actions_of_one_copy_never_reach_another():
    runs = []
    for other in (0.0, 1.0):
        vec = _vec(sensing="full")
        obs, _ = vec.reset(seed=[5, 6])
        trace = []
        for k in range(8):
            act = _actions(vec, k)
            act[1] = other  # copy 1 gets different commands in the two runs
            obs, rew, *_ = vec.step(act)
            trace.append((vec.core.state().positions[0].copy(), _part(obs, 0), rew[0].copy()))
        runs.append(trace)
    for (pos_a, obs_a, rew_a), (pos_b, obs_b, rew_b) in zip(*runs):
        np.testing.assert_array_equal(pos_a, pos_b)
        assert_tree_equal(obs_a, obs_b)
        np.testing.assert_array_equal(rew_a, rew_b)


def test_static_robots_ignore_their_action_rows():
    vec = _vec("swarm_envs/CentroidSeeking-v0", num_envs=1, sensing="ideal")
    vec.reset(seed=0)
    core = vec.core
    static = core.static
    assert static.any(), "the centroid task has static robots"
    start = core.positions[static].copy()
    for _ in range(5):
        core.step(np.ones((core.n_total, core.layout.action_size)))
    np.testing.assert_array_equal(core.positions[static], start)
    assert (core.last_actions[static] == 0).all()


def test_observations_are_built_once_per_frame():
    vec = _vec(sensing="ideal")
    vec.reset(seed=3)
    core = vec.core
    first = core.observations()
    assert core.observations() is first
    core.step(None)
    assert core.observations() is not first


@pytest.mark.parametrize("env_id", ["swarm_envs/Aggregation-v0", "swarm_envs/SortedFollowing-v0"])
def test_the_thread_plan_does_not_change_results(env_id, monkeypatch):
    """Overlapping the sensing's preparation with physics and the rewards with sensing (large scenes) gives
    the same observations and rewards as running the phases in sequence."""
    import swarm_envs.sensing.full as full

    runs = []
    for overlap in (False, True):
        monkeypatch.setattr(full, "rb_on_worker_thread", lambda *args, overlap=overlap: overlap)
        vec = _vec(env_id, sensing="full")
        obs, _ = vec.reset(seed=[11, 12])
        trace = [_part(obs)]
        for k in range(6):
            obs, rew, *_ = vec.step(_actions(vec, k))
            assert vec.core.sensing.large_scene is overlap
            trace += [_part(obs), rew.copy()]
        runs.append(trace)
    assert_tree_equal(runs[0], runs[1])


@pytest.mark.parametrize("platform", ["epuck", "rone"])
def test_one_and_two_threads_give_the_same_steps(platform, monkeypatch):
    """A batch that uses every threaded part (physics spaces in shares taken by threads, the gain kernel's and
    the occluder search's chunks, range & bearing beside SwarmCom (e-puck) or SwarmCom's slot loop in two
    groups of copies (r-one), the rewards beside the sensing; the pair threshold lowered so that a small
    batch qualifies) steps to the same observations, rewards and states on 1 and on 2 numba threads."""
    numba = pytest.importorskip("numba")
    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("needs NUMBA_NUM_THREADS >= 2")
    import swarm_envs
    from swarm_envs.comm.network import Network
    from swarm_envs.ir import layer
    from swarm_envs.sim.world import THREADED_MIN_WORLDS, physics_threads

    monkeypatch.setattr(layer, "THREADED_MIN_PAIRS", 200)
    slot_groups = []
    network_step = Network.step

    def counted(self, links, prepared=None, threads=1):
        slot_groups.append(threads)
        return network_step(self, links, prepared, threads)

    monkeypatch.setattr(Network, "step", counted)
    copies = 3 * THREADED_MIN_WORLDS  # three shares of the spaces, taken by two threads
    before = numba.get_num_threads()
    runs = []
    try:
        for threads in (1, 2):
            numba.set_num_threads(threads)
            assert physics_threads(copies) == threads
            vec = swarm_envs.make_vec("swarm_envs/Flocking-v0", copies, n_robots=8, platform=platform, sensing="full", message_bits=2)
            obs, _ = vec.reset(seed=4)
            rng = np.random.default_rng(0)
            trace = [obs]
            for _ in range(6):
                obs, rew, *_ = vec.step(rng.uniform(-1, 1, vec.action_space.shape).astype(vec.action_space.dtype))
                trace += [obs, rew, dict(vars(vec.core.state()))]
                assert vec.core.sensing.large_scene is (threads == 2)
            runs.append(trace)
            vec.close()
    finally:
        numba.set_num_threads(before)
    assert_tree_equal(runs[0], runs[1])
    assert max(slot_groups) == (2 if platform == "rone" else 1)


def test_the_core_builds_its_sensing_stack_from_the_registry():
    from swarm_envs.sensing.stacks import SENSING_STACKS, build_stack
    from swarm_envs.sim.platforms import get_platform
    from swarm_envs.tasks.settings import COMMON_SETTINGS

    assert COMMON_SETTINGS["sensing"].choices == tuple(SENSING_STACKS)
    for name, target in SENSING_STACKS.items():
        vec = _vec(sensing=name, num_envs=1)
        assert f"{type(vec.core.sensing).__module__}:{type(vec.core.sensing).__name__}" == target
        stack = build_stack(name, get_platform("epuck"), 4, vec.config, n_copies=2)
        assert type(stack) is type(vec.core.sensing)
    with pytest.raises(ValueError, match="unknown sensing stack 'exact'"):
        build_stack("exact", get_platform("epuck"), 4, vec.config)
