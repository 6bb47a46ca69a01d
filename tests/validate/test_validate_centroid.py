"""[L Sec. 6.2.2] centroid seeking in the env: the thesis's pause-for-a-round controller."""

import numpy as np
import pytest

from swarm_envs.sim.platforms import get_platform
from swarm_envs.sensing.full import BEACON_PERIOD
from swarm_envs.validate.centroid import D_STEP, PauseStepSeeker, experiment_env, trial_layouts
from swarm_envs.validate.envs import scene_core


def test_seeker_pauses_for_a_round_then_steps_d_step():
    poly, start, h0 = trial_layouts(3, 1, 1, (0.3, 0.5))[0]
    core = scene_core("swarm_envs/CentroidSeeking-v0", [np.vstack([poly, start])], [np.r_[np.zeros(4), h0]], [0],
                      n_robots=1, n_anchors=4, platform="rone", arena_size=2.0)
    plat = get_platform("rone")
    seeker = PauseStepSeeker(1, plat.max_speed, plat.max_angular_speed, pause_steps=BEACON_PERIOD)
    row = core.agent_rows()[0, 0]
    actions, positions, moved = [], [], []
    for _ in range(4 * (BEACON_PERIOD + 8)):
        obs = {k: v[[row]] for k, v in core.observations().items()}
        a = seeker.act(obs)[0]
        full = np.zeros((core.n_total, 2))
        full[row] = a
        core.step(full)
        actions.append(a)
        positions.append(core.positions[row].copy())
        moved.append(bool(seeker.moved[0]))
    actions, positions = np.array(actions), np.array(positions)
    ends = np.flatnonzero(moved)
    assert len(ends) >= 3
    # the first round: still from the reset until the first plan
    assert np.all(actions[: BEACON_PERIOD - 1] == 0)
    for i in ends[:-1]:
        still = slice(i + 1, i + BEACON_PERIOD)  # pause: zero actions, the robot stands still ...
        assert np.all(actions[still] == 0)
        assert np.abs(positions[still] - positions[i]).max() < 1e-3
        assert np.any(actions[i + BEACON_PERIOD] != 0)  # ... then turns or drives
    for a, b in zip(ends[1:-1], ends[2:]):
        assert abs(np.hypot(*(positions[b] - positions[a])) - D_STEP) < 0.02  # one step of 11 cm (physics)


def test_env_experiment_runs_every_trial_its_rounds():
    res = experiment_env(seed=1, polygons=1, starts=2, rounds=4, r_range=(0.3, 0.5), pause_steps=BEACON_PERIOD)
    assert res["trials_complete"] == res["trials"] == 2
    assert res["rounds"] == 8
    assert np.isfinite(res["mean_second_half_cm"])
    # rounds take at least a pause each
    assert res["control_steps"] >= 4 * BEACON_PERIOD


def test_seeker_rejects_a_zero_pause():
    with pytest.raises(ValueError, match="pause_steps"):
        PauseStepSeeker(1, 0.3, 7.5, pause_steps=0)
