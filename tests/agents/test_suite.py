"""The benchmark-table command (swarm_envs.agents.suite): the runs it plans, resuming, the table, the intervals
and the sensing-cost table."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from scipy import stats

from swarm_envs.agents import suite as suite_mod
from swarm_envs.agents.evaluation import t_interval

ROOT = Path(__file__).resolve().parents[2]
TINY = [
    "env.sensing=ideal",
    "env.n_robots=3",
    "env.max_cycles=10",
    "train.total_timesteps=120",
    "train.n_envs=2",
    "train.checkpoint_freq=0",
    "agent.n_steps=20",
    "agent.batch_size=60",
    "agent.n_epochs=1",
    "eval.n_seeds=2",
]


def _suite_file(tmp_path: Path, **task) -> Path:
    entry = {"config": str(ROOT / "configs" / "sorted_following.yaml"), "variants": {"mlp": {}, "odometry": {"agent.odometry": True}}, **task}
    path = tmp_path / "suite.yaml"
    path.write_text(yaml.safe_dump({"seeds": [0, 1], "tasks": {"sorted_following": entry}}))
    return path


def test_shipped_suite_names_every_task_and_existing_configs():
    suite = suite_mod.load_suite(ROOT / "configs" / "suite" / "benchmark.yaml")
    assert set(suite["tasks"]) == {"aggregation", "flocking", "centroid_seeking", "sorted_following", "parity_clustering", "mid_angle_navigation"}
    assert len(suite["seeds"]) >= 3
    for entry in suite["tasks"].values():
        assert Path(entry["config"]).is_file() and "_long" in entry["config"]
        assert "mlp" in entry["variants"] and entry["variants"]["mlp"] == {}, "the plain MLP PPO stays the reference row"
        assert entry["sensing_cost"] in entry["variants"]


def test_plan_covers_variants_seeds_and_the_sensing_cost(tmp_path):
    suite = suite_mod.load_suite(_suite_file(tmp_path, sensing_cost="odometry"))
    runs = suite_mod.plan(suite, tmp_path / "out")
    dirs = [str(Path(r["dir"]).relative_to(tmp_path / "out")) for r in runs]
    assert dirs == [
        "sorted_following/baselines",
        "sorted_following/mlp/seed0", "sorted_following/mlp/seed1",
        "sorted_following/odometry/seed0", "sorted_following/odometry@ideal/seed0", "sorted_following/odometry@ideal/seed0/eval-full",
        "sorted_following/odometry/seed1", "sorted_following/odometry@ideal/seed1", "sorted_following/odometry@ideal/seed1/eval-full",
    ]
    assert "--baselines-only" in runs[0]["argv"]
    ideal = runs[4]["argv"]
    assert ideal[-2:] == ["--set", "env.sensing=ideal"] and "agent.odometry=true" in ideal
    assert runs[5]["argv"][-2:] == ["--eval-only", str(tmp_path / "out" / "sorted_following" / "odometry@ideal" / "seed0" / "model.zip")]
    subset = suite_mod.plan(suite, tmp_path / "out", seeds=[1], variants=["mlp"])
    assert [Path(r["dir"]).name for r in subset] == ["baselines", "seed1"]
    no_cost = suite_mod.plan(suite, tmp_path / "out", variants=["odometry"], sensing_cost=False)
    assert [str(Path(r["dir"]).relative_to(tmp_path / "out" / "sorted_following")) for r in no_cost] == [
        "baselines", "odometry/seed0", "odometry/seed1"]


@pytest.mark.parametrize(
    "text, message",
    [
        ("tasks: {}\n", "needs a 'tasks' mapping"),
        ("seeds: [-1]\ntasks: {a: {config: x.yaml, variants: {mlp: {}}}}\n", "'seeds' must be a list"),
        ("tasks: {a: {config: x.yaml}}\n", "needs 'config' and a 'variants' mapping"),
        ("tasks: {a: {config: x.yaml, variants: {mlp: {}}, sensing_cost: best}}\n", "sensing_cost names no variant"),
        ("tasks: {a: {config: x.yaml, variants: {'m@x': {}}}}\n", "no '@' or '/'"),
    ],
)
def test_bad_suite_files_fail_clearly(tmp_path, text, message):
    path = tmp_path / "bad.yaml"
    path.write_text(text)
    with pytest.raises(ValueError, match=message):
        suite_mod.load_suite(path)


def test_t_interval_is_students():
    values = [0.2, 0.5, 0.4]
    mean, lo, hi = t_interval(values)
    half = stats.t.ppf(0.975, 2) * np.std(values, ddof=1) / math.sqrt(3)
    assert mean == pytest.approx(np.mean(values)) and lo == pytest.approx(mean - half) and hi == pytest.approx(mean + half)
    assert math.isnan(t_interval([0.3])[1])


@pytest.mark.slow
def test_suite_end_to_end_resumes_and_reports(tmp_path, capsys):
    """One variant with its sensing cost and one seed, on a tiny budget: every run, the tables and the curves;
    a second call starts no run."""
    path = _suite_file(tmp_path, sensing_cost="odometry")
    out = tmp_path / "out"
    argv = ["--suite", str(path), "--output", str(out), "--variants", "odometry", "--seeds", "0", "--jobs", "2"]
    argv += [x for kv in TINY for x in ("--set", kv)]
    assert suite_mod.main(argv) == 0
    task = out / "sorted_following"
    for d in ("baselines", "odometry/seed0", "odometry@ideal/seed0", "odometry@ideal/seed0/eval-full"):
        assert (task / d / "results.csv").is_file(), d
    baselines = json.loads((task / "baselines" / "per_seed.json").read_text())
    assert set(baselines) == {"scripted", "random", "seeds"}
    trained = json.loads((task / "odometry" / "seed0" / "per_seed.json").read_text())
    assert set(trained) == {"ppo", "seeds"} and trained["seeds"] == baselines["seeds"], "every policy on the same evaluation seeds"
    rows = list(csv.DictReader(open(out / "results.csv")))
    assert [r["policy"] for r in rows] == ["rl:odometry", "scripted", "random"]
    assert float(rows[0]["mean"]) == pytest.approx(np.mean(trained["ppo"]["following_fraction"]))
    cost = (out / "sensing_cost.md").read_text()
    assert "| sorted_following (following_fraction) | odometry |" in cost and "not run" not in cost
    assert (out / "curves_sorted_following.png").is_file()
    timing = json.loads((out / "timing.json").read_text())
    assert timing["sorted_following"] > 0

    capsys.readouterr()
    assert suite_mod.main(argv) == 0
    assert "ran 0 runs" in capsys.readouterr().out


def test_unknown_task_is_one_line(tmp_path, capsys):
    assert suite_mod.main(["--suite", str(_suite_file(tmp_path)), "--tasks", "herding", "--output", str(tmp_path / "o")]) == 2
    assert "unknown task(s) ['herding']" in capsys.readouterr().err


def test_concurrent_runs_share_the_cores(monkeypatch):
    monkeypatch.delenv("NUMBA_NUM_THREADS", raising=False)
    monkeypatch.setattr(suite_mod.os, "cpu_count", lambda: 4)
    assert suite_mod.job_environment(2)["NUMBA_NUM_THREADS"] == "2"
    assert suite_mod.job_environment(8)["NUMBA_NUM_THREADS"] == "1"
    assert suite_mod.job_environment(1)["NUMBA_NUM_THREADS"] == "4"
    monkeypatch.setenv("NUMBA_NUM_THREADS", "3")
    assert suite_mod.job_environment(2)["NUMBA_NUM_THREADS"] == "3"
