"""docs/training.md's quick-config tables quote the runs kept in benchmarks/results/quick_runs (their README
names each run's command), so a number on the page is a number a run produced."""

from __future__ import annotations

import csv
import json
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
RUNS = ROOT / "benchmarks" / "results" / "quick_runs"
PAGE = (ROOT / "docs" / "training.md").read_text()
NUMBER = re.compile(r"\d+(?:\.\d+)?")

#: "What the r-one tasks needed": (task cell, start of the overrides cell) -> run folder
ABLATION_ROWS = {
    ("sorted following", "`agent.encoder=mlp agent.odometry=false` (plain MLP)"): "ablation_sf_mlp_noodo",
    ("sorted following", "`agent.encoder=mlp` (MLP + odometry)"): "sorted_following_mlp",
    ("sorted following", "`agent.odometry=false` (DeepSets)"): "ablation_sf_ds_noodo",
    ("sorted following", "none (DeepSets + odometry, as shipped)"): "sorted_following",
    ("sorted following", "`agent.encoder=mlp agent.odometry=false agent.algorithm=recurrent_ppo`"): "ablation_sf_rppo",
    ("sorted following", "`agent.encoder=mlp agent.frame_stack=4`"): "ablation_sf_fs4",
    ("sorted following", "`agent.encoder=mlp agent.action_repeat=4`"): "ablation_sf_ar4",
    ("mid-angle navigation", "`agent.odometry=false train.total_timesteps=60000` (plain MLP)"): "ablation_mid_60k",
    ("mid-angle navigation", "`agent.odometry=false env.sensing=ideal`"): "ablation_mid_ideal",
    ("mid-angle navigation", "none (odometry, 300k, as shipped)"): "mid_angle_navigation",
    ("mid-angle navigation", "`train.total_timesteps=600000 train.n_envs=64`"): "ablation_mid_600k",
    ("parity clustering", "`agent.odometry=false env.reward_term=separation agent.reward_scale=10` (plain MLP)"): "ablation_par_sep",
    ("parity clustering", "the same with `env.sensing=ideal`"): "ablation_par_sep_ideal",
    ("parity clustering", "`agent.odometry=false env.sensing=ideal` (segregation reward)"): "ablation_par_seg_ideal",
    ("parity clustering", "none but the budget (odometry, segregation reward)"): "ablation_par_odo",
    ("parity clustering", "the same with 600k robot-steps"): "ablation_par_odo600",
}


def _cells(line: str) -> list[str]:
    return [cell.strip() for cell in line.strip().strip("|").split("|")]


def _headline(run: str) -> dict[str, dict[str, float]]:
    """policy -> {mean, ci_low, ci_high, n} of the run's headline metric."""
    metric = re.search(r"headline metric `(\w+)`", (RUNS / run / "results.md").read_text()).group(1)
    with open(RUNS / run / "results.csv") as fh:
        return {row["policy"]: {k: float(row[k]) for k in ("mean", "ci_low", "ci_high", "n")} for row in csv.DictReader(fh) if row["metric"] == metric}


def _agrees(printed: str, value: float) -> bool:
    """``printed`` is ``value`` rounded to the digits it shows."""
    decimals = len(printed.split(".")[1]) if "." in printed else 0
    return abs(float(printed) - value) <= 0.5 * 10**-decimals + 1e-12


def _check_cell(cell: str, entry: dict[str, float], what: str) -> None:
    """A cell "mean" or "mean [low, high]" (bold allowed) against the run's values."""
    numbers = NUMBER.findall(cell.replace("*", ""))
    assert numbers, f"{what}: {cell!r} has no number"
    for printed, key in zip(numbers, ("mean", "ci_low", "ci_high")):
        assert _agrees(printed, entry[key]), f"{what}: {key} printed {printed}, the run has {entry[key]}"


def _rows_starting(prefix: str) -> list[list[str]]:
    return [_cells(line) for line in PAGE.splitlines() if line.startswith(prefix)]


@pytest.mark.parametrize("key", sorted(ABLATION_ROWS), ids=lambda key: f"{key[0]}: {key[1][:40]}")
def test_ablation_row_quotes_its_run(key):
    run = ABLATION_ROWS[key]
    rows = [cells for cells in _rows_starting(f"| {key[0]} |") if cells[1] == key[1]]
    assert len(rows) == 1, f"docs/training.md has {len(rows)} rows for {key}"
    headline = _headline(run)
    for cell, policy in zip(rows[0][2:5], ("ppo", "scripted", "random")):
        _check_cell(cell, headline[policy], f"{key} {policy}")


def test_every_ablation_row_is_checked():
    section = PAGE.split("## What the r-one tasks needed")[1].split("What this shows")[0]
    rows = [tuple(_cells(line)[:2]) for line in section.splitlines() if line.startswith("| ") and "---" not in line][1:]
    assert set(rows) == set(ABLATION_ROWS)


def test_quick_config_rows_quote_their_runs():
    rows = _rows_starting("| `")
    quick = {re.match(r"`(\w+)`", cells[0]).group(1): cells for cells in rows if len(cells) == 9}
    assert set(quick) == {"aggregation", "flocking", "centroid_seeking", "sorted_following", "parity_clustering", "mid_angle_navigation"}
    for task, cells in quick.items():
        headline = _headline(task)
        timing = json.loads((RUNS / task / "timing.json").read_text())
        assert cells[3] == f"{round(timing['robot_steps'] / 1000)}k", f"{task}: robot-steps"
        assert cells[4] == f"{round(timing['train_s'])} s", f"{task}: train time {cells[4]}, the run took {timing['train_s']:.1f} s"
        for cell, policy in zip(cells[5:8], ("ppo", "scripted", "random")):
            _check_cell(cell, headline[policy], f"{task} {policy}")
        assert int(cells[8]) == headline["ppo"]["n"], f"{task}: evaluation seeds"
