"""The environment pages quote benchmarks/results/showcase_seeds.json (``python benchmarks/showcase_seeds.py``).

Each page's caption gives the GIF's episode (the showcase seed) beside the random policy's on the same seed,
and the means over seeds 0-7. Every decimal number from the sentence with "same seed" through the one with
"over seeds" must be one of that task's values in the file (a mean or the showcase seed's value, of any of
its policies, at the printed digits).
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
RESULTS = json.loads((ROOT / "benchmarks" / "results" / "showcase_seeds.json").read_text())
DECIMAL = re.compile(r"(?<![\w.])\d+\.\d+(?![\w.])")


def quoted_span(text: str) -> str:
    """The caption's sentences from the one that says "same seed" through the one that says "over seeds"."""
    sentences = re.split(r"(?<=[.)])\s+(?=[A-Z])", " ".join(text.split()))
    first = next(i for i, s in enumerate(sentences) if "same seed" in s)
    last = next(i for i, s in enumerate(sentences) if "over seeds" in s.lower())
    return " ".join(sentences[first : last + 1])


def task_values(task: str) -> list[float]:
    values = []
    for policy in RESULTS["tasks"][task]["policies"].values():
        values += list(policy["mean"].values()) + list((policy["showcase_seed"] or {}).values())
    return values


@pytest.mark.parametrize("task", sorted(RESULTS["tasks"]))
def test_the_environment_page_quotes_the_showcase_file(task):
    page = (ROOT / "docs" / "environments" / f"{task}.md").read_text()
    span = quoted_span(page)
    assert f"over seeds 0-{RESULTS['seeds'] - 1}" in span.lower(), span
    values = task_values(task)
    quoted = DECIMAL.findall(span)
    assert quoted, span
    wrong = [q for q in quoted if not any(abs(round(v, len(q.split(".")[1])) - float(q)) < 1e-9 for v in values)]
    assert not wrong, f"{task}: {wrong} not in showcase_seeds.json; span: {span}"
