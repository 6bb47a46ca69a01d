"""TorchRL: the batched env (make_torchrl) over one SwarmVectorEnv: specs, copy-exactness, resets, state, seeds."""

import numpy as np
import pytest

import swarm_envs

pytest.importorskip("torchrl", reason="torchrl is not installed: pip install -e '.[torchrl]'")
import torch  # noqa: E402
from torchrl.envs.utils import check_env_specs  # noqa: E402

B, N = 3, 4
GROUP = "agents"


def make(env_id="swarm_envs/Flocking-v0", num_envs=B, **kwargs):
    return swarm_envs.make_torchrl(env_id, num_envs, **{"n_robots": N, "max_cycles": 5, "sensing": "ideal", **kwargs})


def actions(step: int, shape) -> torch.Tensor:
    return torch.from_numpy(np.random.default_rng(step).uniform(-1, 1, shape).astype(np.float32))


@pytest.mark.parametrize("env_id", swarm_envs.list_envs())
@pytest.mark.parametrize("sensing", ["ideal", "full"])
@pytest.mark.parametrize("flatten", [False, True])
def test_check_env_specs_and_layout(env_id, sensing, flatten):
    env = make(env_id, sensing=sensing, flatten=flatten, seed=0)
    check_env_specs(env)
    assert env.batch_size == (B,) and env.group_map == {GROUP: [f"robot_{i}" for i in range(N)]}
    obs_spec = env.observation_spec[GROUP, "observation"]
    space = env.vec.agent_observation_space
    if flatten:
        assert obs_spec.shape == (B, N, space.shape[0])
    else:
        assert set(obs_spec.keys()) == set(space.spaces)
        assert all(obs_spec[k].shape == (B, N, *space[k].shape) for k in space.spaces)
    assert env.full_action_spec[GROUP, "action"].shape == (B, N, env.vec.layout.action_size)
    assert env.full_reward_spec[GROUP, "reward"].shape == (B, N, 1)
    for key in ("done", "terminated", "truncated"):
        assert env.full_done_spec[key].shape == (B, 1)
        assert env.full_done_spec[GROUP, key].shape == (B, N, 1)
    infos = set(env.observation_spec[GROUP, "info"].keys())
    assert {"ground_truth_position", "ground_truth_heading", "ground_truth_velocity"} <= infos
    assert any(k.startswith("reward_terms_") for k in infos)
    assert any(k.startswith("sensing_") for k in infos) == (sensing == "full")
    assert "episode_step" in env.observation_spec["info"].keys()


@pytest.mark.parametrize("sensing", ["ideal", "full"])
@pytest.mark.parametrize("flatten", [False, True])
def test_copies_equal_make_vec_copies_bit_for_bit(sensing, flatten):
    env_id = "swarm_envs/Aggregation-v0"
    env = make(env_id, sensing=sensing, flatten=flatten, seed=7)
    vec = swarm_envs.make_vec(env_id, B, n_robots=N, max_cycles=5, sensing=sensing, flatten=flatten)
    td = env.reset()
    obs, infos = vec.reset(seed=7)
    for t in range(12):  # two episodes and a bit: the reset between them is TorchRL's (all copies)
        got = td[GROUP, "observation"]
        if flatten:
            np.testing.assert_array_equal(got.numpy(), obs)
        else:
            for k, v in obs.items():
                np.testing.assert_array_equal(got[k].numpy(), v, err_msg=k)
        np.testing.assert_array_equal(td["state"].numpy(), vec.states())
        np.testing.assert_array_equal(td[GROUP, "info", "ground_truth_position"].numpy(), infos["ground_truth"]["position"].astype(np.float32))
        for name, value in infos["metrics"].items():
            np.testing.assert_array_equal(td["info", name].numpy(), value.astype(np.float32))
        a = actions(t, (B, N, 2))
        td.set((GROUP, "action"), a)
        td = env.step(td)
        obs, rew, term, trunc, infos = vec.step(a.numpy())
        np.testing.assert_array_equal(td["next", GROUP, "reward"].squeeze(-1).numpy(), rew)
        np.testing.assert_array_equal(td["next", GROUP, "truncated"].squeeze(-1).numpy(), trunc)
        np.testing.assert_array_equal(td["next", "done"].squeeze(-1).numpy(), trunc.any(axis=1) | term.any(axis=1))
        if trunc.any():  # episodes end together; TorchRL resets them, make_vec restarts them at its next step
            assert trunc.all()
            td = env.reset()
            obs, infos = vec.reset()  # unseeded: both continue each copy's generator
        else:
            td = td["next"]


def test_copy_b_equals_a_single_env_seeded_s_plus_b():
    env = make("swarm_envs/CentroidSeeking-v0", sensing="full", seed=11)
    singles = [swarm_envs.make("swarm_envs/CentroidSeeking-v0", n_robots=N, max_cycles=5, sensing="full") for _ in range(B)]
    td = env.reset()
    for b, single in enumerate(singles):
        single.reset(seed=11 + b)
    for t in range(4):
        a = actions(t, (B, N, 2))
        td.set((GROUP, "action"), a)
        td = env.step(td)["next"]
        for b, single in enumerate(singles):
            obs, rew, *_ = single.step({agent: a[b, i].numpy() for i, agent in enumerate(single.possible_agents)})
            for i, agent in enumerate(single.possible_agents):
                for k, v in obs[agent].items():
                    np.testing.assert_array_equal(td[GROUP, "observation", k][b, i].numpy(), v)
            np.testing.assert_array_equal(td["state"][b].numpy(), single.state())
            np.testing.assert_array_equal(td[GROUP, "reward"][b, :, 0].numpy(), np.float32([rew[a] for a in single.possible_agents]))


def test_rollout_resets_all_copies_at_the_episode_end():
    env = make(max_cycles=4, seed=0)
    td = env.rollout(10, break_when_any_done=False)
    assert td.shape == (B, 10)
    done = td["next", "done"].squeeze(-1)
    assert done[:, 3].all() and done[:, 7].all() and done.sum() == 2 * B
    steps = td["info", "episode_step"]
    np.testing.assert_array_equal(steps[0].numpy(), [0, 1, 2, 3, 0, 1, 2, 3, 0, 1])
    assert td["next", GROUP, "reward"].abs().sum() > 0


def test_reset_masks():
    env = make(seed=3)
    first = env.reset()
    td = first.clone()
    td.set((GROUP, "action"), actions(0, (B, N, 2)))
    stepped = env.step(td)["next"]
    # an all-false mask leaves every copy where it is
    keep = stepped.clone()
    keep.set("_reset", torch.zeros(B, 1, dtype=torch.bool))
    same = env.reset(keep)
    torch.testing.assert_close(same["state"], stepped["state"], rtol=0, atol=0)
    # a mask of every copy (root or group key) resets all of them
    full = stepped.clone()
    full.set((GROUP, "_reset"), torch.ones(B, N, 1, dtype=torch.bool))
    again = env.reset(full)
    assert (again["info", "episode_step"] == 0).all()
    assert not torch.equal(again["state"], first["state"])  # new spawns (the generators went on)
    # a mask of some copies: the core senses all copies in one step, so this is refused
    some = again.clone()
    some.set("_reset", torch.tensor([[True], [False], [False]]))
    with pytest.raises(ValueError, match="_reset"):
        env.reset(some)


def test_step_after_the_end_needs_a_reset():
    env = make(max_cycles=2, seed=0)
    td = env.reset()
    for t in range(2):
        td.set((GROUP, "action"), actions(t, (B, N, 2)))
        td = env.step(td)["next"]
    assert td["done"].all()
    td.set((GROUP, "action"), actions(9, (B, N, 2)))
    with pytest.raises(RuntimeError, match="reset"):
        env.step(td)


def test_state_equals_single_env_state_and_is_ground_truth():
    env = make("swarm_envs/Aggregation-v0", seed=5)
    singles = [swarm_envs.make("swarm_envs/Aggregation-v0", n_robots=N, max_cycles=5, sensing="ideal") for _ in range(B)]
    td = env.reset()
    for b, single in enumerate(singles):
        single.reset(seed=5 + b)
        np.testing.assert_array_equal(td["state"][b].numpy(), single.state())
    positions = td["state"][:, : 7 * N].reshape(B, N, 7)[..., :2]
    torch.testing.assert_close(positions, td[GROUP, "info", "ground_truth_position"], rtol=0, atol=0)


def test_seeds_are_deterministic_and_distinct():
    def first_states(seed):
        env = make(seed=seed)
        td = env.rollout(3)
        return td["next", "state"]

    torch.manual_seed(0)
    a = first_states(1)
    torch.manual_seed(0)  # the rollout's random actions
    b = first_states(1)
    torch.manual_seed(0)
    c = first_states(2)
    torch.testing.assert_close(a, b, rtol=0, atol=0)
    assert not torch.equal(a, c)
    env = make(seed=4)
    td = env.reset()
    assert not torch.equal(td["state"][0], td["state"][1])  # copy b is seeded with seed + b


def test_bad_arguments_raise_one_line_errors():
    with pytest.raises(ValueError, match="num_envs"):
        swarm_envs.make_torchrl("swarm_envs/Flocking-v0", 0)
    with pytest.raises(ValueError, match="unknown environment id"):
        swarm_envs.make_torchrl("swarm_envs/Nope-v0", 2)
    with pytest.raises(ValueError, match="group"):
        swarm_envs.make_torchrl("swarm_envs/Flocking-v0", 2, group="next")
    with pytest.raises(TypeError):
        swarm_envs.make_torchrl("swarm_envs/Flocking-v0", 2, not_a_setting=1)


def test_sets_torch_threads_by_default_and_on_request(monkeypatch):
    from swarm_envs.adapters.torch_threads import default_torch_threads

    before = torch.get_num_threads()
    try:
        monkeypatch.delenv("OMP_NUM_THREADS", raising=False)
        torch.set_num_threads(2)
        make(num_envs=1)
        assert torch.get_num_threads() == default_torch_threads()
        make(num_envs=1, torch_threads=2)
        assert torch.get_num_threads() == 2
        monkeypatch.setenv("OMP_NUM_THREADS", "3")
        make(num_envs=1)
        assert torch.get_num_threads() == 3
        torch.set_num_threads(2)
        make(num_envs=1, torch_threads=0)  # 0: leave torch's setting
        assert torch.get_num_threads() == 2
    finally:
        torch.set_num_threads(before)
