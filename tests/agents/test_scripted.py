"""Scripted behaviours: each beats random actions on its task metric, seeded, by a statistically clear margin."""

from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

import swarm_envs

from swarm_envs.agents.base import RandomPolicy
from swarm_envs.agents.evaluation import confidence_interval, evaluate, make_env, random_factory, run_episode
from swarm_envs.agents.scripted import SCRIPTED, make_scripted, scripted_class
from swarm_envs.agents.scripted_base import bump_direction, circular_mean
from swarm_envs.agents.tasks import SHORT_NAMES, headline, scripted_policy
from swarm_envs.adapters.env import DT

SEEDS = list(range(5))


@pytest.mark.parametrize(
    "task, kwargs",
    [
        ("aggregation", {"max_cycles": 150}),
        ("flocking", {"max_cycles": 120}),
        ("centroid_seeking", {"max_cycles": 200}),
    ],
)
def test_scripted_beats_random_on_task_metric(task, kwargs):
    kw = {"sensing": "ideal", **kwargs}
    metric, sign = headline(task)
    scripted = evaluate(task, kw, lambda env: make_scripted(scripted_policy(task), env), SEEDS)[metric]
    random = evaluate(task, kw, random_factory, SEEDS)[metric]
    diff = sign * (scripted - random)  # > 0 = scripted better, paired by seed
    assert np.all(diff > 0), (scripted, random)
    # one-sided paired t-test and a practically large effect
    assert stats.ttest_1samp(diff, 0.0, alternative="greater").pvalue < 0.01
    if task == "aggregation":
        assert scripted.mean() >= 0.8 and random.mean() <= 0.5  # largest-cluster fraction
    if task == "flocking":
        assert scripted.mean() > 2 * random.mean()  # polarisation
    if task == "centroid_seeking":
        assert scripted.mean() < 0.11  # within d_step = 11 cm of the centroid over the second half ([L] Sec. 6.2.2)


def test_scripted_metric_improves_over_the_episode():
    """Aggregation by bearing averaging shrinks the swarm's spread from the start to the end of an episode."""
    env = make_env("aggregation", sensing="ideal", max_cycles=120)
    policy = make_scripted("bearing_aggregation", env)
    for seed in SEEDS[:3]:
        _, infos = env.reset(seed=seed)
        start = infos["robot_0"]["metrics"]["mean_distance_to_centroid"]
        end = run_episode(env, policy, seed, "aggregation")["mean_distance_to_centroid"]
        assert end < 0.6 * start


def _displacement(policy_factory, seeds, steps=60):
    env = make_env("aggregation", sensing="ideal", n_robots=4, max_cycles=steps, arena_size=6.0)
    out = []
    for seed in seeds:
        policy = policy_factory(env)
        policy.reset(env.n_agents, np.random.default_rng(seed))
        _, infos = env.reset(seed=seed)
        start = np.array([infos[a]["ground_truth"]["position"] for a in env.possible_agents])
        while env.agents:
            parts = {k: v[env.agent_robots] for k, v in env.batched_observations().items()}
            act = policy.act_batch(parts)
            _, _, _, _, infos = env.step({a: act[i] for i, a in enumerate(env.possible_agents)})
        end = np.array([infos[a]["ground_truth"]["position"] for a in env.possible_agents])
        out.append(np.linalg.norm(end - start, axis=1).mean())
    return np.array(out)


def test_random_walk_explores_further_than_random_actions():
    """[T20] Alg. 1 drives straight for t_m = 2 s, so it travels further than i.i.d. random commands."""
    walk = _displacement(lambda env: make_scripted("random_walk", env), SEEDS)
    rand = _displacement(lambda env: RandomPolicy(env.platform, env.layout), SEEDS)
    assert walk.mean() > 1.5 * rand.mean()
    assert stats.ttest_ind(walk, rand, alternative="greater").pvalue < 0.01


def test_random_walk_follows_algorithm_1():
    env = make_env("aggregation", sensing="ideal", n_robots=3)
    policy = make_scripted("random_walk", env)
    policy.reset(3, np.random.default_rng(0))
    env.reset(seed=0)
    parts = {k: v[env.agent_robots] for k, v in env.batched_observations().items()}
    actions = np.array([policy.act_batch(parts) for _ in range(80)])  # (T, N, 2)
    step_turn = env.platform.max_angular_speed * DT
    for r in range(3):
        lin, ang = actions[:, r, 0], actions[:, r, 1]
        assert np.all((lin == 0) | (ang == 0))  # rotate, then move: never both
        turn_steps = int(np.argmax(lin != 0))
        theta = ang[:turn_steps].sum() * step_turn
        assert -np.pi <= theta <= np.pi and turn_steps == int(np.ceil(abs(theta) / step_turn - 1e-9))
        moving = lin[turn_steps : turn_steps + 20]
        assert np.all(moving == moving[0]) and -1 <= moving[0] <= 1  # constant v for t_m = 2 s = 20 steps
        assert lin[turn_steps + 20] == 0 and ang[turn_steps + 20] != 0  # then the next cycle's rotation


def test_bump_escape_turns_away_without_driving():
    env = make_env("flocking", sensing="ideal", n_robots=2)
    policy = make_scripted("orientation_flocking", env)
    policy.reset(1)
    obs = {k: np.zeros((1,) + v.shape, np.float32) for k, v in env.layout.dict_space().spaces.items()}
    obs["proprio"][0, 0] = 1.0  # frontal bump (sector 0 = ahead)
    act = policy.act_batch(obs)
    assert act[0, 0] == 0 and act[0, 1] != 0
    obs["proprio"][0, 0] = 0.0
    steps = [policy.act_batch(obs)[0] for _ in range(40)]
    turned = (act[0, 1] + sum(a[1] for a in steps if a[0] == 0)) * env.platform.max_angular_speed * DT
    assert abs(turned) == pytest.approx(np.pi, abs=1e-6)  # heading = theta_u + pi, then drives on
    assert steps[-1][0] > 0


def test_mid_angle_seeker_drives_straight_for_evade_steps_after_its_escape_turn():
    env = make_env("mid_angle_navigation", sensing="ideal")
    policy = make_scripted("mid_angle_navigation", env)
    policy.reset(1)
    obs = {k: np.zeros((1,) + v.shape, np.float32) for k, v in env.layout.dict_space().spaces.items()}
    obs["proprio"][0, 0] = 1.0  # frontal bump
    first = policy.act_batch(obs)[0]
    obs["proprio"][0, 0] = 0.0
    actions = [first] + [policy.act_batch(obs)[0].copy() for _ in range(40)]
    turning = [a[0] == 0 and a[1] != 0 for a in actions]
    n_turn = turning.index(False)
    assert n_turn >= 1 and not any(turning[n_turn:n_turn + policy.evade_steps])
    straight = [a[0] == pytest.approx(policy.speed) and a[1] == 0 for a in actions[n_turn:]]
    assert straight[:policy.evade_steps] == [True] * policy.evade_steps  # then the seeker steers (here: random walk)
    assert not straight[policy.evade_steps]


def test_helpers():
    ang, has = circular_mean(np.array([[1.0, 0.0, 1.0]]), np.array([[0.0, 1.0, 0.0]]), np.array([[1, 1, 0]], bool))
    assert has[0] and ang[0] == pytest.approx(np.pi / 4)
    _, has = circular_mean(np.ones((1, 2)), np.zeros((1, 2)), np.zeros((1, 2), bool))
    assert not has[0]
    proprio = np.zeros((1, 10))
    proprio[0, 2] = 1  # sector 2 = 90 degrees (left)
    d, b = bump_direction(proprio)
    assert b[0] and d[0] == pytest.approx(np.pi / 2)
    mean, lo, hi = confidence_interval([1.0, 2.0, 3.0])
    assert mean == 2.0 and lo < 2.0 < hi
    assert confidence_interval([4.0, 4.0]) == (4.0, 4.0, 4.0)


def test_single_robot_act_and_flat_observations():
    env = make_env("centroid_seeking", sensing="ideal", flatten=True)
    obs, _ = env.reset(seed=0)
    for name in ("centroid_seeker", "random_walk", "orientation_flocking", "bearing_aggregation"):
        policy = make_scripted(name, env)
        a = policy.act(obs["robot_0"])
        assert a.shape == (2,) and np.all(np.abs(a) <= 1)
    with pytest.raises(ValueError, match="unknown scripted policy"):
        make_scripted("nope", env)
    with pytest.raises(ValueError, match="message_bits"):
        make_scripted("mid_angle_navigation", env)
    for name in ("sorted_following", "parity_clustering"):  # they read decoded ids
        with pytest.raises(ValueError, match="observe_ids=True"):
            make_scripted(name, env).act(obs["robot_0"])


def test_sorted_following_keeps_robots_behind_their_predecessor():
    """[L] Alg. 6: robot i follows robot i-1 (decoded ids, ``observe_ids``); predecessor distance << random."""

    def pred_distance(factory, seed):
        env = make_env("flocking", sensing="ideal", n_robots=5, observe_ids=True, max_cycles=200)
        policy = factory(env)
        policy.reset(env.n_agents, np.random.default_rng(seed))
        env.reset(seed=seed)
        d = []
        while env.agents:
            parts = {k: v[env.agent_robots] for k, v in env.batched_observations().items()}
            act = policy.act_batch(parts)
            _, _, _, _, infos = env.step({a: act[i] for i, a in enumerate(env.possible_agents)})
            pos = np.array([infos[a]["ground_truth"]["position"] for a in env.possible_agents])
            d.append(np.linalg.norm(pos[1:] - pos[:-1], axis=1).mean())
        return np.mean(d[100:])

    follow = np.array([pred_distance(lambda env: make_scripted("sorted_following", env), s) for s in SEEDS[:4]])
    rand = np.array([pred_distance(lambda env: RandomPolicy(env.platform, env.layout), s) for s in SEEDS[:4]])
    assert np.all(follow < rand) and follow.mean() < 0.6 * rand.mean()


@pytest.mark.parametrize(
    "name, task, kwargs",
    [(scripted_policy(k), k, {}) for k in SHORT_NAMES]
    + [("random_walk", "aggregation", {}), ("sorted_following", "flocking", {"n_robots": 5, "observe_ids": True})],
)
def test_scripted_runs_with_full_sensing(name, task, kwargs):
    env = make_env(task, sensing="full", max_cycles=10, **kwargs)
    metrics = run_episode(env, make_scripted(name, env), 0, task)
    # path_ratio is NaN until a seeker arrives (MidAngleNavigation's definition); everything else is finite
    assert all(np.isfinite(v) or (k == "path_ratio" and np.isnan(v)) for k, v in metrics.items())


def test_registry_complete():
    for task in SHORT_NAMES:  # every task's declared baseline loads as a scripted controller
        assert scripted_class(scripted_policy(task)).name in SCRIPTED
    assert {"random_walk", "sorted_following", "parity_clustering", "mid_angle_navigation"} <= set(SCRIPTED)


@pytest.mark.slow
@pytest.mark.parametrize("task", list(SHORT_NAMES))
def test_scripted_beats_random_with_full_sensing(task):
    """~40 s: runs only when selected with ``-m slow`` (see tests/conftest.py)."""
    kw = {"sensing": "full", "max_cycles": 600 if task == "mid_angle_navigation" else 200}  # the seeker needs ~30 s
    metric, sign = headline(task)
    seeds = list(range(10))
    scripted = evaluate(task, kw, lambda env: make_scripted(scripted_policy(task), env), seeds)[metric]
    random = evaluate(task, kw, random_factory, seeds)[metric]
    diff = sign * (scripted - random)
    assert diff.mean() > 0 and stats.ttest_1samp(diff, 0.0, alternative="greater").pvalue < 0.01, (scripted, random)


@pytest.mark.parametrize(
    "task, kwargs, factory",
    [
        ("aggregation", {"sensing": "full", "max_cycles": 40}, "scripted"),
        ("flocking", {"sensing": "full", "max_cycles": 30}, "random"),
        ("centroid_seeking", {"sensing": "full", "max_cycles": 40}, "scripted"),
    ],
)
def test_batched_evaluation_equals_sequential(task, kwargs, factory):
    """Evaluating seeds as copies of one vector env gives exactly the per-seed numbers of run_episode
    (copies are bit-identical to single envs; each copy has its own policy instance and generator)."""
    make = (lambda env: make_scripted(scripted_policy(task), env)) if factory == "scripted" else random_factory
    seeds = [3, 11, 4]
    batched = evaluate(task, kwargs, make, seeds, max_copies=2)  # two chunks: 2 + 1 copies
    env = make_env(task, **kwargs)
    for i, seed in enumerate(seeds):
        single = run_episode(env, make(env), seed, task)
        assert {k: v[i] for k, v in batched.items()} == single


def test_evaluate_rejects_bad_arguments():
    with pytest.raises(ValueError, match="max_copies"):
        evaluate("aggregation", {}, random_factory, [0], max_copies=0)
    with pytest.raises(ValueError, match="at least one seed"):
        evaluate("aggregation", {}, random_factory, [])


def test_centroid_seeker_pauses_until_its_readings_are_younger_than_the_pause():
    """pause_steps=None: after a step the seeker turns only once every range & bearing reading was measured
    after it stopped (ages below the pause so far), or after MAX_PAUSE steps."""
    env = swarm_envs.make("swarm_envs/CentroidSeeking-v0", sensing="ideal")
    seeker = make_scripted("centroid_seeker", env)
    seeker.reset(1)
    obs, _ = env.reset(seed=0)
    batch = {k: v[None].copy() for k, v in obs[env.agents[0]].items()}
    batch["rigid"][:] = 0.0  # steer by the mean bearing of the rows
    batch["range_bearing"][0, :, :] = 0.0
    batch["range_bearing"][0, 0, [0, 3, 6]] = 1.0, 1.0, 7.0  # one reading to the left, 7 steps old
    for paused in range(1, 8):  # the readings stay 7 steps old: not fresh until 8 steps of pause
        assert seeker.act_batch(batch)[0, 1] == 0.0 and seeker._phase[0] == 0, paused
    assert seeker.act_batch(batch) is not None and seeker._phase[0] == 1  # the 8th step: 7 < 8, plan the turn
    seeker.reset(1)
    batch["range_bearing"][0, 0, 6] = 1000.0  # never fresh: the pause ends after MAX_PAUSE steps
    phases = [seeker.act_batch(batch) is not None and int(seeker._phase[0]) for _ in range(seeker.MAX_PAUSE)]
    assert phases[-2] == 0 and phases[-1] == 1


def test_task_robot_groups_are_drawn_in_two_colours():
    from swarm_envs.adapters.render import _ROBOT, _ROBOT_B

    env = swarm_envs.make("swarm_envs/ParityClustering-v0", sensing="ideal", render_mode="rgb_array")
    env.reset(seed=0)
    env.step({a: np.zeros(env.action_space(a).shape) for a in env.agents})
    frame = env.render()
    colours = {tuple(c) for c in frame.reshape(-1, 3)}
    assert _ROBOT in colours and _ROBOT_B in colours
    groups, labels = env.task.robot_groups()
    assert labels == ("even id", "odd id") and groups.tolist() == [i % 2 for i in range(env.n_world)]
