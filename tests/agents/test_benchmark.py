"""``python -m swarm_envs.agents.benchmark``: task selection (repeatable or comma list) on tiny episodes."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from swarm_envs.agents import benchmark

ROOT = Path(__file__).resolve().parents[2]
TINY = ["--episodes", "2", "--max-cycles", "3", "--sensing", "ideal", "--n-robots", "4"]


def test_one_task(capsys):
    assert benchmark.main(["--task", "aggregation", *TINY]) == 0
    out = capsys.readouterr().out
    assert "## aggregation" in out and "## flocking" not in out and "## centroid_seeking" not in out
    assert "n=2 seeds" in out and "| largest_cluster_fraction |" in out


def test_tasks_repeated_and_comma_list(capsys):
    assert benchmark.main(["--task", "flocking,aggregation", "--task", "aggregation", *TINY, "--json"]) == 0
    res = json.loads(capsys.readouterr().out)
    assert list(res) == ["flocking", "aggregation"]
    assert {r["policy"] for r in res["flocking"]["rows"]} == {"orientation_flocking", "random_walk", "random"}


def test_unknown_task_is_a_usage_error(capsys):
    with pytest.raises(SystemExit) as exc:
        benchmark.main(["--task", "herding", *TINY])
    assert exc.value.code == 2 and "unknown task 'herding'" in capsys.readouterr().err


def test_module_runs_with_one_episode():
    """``python -m swarm_envs.agents.benchmark`` as a command; one episode gives means without intervals (n=1)."""
    cmd = [sys.executable, "-m", "swarm_envs.agents.benchmark", "--task", "centroid_seeking", "--episodes", "1", "--max-cycles", "3",
           "--sensing", "ideal", "--json"]
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert "centroid_seeking/" not in proc.stderr, proc.stderr  # no evaluation bars: stderr is not a terminal
    res = json.loads(proc.stdout)
    assert list(res) == ["centroid_seeking"]
    assert all(r["n"] == 1 and r["ci_low"] is None and r["ci_high"] is None for r in res["centroid_seeking"]["rows"])
