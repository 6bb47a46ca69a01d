"""Every fenced code block of README.md and docs/**/*.md runs in a test, as written.

A block's fence language says what it is: ``python`` blocks run in a fresh interpreter, ``bash``/``sh``/``console``
blocks run command by command (in order, in one scratch folder, so a command may use what an earlier one wrote),
``yaml`` blocks are parsed (and validated as a training config when they are one), and ``text`` (output samples,
usage synopses with placeholders) is not run. Budgets are trimmed only by appending documented options to a
command (``TRIM``); a command that cannot run in CI is listed once, with its reason, in ``NOT_RUN``.
"""

from __future__ import annotations

import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest
import yaml

ROOT = Path(__file__).resolve().parents[2]
PAGES = [ROOT / "README.md", *sorted((ROOT / "docs").rglob("*.md"))]
#: ``c``: firmware fragments that call the robot's own functions (tests/test_export*.py compile the exported C)
LANGUAGES = {"python", "bash", "sh", "console", "text", "yaml", "json", "toml", "mermaid", "c"}
SHELL = {"bash", "sh", "console"}

#: commands (their text as documented, without trailing comment) that no test runs, with the reason
NOT_RUN: dict[str, str] = {
    'python3 -m venv .venv && . .venv/bin/activate && pip install torch==2.13.0 && pip install -e ".[rl]" && python train.py --config configs/aggregation.yaml':
        "creates a venv and installs; its training command runs trimmed from docs/installation.md and docs/training.md",
    'python3 -m venv .venv && . .venv/bin/activate && pip install torch==2.13.0 && pip install -e ".[dev]" && python -m pytest -q':
        ".ci/run runs it verbatim (tests/project/test_readme.py checks that)",
    "python -m pytest -q": "the CI's own test command (.ci/run)",
    "mkdocs build --strict": "the CI's documentation step runs it (.ci/run)",
    "python benchmarks/run_all.py --markdown": "rewrites docs/performance.md from a measurement run of many minutes",
    "python benchmarks/run_all.py": "every component benchmark at its measurement budget (many minutes)",
    "python benchmarks/bench_first_run.py": "compiles every numba kernel from an empty cache three times (minutes); "
                                            "tests/compile/test_first_run.py covers the cold start",
}
#: lines of shell blocks that are package installs (.ci/run performs them) are not run either
INSTALL = re.compile(r"^(python3 -m venv|pip install)")

#: (command regex, options appended to trim its budget); the first match applies
TINY_TRAIN = ["--set", "train.total_timesteps=320", "--set", "train.n_envs=2", "--set", "eval.n_seeds=1",
              "--set", "env.max_cycles=10", "--set", "agent.n_steps=16", "--set", "agent.batch_size=64",
              "--set", "train.progress_bar=false"]
SUITE_TRIM = ["--jobs", "1", "--seeds", "0", "--set", "train.total_timesteps=320",
              "--set", "eval.n_seeds=1", "--set", "env.max_cycles=10"]
TRIM: list[tuple[str, list[str]]] = [
    (r"^(python train\.py|swarm-train) --config", TINY_TRAIN),
    # the whole suite is every task's long config x variants x seeds: one task of it, one seed
    (r"^python -m swarm_envs\.agents\.suite(?!.*--report-only)(?!.*--tasks)", ["--tasks", "aggregation", *SUITE_TRIM]),
    (r"^python -m swarm_envs\.agents\.suite(?!.*--report-only)", SUITE_TRIM),
    (r"^(swarm-benchmark|python -m swarm_envs\.agents\.benchmark)", ["--episodes", "1", "--max-cycles", "10"]),
    (r"^swarm-demo", ["--steps", "5"]),
    (r"^python benchmarks/bench_vec\.py.*--interleave", ["--interleave", "1", "--vmas-steps", "1"]),
    (r"^python benchmarks/bench_vec\.py$", ["--quick", "--min-steps", "1", "--min-seconds", "0", "--vmas-steps", "1"]),
    (r"^python benchmarks/bench_vec\.py", ["--min-steps", "1", "--min-seconds", "0", "--vmas-steps", "1"]),
    (r"^python benchmarks/bench_stages\.py", ["--copies", "4", "--steps", "2"]),
    (r"^python benchmarks/bench_views\.py", ["--n", "20", "--steps", "2", "--rounds", "1"]),
    (r"^python benchmarks/bench_torchrl\.py", ["--copies", "4", "--steps", "2", "--rounds", "1"]),
    (r"^python examples/benchmarl_mappo\.py", ["--frames", "200", "--frames-per-batch", "100", "--num-envs", "2", "--max-steps", "10",
                                                "--algorithms", "mappo"]),
    (r"^python -m swarm_envs\.validate range-bearing", ["--repeats", "1", "--env-steps", "1", "--no-plots"]),
    (r"^python -m swarm_envs\.validate swarmcom", ["--quick", "--experiment", "a", "--no-plots"]),
    (r"^python -m swarm_envs\.validate scale-free", ["--trials", "1", "--populations", "20", "--ks", "1", "--env-steps", "1", "--no-plots"]),
    (r"^python -m swarm_envs\.validate centroid", ["--polygons", "1", "--starts", "1", "--rounds", "2", "--no-env", "--no-plots"]),
    (r"^python -m swarm_envs\.validate behaviours", ["--seeds", "1", "--max-cycles", "10", "--only", "flocking"]),
]
#: optional packages (extras) a block needs: the test skips when they are not installed
EXTRAS = {"torchrl": "torchrl", "make_torchrl": "torchrl", "benchmarl": "benchmarl", "ray": "ray", "supersuit": "supersuit", "bench_torchrl": "torchrl",
          "benchmarl_mappo": "benchmarl", "vmas": "vmas"}


def _blocks() -> list[tuple[str, int, str, str]]:
    """(page relative to the root, line of the opening fence, language, body) of every fenced block."""
    found = []
    for page in PAGES:
        text = page.read_text(encoding="utf-8")
        for match in re.finditer(r"^```([^\n`]*)\n(.*?)^```[ \t]*$", text, flags=re.S | re.M):
            line = text.count("\n", 0, match.start()) + 1
            found.append((str(page.relative_to(ROOT)), line, match.group(1).strip(), match.group(2)))
    return found


BLOCKS = _blocks()


def _commands() -> list[tuple[str, int, str]]:
    """(page, line, command) of every command line of the shell blocks, comments stripped."""
    found = []
    for page, line, lang, body in BLOCKS:
        if lang in SHELL:
            for offset, raw in enumerate(body.splitlines(), start=1):
                command = re.sub(r"\s+#.*$", "", raw).strip()
                if command and not command.startswith("#"):
                    found.append((page, line + offset, command.removeprefix("$ ")))
    return found


COMMANDS = _commands()


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env.update(PYTHONPATH=os.pathsep.join(filter(None, [str(ROOT), env.get("PYTHONPATH")])), OMP_NUM_THREADS="1",
               NUMBA_NUM_THREADS="1", MKL_NUM_THREADS="1", SDL_VIDEODRIVER="dummy", MPLBACKEND="Agg",
               PATH=os.pathsep.join([str(Path(sys.executable).parent), env.get("PATH", "")]))
    return env


def _skip_without_extras(text: str) -> None:
    for word, module in EXTRAS.items():
        if re.search(rf"\b{word}\b", text) and importlib.util.find_spec(module) is None:
            pytest.skip(f"needs {module} (an optional extra), not installed")


def _scratch(tmp_path: Path) -> Path:
    """A folder that looks like the repository root to documented commands but keeps their outputs."""
    for name in ("configs", "examples", "benchmarks", "train.py"):
        (tmp_path / name).symlink_to(ROOT / name)
    (tmp_path / "docs" / "img" / "validation").mkdir(parents=True)
    return tmp_path


def test_every_block_declares_its_language():
    unknown = [f"{page}:{line} ```{lang}" for page, line, lang, _ in BLOCKS if lang not in LANGUAGES]
    assert not unknown, f"fence languages must be one of {sorted(LANGUAGES)}: {unknown}"
    assert sum(lang == "python" for *_, lang, _ in BLOCKS) >= 10 and len(COMMANDS) >= 30


def test_not_run_lists_only_documented_commands():
    documented = {command for *_, command in COMMANDS}
    assert not set(NOT_RUN) - documented, "NOT_RUN names a command no page documents any more"


#: pages whose shell commands together take more than ~10 s even trimmed (trainings, validations, benchmarks), and
#: python blocks that train: marked slow, so the default test run stays short; .ci/run runs them with `-m slow`
SLOW_PAGES = {"README.md", "docs/training.md", "docs/performance.md", "docs/custom_tasks.md", "docs/validation.md", "docs/export.md"}


def _slow_if(condition: bool, *values):
    return pytest.param(*values, marks=pytest.mark.slow) if condition else pytest.param(*values)


@pytest.mark.parametrize("page, line, code", [_slow_if(".learn(" in b, p, n, b) for p, n, lang, b in BLOCKS if lang == "python"],
                         ids=lambda v: v if isinstance(v, (str, int)) and "\n" not in str(v) else "")
def test_python_block_runs(page, line, code, tmp_path):
    _skip_without_extras(code)
    result = subprocess.run([sys.executable, "-c", code], cwd=_scratch(tmp_path), env=_env(), capture_output=True,
                            text=True, timeout=900)
    assert result.returncode == 0, f"{page}:{line}\n{result.stderr[-3000:]}"


def _pages_with_shell() -> list[str]:
    return sorted({page for page, *_ in COMMANDS})


@pytest.mark.parametrize("page", [_slow_if(p in SLOW_PAGES, p) for p in _pages_with_shell()])
def test_shell_commands_run(page, tmp_path):
    """Every command of the page's shell blocks, in order, in one scratch folder, budgets trimmed by ``TRIM``."""
    scratch = _scratch(tmp_path)
    ran, missing = 0, set()
    for _, line, command in [c for c in COMMANDS if c[0] == page]:
        if command in NOT_RUN or INSTALL.match(command):
            continue
        if any(word in command for word in ("bench_torchrl", "benchmarl_mappo")):
            needed = ("torchrl", "benchmarl") if "benchmarl" in command else ("torchrl",)
            absent = {m for m in needed if importlib.util.find_spec(m) is None}
            if absent:
                missing |= absent  # the extras' CI steps run them
                continue
        extra = next((args for pattern, args in TRIM if re.search(pattern, command)), [])
        full = " ".join([command, *extra])
        result = subprocess.run(["bash", "-c", full], cwd=scratch, env=_env(), capture_output=True, text=True, timeout=900)
        assert result.returncode == 0, f"{page}:{line}: {full}\n{result.stdout[-1500:]}\n{result.stderr[-3000:]}"
        ran += 1
    if not ran:
        pytest.skip(f"every command needs {sorted(missing)} (optional extras), not installed" if missing else "nothing to run")


@pytest.mark.parametrize("page, line, body", [(p, n, b) for p, n, lang, b in BLOCKS if lang == "yaml"])
def test_yaml_block_parses(page, line, body, tmp_path, monkeypatch, forget_registered_ids):
    """Parsed by PyYAML; a training config (it names a ``task``) also passes train.py's loader, from the root."""
    data = yaml.safe_load(body)
    assert data is not None, f"{page}:{line}: an empty yaml block"
    if isinstance(data, dict) and "task" in data:
        from swarm_envs.agents.config import load_config

        path = tmp_path / "block.yaml"
        path.write_text(body, encoding="utf-8")
        (tmp_path / "root").mkdir()
        monkeypatch.chdir(_scratch(tmp_path / "root"))
        monkeypatch.syspath_prepend(str(ROOT))
        assert load_config(path)["task"] == data["task"]
