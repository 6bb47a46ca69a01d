"""``benchmarks/bench_train_stages.py``: the stage table of a tiny PPO run adds up to the learn time."""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.slow  # a short PPO run in a subprocess (~45 s)
def test_stage_shares_add_up():
    cmd = [sys.executable, str(ROOT / "benchmarks" / "bench_train_stages.py"), "--set", "train.total_timesteps=2560",
           "--set", "train.n_envs=2", "--set", "agent.batch_size=160", "--set", "agent.n_steps=16", "--set", "agent.n_epochs=1",
           "--set", "env.max_cycles=8"]
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, timeout=600, env=env)
    assert proc.returncode == 0, proc.stderr
    learn = float(re.search(r"robot-steps in ([0-9.]+) s of learn", proc.stdout).group(1))
    rows = dict(re.findall(r"^\| ([a-zA-Z ,]+) \| ([0-9.-]+) \|", proc.stdout, flags=re.M))
    assert {"env step", "env reset", "adapter", "rollout, policy forward", "PPO update", "rest"} <= set(rows)
    assert float(rows["env step"]) > 0 and float(rows["PPO update"]) > 0
    assert abs(sum(float(v) for v in rows.values()) - learn) < 0.02 + 0.01 * len(rows)  # printed to 0.01 s
