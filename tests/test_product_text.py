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

ROOT = Path(__file__).resolve().parent.parent
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
    assert "tests/test_product_text.py" not in names and "CHANGELOG.md" not in names


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
    for env_id, module_name in swarm_envs.registry.ENV_IDS.items():
        module = __import__(module_name, fromlist=["parallel_env"])
        doc = module.parallel_env.__doc__ or ""
        history = doc.split("## Version History", 1)[1]
        current = env_id.rsplit("-", 1)[1]  # "v0"
        assert re.search(rf"^\s*- {current}:", history, re.M), f"{env_id}: no Version History entry for {current}"
        for release in re.findall(r"swarm_envs (\d+\.\d+\.\d+)", history):
            assert release in released, f"{env_id}: Version History names {release}, which CHANGELOG.md lacks"
        assert env_id in changelog, f"CHANGELOG.md does not mention {env_id}"
