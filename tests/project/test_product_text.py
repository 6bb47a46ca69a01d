"""The product describes itself as it is: no citations of documents outside the repository, no development
history in docs, code, comments or configs, and the version in one place (pyproject.toml).

CHANGELOG.md is the one file whose job is history; it is not scanned. This file holds the pattern list and
is not scanned either.
"""

from __future__ import annotations

import re
from pathlib import Path

import pytest

import swarm_envs

ROOT = Path(__file__).resolve().parents[2]
THIS = Path(__file__).resolve()

#: the product's text: (folder, glob) pairs scanned for the patterns below
SCANNED = [
    (".", "README.md"),
    (".", "train.py"),
    ("docs", "**/*.md"),
    ("swarm_envs", "**/*.py"),
    ("agents", "**/*.py"),
    ("benchmarks", "**/*.py"),
    ("examples", "**/*.py"),
    ("tests", "**/*.py"),
    ("configs", "**/*.yaml"),
]

#: citations of a specification that is not part of the repository (cite the papers or docs/design.md)
CITATION_PATTERNS = [r"\bSPEC\b"]

#: sentences that tell how or when the project was built rather than what it does (case-insensitive)
HISTORY_PATTERNS = [
    r"\b(this|previous|earlier|last|next) round\b",
    r"\bround before\b",
    r"\brounds? (ago|earlier)\b",
    r"\ba round earlier\b",
    r"\b(this|previous|earlier|last) session\b",
    r"\bthis session's\b",
    r"\bfirst version\b",
    r"\bcommit [0-9a-f]{7,40}\b",
    r"\b[0-9a-f]{7,40} commit\b",
    # a bare git hash: 7-40 hex digits with at least one digit and one letter, not part of a number or
    # of a 0b/0x literal
    r"(?<![\w.])(?!0[bx])(?=[0-9a-f]*[0-9])(?=[0-9a-f]*[a-f])[0-9a-f]{7,40}(?![\w.+-])",
    r"\bused to (be|give|take|run|use)\b",
    r"\bthe (old|previous|new) (code|model|implementation|spawner)s?\b",
    r"\bprevious implementations?\b",
    r"\bkept verbatim\b",
    r"\b(than|as) before\b",
    r"\bbefore this (round|change|commit)\b",
    r"\bfollow-up\b",
    r"\bno longer swapped\b",
    r"\bspeed work\b",
]


def _files() -> list[Path]:
    files: set[Path] = set()
    for folder, pattern in SCANNED:
        files.update(p for p in (ROOT / folder).glob(pattern) if p.is_file())
    return sorted(p for p in files if p.resolve() != THIS and ".venv" not in p.parts and "site" not in p.parts[:1])


def _hits(patterns: list[str], flags: int = 0) -> list[str]:
    compiled = [re.compile(p, flags) for p in patterns]
    hits = []
    for path in _files():
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            for rx in compiled:
                found = rx.search(line)
                if found:
                    hits.append(f"{path.relative_to(ROOT)}:{number}: {found.group(0)!r} in {line.strip()[:100]!r}")
                    break
    return hits


def test_the_scan_covers_the_product():
    names = {p.relative_to(ROOT).as_posix() for p in _files()}
    for expected in ("README.md", "docs/design.md", "swarm_envs/core.py", "agents/train.py", "configs/aggregation.yaml"):
        assert expected in names
    assert "tests/project/test_product_text.py" not in names and "CHANGELOG.md" not in names


def test_no_citation_of_documents_outside_the_repository():
    hits = _hits(CITATION_PATTERNS)
    assert not hits, "cite the papers ([F14 Eq. (4)]) or docs/design.md#<section> instead:\n" + "\n".join(hits)


def test_no_development_history_in_the_product():
    hits = _hits(HISTORY_PATTERNS, re.IGNORECASE)
    assert not hits, "say what the code does and why, not how it was built:\n" + "\n".join(hits)


@pytest.mark.parametrize(
    "line, flagged",
    [
        ("the previous round's table ran at 53.7 ms", True),
        ("measured at commit 6a93479 on a quiet host", True),
        ("(57fd540, VMAS 57.5k)", True),
        ("keeps the first version's centre-line rule", True),
        ("polynomial 0xA001 over the id bytes, masks like 0b10110011", False),
        ("_LN2_LO = 1.90821492927058770002e-10", False),
        ("total_timesteps: 3000000", False),
        ("every robot broadcasts once per round of 24 steps", False),
    ],
)
def test_the_history_patterns_flag_history_and_nothing_else(line, flagged):
    assert any(re.search(p, line, re.IGNORECASE) for p in HISTORY_PATTERNS) == flagged


# -- the version lives in pyproject.toml ------------------------------------------------------------------
def _pyproject_version() -> str:
    text = (ROOT / "pyproject.toml").read_text(encoding="utf-8")
    project = text.split("[project]", 1)[1].split("\n[", 1)[0]
    return re.search(r'^version\s*=\s*"([^"]+)"', project, re.M).group(1)


def test_version_is_read_from_pyproject():
    assert swarm_envs.__version__ == _pyproject_version()


def test_version_falls_back_to_the_source_tree(monkeypatch):
    from importlib import metadata

    def not_installed(name):
        raise metadata.PackageNotFoundError(name)

    monkeypatch.setattr(metadata, "version", not_installed)
    assert swarm_envs._read_version() == _pyproject_version()


def test_no_hard_coded_package_version():
    version = re.escape(_pyproject_version())
    for path in sorted((ROOT / "swarm_envs").rglob("*.py")) + sorted((ROOT / "agents").rglob("*.py")):
        text = path.read_text(encoding="utf-8")
        assert not re.search(r"__version__\s*=\s*['\"]", text), f"{path.relative_to(ROOT)} assigns a literal __version__"
        # the one allowed mention: a task's "Version History" entry naming the release that introduced it
        for line in text.splitlines():
            if re.search(rf"(?<![\d.]){version}(?![\d.])", line):
                assert re.search(rf"swarm_envs {version}\)", line), f"{path.relative_to(ROOT)}: {line.strip()}"


def test_version_history_entries_name_changelog_releases():
    changelog = (ROOT / "CHANGELOG.md").read_text(encoding="utf-8")
    released = set(re.findall(r"^## \[(\d+\.\d+\.\d+)\]", changelog, re.M))
    assert _pyproject_version() in released, "CHANGELOG.md has no section for the version in pyproject.toml"
    for env_id, env_spec in swarm_envs.registry.ENV_IDS.items():
        if not env_id.startswith("swarm_envs/"):  # the suite's own ids (tests register others)
            continue
        module = __import__(env_spec.entry_point.partition(":")[0], fromlist=["parallel_env"])
        doc = module.parallel_env.__doc__ or ""
        history = doc.split("## Version History", 1)[1]
        current = env_id.rsplit("-", 1)[1]  # "v0"
        assert re.search(rf"^\s*- {current}:", history, re.M), f"{env_id}: no Version History entry for {current}"
        for release in re.findall(r"swarm_envs (\d+\.\d+\.\d+)", history):
            assert release in released, f"{env_id}: Version History names {release}, which CHANGELOG.md lacks"
        assert env_id in changelog, f"CHANGELOG.md does not mention {env_id}"


# -- links into docs/design.md and the generated performance page ------------------------------------------
def _slug(heading: str) -> str:
    """Python-Markdown's toc slug (the anchors MkDocs gives headings)."""
    return re.sub(r"[\s-]+", "-", re.sub(r"[^\w\s-]", "", heading).strip().lower())


def test_design_anchors_cited_in_the_product_exist():
    design = (ROOT / "docs" / "design.md").read_text(encoding="utf-8")
    anchors = {_slug(h) for h in re.findall(r"^#{2,4} (.+?)\s*$", design, re.M)}
    assert {"physics", "infrared-physical-layer", "range-and-bearing", "deviations-and-assumptions"} <= anchors
    cited = []
    for path in _files():
        for number, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            cited += [(path, number, a) for a in re.findall(r"design\.md#([\w-]+)", line)]
    assert cited, "code and docs cite docs/design.md sections"
    missing = [f"{p.relative_to(ROOT)}:{n}: #{a}" for p, n, a in cited if a not in anchors]
    assert not missing, "no such section in docs/design.md:\n" + "\n".join(missing)


def _run_all():
    import importlib.util

    spec = importlib.util.spec_from_file_location("run_all", ROOT / "benchmarks" / "run_all.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_performance_page_is_rendered_from_the_measurements():
    import datetime

    run_all = _run_all()
    rows = [{"n": 10, "copies": 256, "sensing": s, "s_per_step": t, "cpu_s_per_step": t, "agent_steps_per_s": 2560 / t,
             "env_steps_per_s": 1 / t, "neighbours_in_range": 9.0} for s, t in (("full", 0.08), ("ideal", 0.04))]
    rows2 = [dict(row, s_per_step=0.05, cpu_s_per_step=0.09, agent_steps_per_s=51200.0, env_steps_per_s=20.0) for row in rows[:1]]
    runs = [{"numba_threads": 1, "vmas": {"version": "1.5.2", "n_agents": 10, "num_envs": 1024, "s_per_step": 0.2,
                                          "agent_steps_per_s": 51200.0}, "rows": rows},
            {"numba_threads": 2, "vmas": {"version": "1.5.2", "n_agents": 10, "num_envs": 1024, "s_per_step": 0.1,
                                          "agent_steps_per_s": 102400.0}, "rows": rows2}]
    info = {"cpu": "Test CPU", "cores": "2", "os": "Linux", "Python": "3.11", "numpy": "2"}
    train = {"robot_steps": 202240, "train_s": 30.0, "total_s": 40.0, "robot_steps_per_s": 6741.3,
             "stages": [("env step", 2.5, 45.1), ("PPO update", 2.4, 43.2)]}
    when = datetime.datetime(2030, 1, 2, 3, 4, tzinfo=datetime.timezone.utc)
    first = {"runs": 3, "background_started": [True, True, False], "cold_s": [11.2, 12.4, 11.9], "warm_s": [2.0, 2.2, 2.1], "cold_median_s": 11.9,
             "warm_median_s": 2.1, "load_before": [0.5, 0.4, 0.3], "load_after": [0.7, 0.5, 0.4]}
    views = {"env": "swarm_envs/Aggregation-v0", "n": 1000, "sensing": "full", "rounds": 5, "parallel_env_steps_per_s": 21.0,
             "make_vec_steps_per_s": 23.5, "ratio": 0.894}
    torchrl = {"n": 10, "copies": 64, "sensing": "full", "rounds": 5, "make_vec": 25686.0, "make_vec ratio": 1.0,
               "make_torchrl rollout": 20711.0, "make_torchrl rollout ratio": 0.78, "PettingZooWrapper rollout (B = 1)": 720.0,
               "PettingZooWrapper rollout (B = 1) ratio": 0.028}
    page = run_all.render(info, runs, train, [10], when, 5.0, (0.5, 0.4, 0.3), (0.6, 0.5, 0.4), first, views, torchrl)
    assert "21.0 against 23.5 env steps/s" in page and "**ratio 0.89**" in page
    assert "20,711 against 25,686 agent-steps/s, **ratio 0.78**" in page and "(ratio 0.028)" in page
    assert "**11.9 s** (median of 3 runs: 11.2, 12.4, 11.9 s)" in page and "filled cache: 2.1 s" in page
    assert "it ran in\n2 of these 3 runs" in page
    assert "| 10 | 256 | full | 1 | 80.0 | 80.0 | 12.5 | 32,000 | 0.62x | 9.0 | 3.47 |" in page  # 80 ms / 2560 robots / 9
    assert "| 10 | 256 | full | 2 | 50.0 | 90.0 | 20.0 | 51,200 | 0.50x | 9.0 | 2.17 |" in page  # to VMAS on 2 threads
    assert "| 10 | 256 | ideal | 1 | 40.0 | 40.0 | 25.0 | 64,000 | 1.25x | 9.0 | 1.74 |" in page
    assert "51,200 agent-steps/s (200.0 ms per step) on 1 torch thread; 102,400" in page and "6,741 robot-steps/s" in page and "Test CPU, 2 cores" in page
    assert "Reduced run: only N = 10" in page
    assert "| env step | 2.50 | 45.1 % |\n| PPO update | 2.40 | 43.2 % |" in page
    alternated = [{"sensing": "full", "numba_threads": 1, "rounds": 5, "vmas_median_agent_steps_per_s": 120000.0,
                   "ratios": {"64": {"median": 0.43, "min": 0.41, "max": 0.45}, "256": {"median": 0.51, "min": 0.5, "max": 0.54}}}]
    same_load = run_all.render(info, runs, train, [10], when, 5.0, (0.5, 0.4, 0.3), (0.6, 0.5, 0.4), first, views, torchrl, alternated)
    assert "| full | 1 | 120,000 | 0.43x [0.41, 0.45] | 0.51x [0.50, 0.54] |" in same_load and "### Ratios under the same load" not in page
    failed = run_all.render(info, runs, dict(train, stages="not measured: bench_train_stages.py exited with code 1"), [10], when, 5.0,
                            (0.5, 0.4, 0.3), (0.6, 0.5, 0.4), first, views, torchrl)
    assert "The split of the training time was not measured: bench_train_stages.py exited with code 1." in failed
    without = run_all.render(info, [dict(runs[0], vmas=None), dict(runs[1], vmas=None)], "not measured (`--no-training`)", list(run_all.SIZES),
                             when, 5.0, (0.5, 0.4, 0.3), (0.6, 0.5, 0.4))
    assert "VMAS was not installed" in without and "| - |" in without and "Reduced run" not in without
    assert "was not measured (`--no-first-run`)" in without and "Not measured (`--no-adapters`)" in without
    assert not any(re.search(p, without, re.IGNORECASE) for p in HISTORY_PATTERNS)
