"""The numbers README.md and docs/validation.md quote are `swarm-validate`'s: every number in the "ours"
column of docs/validation.md's validation table and of the README's "Faithful to the papers" table occurs
in the rows of the figure it names in the committed output files (benchmarks/results/validation/*.json,
written by the commands in that folder's README.md), and every measured row of those files is quoted.
The slow test re-runs the quick experiments and finds the committed rows again."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
RESULTS = ROOT / "benchmarks" / "results" / "validation"
NUMBER = re.compile(r"(?<![\w.])-?\d+(?:,\d{3})*(?:\.\d+)?(?:e[+-]?\d+)?")
CODE = re.compile(r"`[^`]*`")
PAPER_FIGURE = re.compile(r"\[(F14|T20|L)\b.*?\b(Figs?\.\s*[\d.]+[a-z]?|Sec\.\s*[\d.]+)")


def numbers(text: str) -> set[float]:
    """The numbers in a table cell, code spans (settings, option values) left out; 1,035 is 1035."""
    return {float(x.replace(",", "")) for x in NUMBER.findall(CODE.sub(" ", text))}


def output_file(command: str) -> str:
    """The committed output file of a table row's command cell, e.g. `swarmcom --experiment a` -> swarmcom."""
    name = command.strip("` ").split()[0]
    return f"{name}-variation" if "--variation" in command else name


def load_rows() -> dict[str, list[dict[str, str]]]:
    """The compared rows of every output file that has them (behaviours.json has metrics instead)."""
    outputs = {path.stem: json.loads(path.read_text()) for path in sorted(RESULTS.glob("*.json"))}
    return {name: out["rows"] for name, out in outputs.items() if "rows" in out}


def table_rows(path: Path, heading: str) -> list[list[str]]:
    """The body rows (header and separator dropped) of the first table after ``heading``, as lists of cells."""
    text = path.read_text()
    lines = []
    for line in text[text.index(heading):].splitlines()[1:]:
        if line.startswith("|"):
            lines.append(line)
        elif lines:
            break
    rows = [[cell.strip() for cell in re.split(r"(?<!\\)\|", line)[1:-1]] for line in lines[2:]]
    assert rows, f"no table after {heading!r} in {path.name}"
    return rows


def measured(rows: list[dict[str, str]]) -> list[dict[str, str]]:
    return [r for r in rows if not r["ours"].startswith("not measured")]


def test_validation_page_quotes_the_output_files():
    outputs = load_rows()
    missing = []
    for figure, quantity, ours, *_, command in table_rows(ROOT / "docs" / "validation.md", "## The validation table"):
        rows = [r for r in outputs[output_file(command)] if r["figure"] == figure]
        assert rows, f"{figure} ({quantity}): no row of that figure in {output_file(command)}.json"
        stale = numbers(ours) - set().union(*(numbers(r["ours"]) for r in rows))
        if stale:
            missing.append(f"{figure} {quantity!r}: {sorted(stale)} not in {output_file(command)}.json")
    assert not missing, "\n".join(missing)


def headline_numbers(text: str) -> list[float]:
    """The numbers of a result in order, without its bracketed or parenthesised parts (intervals, counts,
    conditions) and code spans: ``7 [5, 8] / 10 [7, 13] (env)`` -> [7, 10]."""
    text = CODE.sub(" ", text)
    previous = None
    while previous != text:
        previous, text = text, re.sub(r"\([^()]*\)|\[[^\[\]]*\]", " ", text)
    return [float(x.replace(",", "")) for x in NUMBER.findall(text)]


def test_every_measured_row_is_quoted_on_the_validation_page():
    """Each measured row's result (its numbers outside brackets and parentheses, in order) appears in that
    order in one "ours" cell of its figure: a changed count in any position of ``7 / 10 / 12`` is caught."""
    cells: dict[str, list[list[float]]] = {}
    for figure, _quantity, ours, *_ in table_rows(ROOT / "docs" / "validation.md", "## The validation table"):
        cells.setdefault(figure, []).append(headline_numbers(ours))

    def quoted(result: list[float], cell: list[float]) -> bool:
        return any(cell[i : i + len(result)] == result for i in range(len(cell) - len(result) + 1))

    unquoted = []
    for name, rows in load_rows().items():
        for r in measured(rows):
            result = headline_numbers(r["ours"])
            if not any(quoted(result, cell) for cell in cells.get(r["figure"], [])):
                unquoted.append(f"{name}: {r['figure']} {r['quantity']!r} = {r['ours']!r}")
    assert not unquoted, "\n".join(unquoted)


def test_readme_quotes_the_output_files():
    rows = [r for file_rows in load_rows().values() for r in file_rows]
    stale = []
    for figure, quantity, ours, _paper in table_rows(ROOT / "README.md", "## Faithful to the papers"):
        paper, where = PAPER_FIGURE.search(figure).groups()
        token = re.compile(re.escape(where) + r"(?![\d])")
        same = [r for r in rows if r["figure"].startswith(f"[{paper} ") and token.search(r["figure"])]
        assert same, f"README {figure}: no output row of that figure"
        extra = numbers(ours) - set().union(*(numbers(r["ours"]) for r in same))
        if extra:
            stale.append(f"README {figure} {quantity!r}: {sorted(extra)}")
    assert not stale, "\n".join(stale)


def _matches(quoted: str, values: list[float]) -> bool:
    """``quoted`` (as printed, e.g. ``0.301`` or ``22``) is one of ``values`` or of ``100 * values`` rounded to its decimals."""
    decimals = len(quoted.split(".")[1]) if "." in quoted else 0
    x = float(quoted)
    return any(abs(round(v, decimals) - x) < 1e-9 or abs(round(100.0 * v, decimals) - x) < 1e-9 for v in values)


def test_behaviours_table_quotes_the_output_file():
    """docs/validation.md's behaviours table: every number of a row's "ours" cell is one of that behaviour's mean
    metrics or interval bounds in behaviours.json (a share may be quoted in %)."""
    behaviours = json.loads((RESULTS / "behaviours.json").read_text())["behaviours"]
    stale = []
    for name_cell, _thesis, ours in table_rows(ROOT / "docs" / "validation.md", "## The r-one's behaviours"):
        figure = re.search(r"Fig\. [\d.]+", name_cell).group(0)
        keys = [k for k, b in behaviours.items() if b["thesis_figure"] == figure
                and ("leader_removed" in k) == ("leader" in name_cell)]
        assert len(keys) == 1, f"{name_cell}: behaviours {keys}"
        values = [v for triple in behaviours[keys[0]]["mean"].values() for v in triple]
        wrong = [q for q in NUMBER.findall(CODE.sub(" ", ours)) if not _matches(q.replace(",", ""), values)]
        if wrong:
            stale.append(f"{keys[0]}: {wrong} not in behaviours.json")
    assert not stale, "\n".join(stale)


@pytest.mark.slow
@pytest.mark.parametrize("name, argv", [("range-bearing", ["range-bearing", "--no-plots"]),
                                        ("behaviours", ["behaviours", "--message-range", "--out", "plots"])])
def test_a_fresh_run_gives_the_committed_rows(name, argv, tmp_path):
    """The quick experiments (~15 s and ~45 s) re-run with the committed command give the committed rows."""
    result = subprocess.run([sys.executable, "-m", "swarm_envs.validate", *argv, "--json"],
                            cwd=tmp_path, capture_output=True, text=True, timeout=900)
    assert result.returncode == 0, result.stderr[-2000:]
    fresh, committed = json.loads(result.stdout), json.loads((RESULTS / f"{name}.json").read_text())
    if "rows" in committed:
        assert fresh["rows"] == committed["rows"]
    else:  # behaviours: the metrics per behaviour
        assert {k: b["mean"] for k, b in fresh["behaviours"].items()} == {k: b["mean"] for k, b in committed["behaviours"].items()}
