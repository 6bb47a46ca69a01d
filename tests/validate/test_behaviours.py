"""swarm-validate behaviours: trajectory figures and metrics of the r-one behaviours [L Sec. 6.4]."""

from __future__ import annotations

import json

import numpy as np
import pytest

from swarm_envs.tasks.task import MESSAGE_RANGE
from swarm_envs.validate import __main__ as validate
from swarm_envs.validate import behaviours


def test_behaviours_draws_figures_and_reports_metrics(tmp_path, capsys):
    argv = ["behaviours", "--only", "sorted_following_leader_removed", "--only", "mid_angle_navigation", "--seeds", "2",
            "--max-cycles", "40", "--out", str(tmp_path), "--json"]
    assert validate.main(argv) == 0
    res = json.loads(capsys.readouterr().out)["behaviours"]
    assert set(res) == {"sorted_following_leader_removed", "mid_angle_navigation"}
    for name, r in res.items():
        assert (tmp_path / f"behaviour_{name}.png").stat().st_size > 10_000
        assert set(r["episode"]) == set(r["mean"])  # every metric, for the drawn episode and over the seeds
    assert set(res["mid_angle_navigation"]["episode"]) == {"success_rate", "time_to_goal", "path_ratio", "collision_fraction"}
    assert behaviours.typical_seed(np.array([0.1, 0.9, 0.5, 0.4])) == 2 and behaviours.typical_seed(np.array([0.0, 1.0])) == 0


def test_the_drawn_episode_is_the_evaluated_one():
    """The figure's episode has the seed and policy generator of the evaluator's seed 0: same metrics."""
    from swarm_envs.agents.evaluation import evaluate
    from swarm_envs.agents.scripted import make_scripted

    env_id = "swarm_envs/SortedFollowing-v0"
    _, path, metrics = behaviours.run_episode_trajectory(env_id, {"n_robots": 4, "max_cycles": 30}, seed=0)
    assert path.shape == (31, 4, 2)
    per_seed = evaluate(env_id, {"sensing": "full", "n_robots": 4, "max_cycles": 30}, lambda e: make_scripted("sorted_following", e), [0])
    for name, value in metrics.items():
        assert per_seed[name][0] == pytest.approx(value, abs=1e-12)


@pytest.mark.slow
def test_measured_message_ranges_match_the_recorded_ones():
    measured = behaviours.message_ranges()
    for name, recorded in MESSAGE_RANGE.items():
        assert measured[name] == pytest.approx(recorded, abs=0.03), name
    assert np.isfinite(list(measured.values())).all()
