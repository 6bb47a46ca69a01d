"""The policy variants of train.py (swarm_envs.agents.policies): odometry, action repeat, frame stacking, the
set encoder and RecurrentPPO, and that evaluation runs the same pipeline as training."""

from __future__ import annotations

import numpy as np
import pytest
import torch
from gymnasium import spaces

import swarm_envs
from swarm_envs.agents.base import flatten_batch
from swarm_envs.agents.policies import (
    DT,
    N_BUMP_SECTORS,
    DecisionVecEnv,
    Odometry,
    PolicySpec,
    SetEncoder,
    TrainedPolicy,
    build_model,
    row_groups,
    wrap_training_env,
)
from swarm_envs.agents.sb3_vec_env import SwarmVecEnv

SORTED = "swarm_envs/SortedFollowing-v0"
SMALL = {"n_robots": 3, "max_cycles": 12}


@pytest.fixture(scope="module")
def env():
    e = swarm_envs.make(SORTED, **SMALL)
    yield e
    e.close()


def _flat_with(layout, n: int, rows: dict[int, tuple[float, int]], angular: float) -> np.ndarray:
    """Flat observations of ``n`` robots: range_bearing row k valid with bearing b (rad) and age a for
    ``rows[k] = (b, a)``; last action (0, ``angular``)."""
    parts = {name: np.zeros((n, *box.shape), np.float32) for name, box in layout.dict_space().spaces.items()}
    for k, (bearing, age) in rows.items():
        parts["range_bearing"][:, k] = [1, 0, np.cos(bearing), np.sin(bearing), 1, 0, age]
    parts["proprio"][:, N_BUMP_SECTORS + 1] = angular
    return flatten_batch(layout, parts)


def test_odometry_turns_a_reading_back_by_the_rotation_since_it_was_measured(env):
    layout, platform = env.layout, env.platform
    odometry = Odometry(layout, platform)
    odometry.reset(1)
    w = 0.25  # angular action: a quarter of full angular speed, within the wheel limits at zero linear speed
    for _ in range(5):  # five steps of turning
        odometry(_flat_with(layout, 1, {}, w))
    out = layout.unflatten(odometry(_flat_with(layout, 1, {0: (0.3, 0), 1: (0.3, 4), 2: (0.3, 6)}, w)))
    bearing = np.arctan2(out["range_bearing"][0, :3, 3], out["range_bearing"][0, :3, 2])
    step = w * platform.max_angular_speed * DT
    # age 0: measured now; age a: the robot has turned a steps since (the newest step included)
    np.testing.assert_allclose(bearing, [0.3, 0.3 - 4 * step, 0.3 - 6 * step], atol=1e-5)
    heading = np.arctan2(out["range_bearing"][0, :3, 5], out["range_bearing"][0, :3, 4])
    np.testing.assert_allclose(heading, [0.0, -4 * step, -6 * step], atol=1e-5)
    assert not out["range_bearing"][0, 3:].any(), "empty rows stay empty"


def test_odometry_uses_the_wheel_limited_rotation(env):
    layout, platform = env.layout, env.platform
    odometry = Odometry(layout, platform)
    odometry.reset(1)
    flat = _flat_with(layout, 1, {}, 1.0)
    flat[0, layout.unflatten(np.arange(flat.shape[1]))["proprio"][N_BUMP_SECTORS]] = 1.0  # full speed ahead too
    odometry(flat)
    # full linear and full angular saturate one wheel: the robot turns at half its maximum rate
    assert odometry.turned[0, 0] == pytest.approx(0.5 * platform.max_angular_speed * DT)


def test_action_repeat_holds_the_action_and_sums_the_rewards():
    inner = SwarmVecEnv(SORTED, 2, SMALL)
    reference = SwarmVecEnv(SORTED, 2, SMALL)
    for v in (inner, reference):
        v.seed(3)
    wrapped = DecisionVecEnv(inner, inner.layout, inner.platform, odometry=False, action_repeat=3)
    obs = wrapped.reset()
    np.testing.assert_array_equal(obs, reference.reset())
    actions = np.random.default_rng(0).uniform(-1, 1, (inner.num_envs, inner.layout.action_size)).astype(np.float32)
    obs, rewards, dones, _ = wrapped.step(actions)
    total = np.zeros(inner.num_envs, np.float32)
    for _ in range(3):
        ref_obs, r, _, _ = reference.step(actions)
        total += r
    np.testing.assert_array_equal(obs, ref_obs)
    np.testing.assert_allclose(rewards, total, rtol=1e-6)
    # 12-step episodes: the 4th decision ends them (dones), the next observation is the new episode's first
    for _ in range(3):
        obs, rewards, dones, infos = wrapped.step(actions)
    assert dones.all() and "terminal_observation" in infos[0]
    wrapped.close()
    reference.close()


def test_set_encoder_ignores_row_order_and_empty_rows(env):
    layout = env.layout
    groups = row_groups(layout)
    size = groups["size"]
    encoder = SetEncoder(spaces.Box(-np.inf, np.inf, (size,), np.float32), groups, embedding=8)
    rng = np.random.default_rng(1)
    flat = rng.uniform(-1, 1, (1, size)).astype(np.float32)
    parts = layout.unflatten(flat.copy())
    for name in ("range_bearing", "scale_free", "messages"):
        parts[name][..., 0] = 0.0
        parts[name][:, :3, 0] = 1.0  # three valid rows, the rest empty (with junk in them)
    flat = flatten_batch(layout, parts)
    out = encoder(torch.as_tensor(flat))
    permuted = {k: v.copy() for k, v in parts.items()}
    order = [2, 0, 1]
    for base, ids in (("range_bearing", "range_bearing_ids"), ("scale_free", "scale_free_ids"), ("messages", "message_ids")):
        for name in (base, ids):
            permuted[name][:, :3] = parts[name][:, order]
            permuted[name][:, 3:] = rng.uniform(-1, 1, permuted[name][:, 3:].shape)  # other junk in the empty rows
        permuted[base][:, 3:, 0] = 0.0
    out_permuted = encoder(torch.as_tensor(flatten_batch(layout, permuted)))
    torch.testing.assert_close(out, out_permuted)


def _agent(**changes):
    from swarm_envs.agents.config import DEFAULTS

    return {**DEFAULTS["agent"], "n_steps": 8, "batch_size": 24, **changes}


@pytest.mark.parametrize(
    "changes",
    [
        {"odometry": True, "action_repeat": 2, "frame_stack": 3},
        {"encoder": "deepsets", "frame_stack": 2},
        {"algorithm": "recurrent_ppo", "odometry": True, "action_repeat": 3},
        {"algorithm": "recurrent_ppo", "encoder": "deepsets"},
    ],
    ids=["odometry-repeat-stack", "deepsets-stack", "recurrent-odometry-repeat", "recurrent-deepsets"],
)
def test_evaluation_acts_like_training(changes):
    """The evaluation policy (one env copy, the env's own observations) takes exactly the actions the model
    takes through the training wrappers on the same copy."""
    agent = _agent(**changes)
    spec = PolicySpec.from_agent(agent)
    venv = SwarmVecEnv(SORTED, 1, SMALL)
    wrapped = wrap_training_env(venv, spec, venv.layout, venv.platform)
    model = build_model(agent, wrapped, venv.layout, seed=0)
    venv.seed(5)  # after the model, which seeds its env
    policy = TrainedPolicy(model, venv.platform, venv.layout, spec)

    obs = wrapped.reset()
    state, starts = None, np.ones(venv.num_envs, dtype=bool)
    train_actions = []
    for _ in range(SMALL["max_cycles"] // spec.action_repeat):
        if spec.algorithm == "recurrent_ppo":
            actions, state = model.predict(obs, state=state, episode_start=starts, deterministic=True)
            starts[:] = False
        else:
            actions, _ = model.predict(obs, deterministic=True)
        actions = np.clip(actions, -1, 1)
        train_actions += [actions] * spec.action_repeat
        obs, _, dones, _ = wrapped.step(actions)
    assert dones.all()
    wrapped.close()

    env = swarm_envs.make(SORTED, **SMALL, flatten=False)
    env.reset(seed=5)
    policy.reset(env.n_agents)
    for step in range(SMALL["max_cycles"]):
        parts = {k: v[env.agent_robots] for k, v in env.batched_observations().items()}
        actions = policy.act_batch(parts)
        np.testing.assert_allclose(actions, train_actions[step], atol=1e-6, err_msg=f"step {step}")
        env.step({a: actions[i] for i, a in enumerate(env.possible_agents)})
    env.close()


def test_spec_names():
    assert PolicySpec().name == "ppo"
    assert PolicySpec(algorithm="recurrent_ppo", encoder="deepsets", odometry=True, action_repeat=2, frame_stack=4).name == (
        "recurrent_ppo+deepsets+odometry+repeat2+stack4")
