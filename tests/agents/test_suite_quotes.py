"""The benchmark table quoted in README.md and docs/training.md is the suite's own output
(benchmarks/results/suite), so a rerun that changes a number cannot leave the documents behind."""
import csv
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SUITE = ROOT / "benchmarks" / "results" / "suite"


def _table_lines(path: Path) -> list[str]:
    return [line for line in path.read_text().splitlines() if line.startswith("| ") and "---" not in line]


def _results() -> dict[tuple[str, str], dict[str, str]]:
    with open(SUITE / "results.csv") as fh:
        return {(row["task"], row["policy"]): row for row in csv.DictReader(fh)}


@pytest.mark.parametrize("table", ["results.md", "sensing_cost.md"])
def test_training_page_quotes_the_suite_tables(table):
    page = (ROOT / "docs" / "training.md").read_text()
    lines = _table_lines(SUITE / table)
    assert lines, f"{table} has no table rows"
    missing = [line for line in lines if line not in page]
    assert not missing, f"docs/training.md does not quote these rows of {table}:\n" + "\n".join(missing)


def _matches(printed: str, value: float) -> bool:
    """``printed`` is ``value`` rounded to the digits it shows (any rounding the table uses)."""
    decimals = len(printed.split(".")[1]) if "." in printed else 0
    return abs(float(printed) - value) <= 0.5 * 10 ** -decimals + 1e-12


def test_readme_benchmark_table_quotes_results_csv():
    results = _results()
    rows = [line for line in _table_lines(ROOT / "README.md") if re.match(r"\| `\w+_long`", line)]
    tasks = {task for task, _ in results}
    assert {re.match(r"\| `(\w+)_long`", row).group(1) for row in rows} == tasks, "README lacks a suite task"
    columns = ["rl:mlp", "rl:odometry", "rl:deepsets", "scripted", "random"]
    for row in rows:
        task = re.match(r"\| `(\w+)_long`", row).group(1)
        cells = [cell.strip() for cell in row.strip("|").split("|")][2:]
        assert len(cells) == len(columns), row
        for policy, cell in zip(columns, cells):
            if not cell:
                assert (task, policy) not in results, f"README leaves out {task} {policy}"
                continue
            number = re.match(r"([0-9.]+)( \((\d+) seeds\))?$", cell)
            assert number, f"README cell {cell!r} ({task} {policy}) is not a number"
            entry = results[(task, policy)]
            assert _matches(number.group(1), float(entry["mean"])), (
                f"README quotes {task} {policy} as {number.group(1)}; results.csv has {entry['mean']}")
            if number.group(3):
                assert int(number.group(3)) == int(entry["n"]), f"{task} {policy}: seeds"
