"""Property tests of the console commands' argument handling: ``train.py``, ``swarm-demo``, ``swarm-benchmark``
and ``swarm-validate``, run in-process through their ``main(argv)`` with random argument lists (random
options in random order, random ``--set key=value``, paths that are missing, files, directories, not
writable, not models). Every run either passes the command's checks (the work itself is stubbed: no
training, episode or experiment runs), prints its help or listing (exit code 0), or ends with exit code 2
and one ``error:`` line, never a traceback or another exception. ``pytest -m slow`` runs more examples.

The commands run inside a scratch folder (the current directory while they run), and every path they are
given lies inside it."""

from __future__ import annotations

import contextlib
import io
import os
import signal
import zipfile
from pathlib import Path

import pytest

pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, event, example, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from swarm_envs.agents import benchmark, train  # noqa: E402
from swarm_envs.agents.config import DEFAULTS  # noqa: E402
from swarm_envs.agents.tasks import SHORT_NAMES  # noqa: E402
from swarm_envs.tasks.settings import COMMON_SETTINGS  # noqa: E402
from tests.conftest import dotted_keys  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
#: examples per command in the default run, and with ``pytest -m slow`` (SWARM_ENVS_CLI_EXAMPLES sets it)
FAST, SLOW = 15, int(os.environ.get('SWARM_ENVS_CLI_EXAMPLES', 300))
#: seconds one example may take (its checks build an env or load a file, nothing more)
TIME_LIMIT = 60


def _settings(examples: int) -> settings:
    """Few examples, the same on every run, by default; many random ones with ``pytest -m slow``."""
    return settings(max_examples=examples, deadline=None, database=None, derandomize=examples <= FAST,
                    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])


class _Accepted(BaseException):
    """Raised by a stub in place of the command's work: the arguments passed every check."""


def _accepted(*args, **kwargs):
    raise _Accepted


# -- the scratch folder the commands run in ---------------------------------------------------------------
@pytest.fixture(scope="module")
def untrained_run(tmp_path_factory) -> Path:
    """A run folder with an untrained PPO model (built and saved, never trained) of configs/aggregation.yaml
    with ideal sensing, and its config.yaml, as train.py writes them."""
    import yaml

    from swarm_envs.agents.config import load_config, resolve
    from swarm_envs.agents.sb3_vec_env import SwarmVecEnv
    from swarm_envs.agents.tasks import env_id

    cfg = resolve(load_config(ROOT / "configs" / "aggregation.yaml", ["env.sensing=ideal", "agent.batch_size=160"]))  # one copy: 160-step rollouts
    venv = SwarmVecEnv(env_id(cfg["task"]), 1, train.env_kwargs_of(cfg))
    try:
        model = train.build_model(cfg, venv, venv.layout)
    finally:
        venv.close()
    folder = tmp_path_factory.mktemp("untrained")
    model.save(folder / "model.zip")
    (folder / "config.yaml").write_text(yaml.safe_dump(cfg, sort_keys=False))
    return folder


@pytest.fixture
def scratch(tmp_path, monkeypatch, untrained_run) -> Path:
    """A folder with configs, models, files and a run that the arguments name; the current directory.
    ``trained/`` holds a model with its run config, ``bare/`` the model alone, ``fuzzed/`` the model with a
    config.yaml a test writes."""
    for name, files in (("trained", ("model.zip", "config.yaml")), ("bare", ("model.zip",)), ("fuzzed", ("model.zip",))):
        (tmp_path / name).mkdir()
        for file in files:
            (tmp_path / name / file).write_bytes((untrained_run / file).read_bytes())
    (tmp_path / "empty.yaml").write_text("")
    (tmp_path / "list.yaml").write_text("- a\n- b\n")
    (tmp_path / "broken.yaml").write_text("task: [\n")
    (tmp_path / "binary.yaml").write_bytes(b"\x89PNG\r\n\x1a\n\x00\xff")
    (tmp_path / "seed_only.yaml").write_text("seed: 1\n")
    (tmp_path / "folder").mkdir()
    (tmp_path / "afile").write_text("a file\n")
    (tmp_path / "run").mkdir()
    (tmp_path / "run" / "config.yaml").write_text("seed: 0\n")
    (tmp_path / "run" / "model.zip").write_text("not a model")
    (tmp_path / "text.zip").write_text("not a zip\n")
    (tmp_path / "empty.zip").write_bytes(b"PK\x05\x06" + bytes(18))
    with zipfile.ZipFile(tmp_path / "other.zip", "w") as zf:
        zf.writestr("hello.txt", "a zip, not a model")
    (tmp_path / "raises.py").write_text("raise RuntimeError('a broken tasks module')\n")
    (tmp_path / "registers_nothing.py").write_text("X = 1\n")
    (tmp_path / ".run.1-abcdefgh.partial").mkdir()  # a staging directory whose process (pid 1) runs
    monkeypatch.chdir(tmp_path)
    return tmp_path


#: names of files and folders inside the scratch folder (no path separator, never '.' or '..')
NAME = st.text(st.characters(blacklist_characters="/\x00", blacklist_categories=("Cs",)), min_size=1, max_size=12).filter(
    lambda s: s not in (".", ".."))
PATH = st.one_of(
    st.sampled_from(["empty.yaml", "list.yaml", "broken.yaml", "binary.yaml", "seed_only.yaml", "folder", "afile", "afile/sub",
                     "run", "run/model.zip", "text.zip", "empty.zip", "other.zip", "missing", "missing/deeper", "", " ",
                     "folder/new", "new-run", "trained/model.zip", "trained/model", "bare/model.zip", "trained", "/dev/null",
                     "x" * 300, "x" * 300 + ".py", "x" * 300 + ".gif", "x" * 300 + "/model.zip"]),
    NAME,
)
YAML_VALUE = st.one_of(
    st.sampled_from(["null", "true", "false", "[]", "{}", "[1, 2]", "{a: 1}", "''", "0", "-1", "1", "3", "0.5", "1e9", "1e400",
                     ".nan", ".inf", "-.inf", "[", ":", "!!binary aGVsbG8=", "ideal", "full", "rone", "epuck", "droplet",
                     "4294967296", "9" * 400, "2020-01-01", "[64, 64]", *SHORT_NAMES]),
    st.integers(-(2**70), 2**70).map(str),
    st.text(max_size=8),
)


CONFIG_KEY = st.one_of(
    st.sampled_from(sorted(set(dotted_keys(DEFAULTS)) | {f"env.{k}" for k in COMMON_SETTINGS}
                           | {"", ".", "train.", ".seed", "a..b", "bogus", "train.bogus", "env.bogus", "task.x", "seed.x"})),
    st.text(max_size=10),
)
SET_VALUE = st.one_of(st.tuples(CONFIG_KEY, YAML_VALUE).map(lambda kv: f"{kv[0]}={kv[1]}"), st.text(max_size=10))
JUNK = st.sampled_from([["--bogus"], ["positional"], ["-x"], ["--"], ["-"], ["--set"], ["--output"], ["--config"], ["=1"]])


def _argv(groups: st.SearchStrategy) -> st.SearchStrategy:
    """Argument lists made of 0-6 option groups in random order."""
    return st.lists(groups, max_size=6).map(lambda gs: [arg for g in gs for arg in g])


def _run(main, argv: list[str]) -> tuple[str, int | None, str, str]:
    """Run ``main(argv)`` capturing stdout and stderr: ("accepted", None, ...) if it got past its checks,
    else ("exit", code, ...). An example running longer than :data:`TIME_LIMIT` fails."""
    def hang(*args):
        raise AssertionError(f"took more than {TIME_LIMIT} s: {argv}")

    out, err = io.StringIO(), io.StringIO()
    previous = signal.signal(signal.SIGALRM, hang)
    signal.alarm(TIME_LIMIT)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            try:
                code = main(argv)
            except SystemExit as exit_:
                code = exit_.code if isinstance(exit_.code, int) else (0 if exit_.code is None else 1)
            except _Accepted:
                return "accepted", None, out.getvalue(), err.getvalue()
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)
    return "exit", code, out.getvalue(), err.getvalue()


def _check(main, argv: list[str], listing_ok: bool = True) -> None:
    """The outcome rule of the module docstring (notes, ``note: ...`` lines, may precede an error line)."""
    kind, code, out, err = _run(main, argv)
    assert "Traceback" not in out + err, (argv, out, err)
    if kind == "accepted":
        event("accepted")
        return
    event(f"exit {code}")
    if code == 0:
        assert listing_ok and not [line for line in err.splitlines() if "error" in line], (argv, err)
        return
    assert code == 2, (argv, code, out, err)
    lines = [line for line in err.splitlines() if not line.startswith("note: ")]
    assert len(lines) == 1 and "error: " in lines[0], (argv, err)


# -- train.py ---------------------------------------------------------------------------------------------
TRAIN_GROUPS = st.one_of(
    st.one_of(st.sampled_from([str(ROOT / "configs" / "aggregation.yaml"), str(ROOT / "configs" / "flocking.yaml")]), PATH).map(
        lambda c: ["--config", c]),
    SET_VALUE.map(lambda s: ["--set", s]),
    PATH.map(lambda o: ["--output", o]),
    PATH.map(lambda m: ["--eval-only", m]),
    PATH.map(lambda d: ["--list-partial", d]),
    PATH.map(lambda d: ["--clean-partial", d]),
    st.sampled_from([["--render"], ["--force"], ["--baselines-only"]]),
    JUNK,
)


def _train_stubs(monkeypatch) -> None:
    monkeypatch.setattr(train, "Staging", _accepted)  # all checks passed: the run would start writing


def _check_train(argv: list[str]) -> None:
    _check(train.main, argv)


AGG = str(ROOT / "configs" / "aggregation.yaml")


@_settings(FAST)
@given(argv=_argv(TRAIN_GROUPS))
@example(argv=["--list-partial", "x" * 300])  # names too long for the file system
@example(argv=["--config", AGG, "--output", "x" * 300])
@example(argv=["--config", AGG, "--eval-only", "x" * 300])
@example(argv=["--config", AGG, "--eval-only", "/dev/null"])  # a device, not a directory
@example(argv=["--config", AGG, "--eval-only", "trained/model"])  # the model without .zip: accepted
def test_train_arguments(scratch, monkeypatch, argv):
    _train_stubs(monkeypatch)
    _check_train(argv)


@_settings(FAST)
@given(sets=st.lists(SET_VALUE, min_size=1, max_size=3), output=PATH)
def test_train_sets_with_a_shipped_config(scratch, monkeypatch, sets, output):
    """The common case: a shipped config, an --output and a few --set of random keys and values."""
    _train_stubs(monkeypatch)
    _check_train(["--config", str(ROOT / "configs" / "aggregation.yaml"), "--output", output] + [x for s in sets for x in ("--set", s)])


@pytest.mark.slow
@_settings(SLOW)
@given(argv=_argv(TRAIN_GROUPS))
def test_train_arguments_many(scratch, monkeypatch, argv):
    _train_stubs(monkeypatch)
    _check_train(argv)


@pytest.mark.slow
@_settings(SLOW)
@given(sets=st.lists(SET_VALUE, min_size=1, max_size=3), output=PATH, extra=st.lists(TRAIN_GROUPS, max_size=2))
def test_train_sets_with_a_shipped_config_many(scratch, monkeypatch, sets, output, extra):
    _train_stubs(monkeypatch)
    _check_train(["--config", str(ROOT / "configs" / "aggregation.yaml"), "--output", output]
                 + [x for s in sets for x in ("--set", s)] + [x for g in extra for x in g])


RUN_CONFIG = st.fixed_dictionaries(
    {"task": st.one_of(st.sampled_from([*SHORT_NAMES, "swarm_envs/Aggregation-v0", "herding"]), st.integers(), st.none())},
    optional={
        "env": st.one_of(st.dictionaries(st.one_of(st.sampled_from(sorted(COMMON_SETTINGS)), st.text(max_size=5)),
                                         st.one_of(st.integers(-3, 40), st.floats(allow_nan=True), st.text(max_size=5), st.none(),
                                                   st.sampled_from(["ideal", "full", "droplet", "rone", "epuck"]),
                                                   st.lists(st.integers(0, 3), max_size=3)), max_size=3),
                          st.integers(), st.none()),
        "agent": st.one_of(st.dictionaries(st.sampled_from(["algorithm", "encoder", "odometry", "action_repeat", "frame_stack",
                                                            "set_embedding", "lstm_hidden", "bogus"]),
                                           st.one_of(st.integers(-2, 5), st.booleans(), st.text(max_size=5), st.none()), max_size=3),
                           st.text(max_size=3)),
    },
)


@_settings(FAST)
@given(run=st.one_of(RUN_CONFIG, st.text(max_size=20), st.lists(st.integers(), max_size=2)), sets=st.lists(SET_VALUE, max_size=2))
def test_eval_only_with_any_run_config(scratch, monkeypatch, run, sets):
    """--eval-only of a model whose run config (config.yaml beside it) holds anything: refused with one line,
    or evaluated."""
    import yaml

    (scratch / "fuzzed" / "config.yaml").write_text(run if isinstance(run, str) else yaml.safe_dump(run))
    _train_stubs(monkeypatch)
    _check_train(["--config", str(ROOT / "configs" / "aggregation.yaml"), "--eval-only", "fuzzed/model.zip",
                  "--set", "env.sensing=ideal"] + [x for s in sets for x in ("--set", s)])


@pytest.mark.slow
@_settings(SLOW)
@given(run=st.one_of(RUN_CONFIG, st.text(max_size=20), st.lists(st.integers(), max_size=2)), sets=st.lists(SET_VALUE, max_size=2))
def test_eval_only_with_any_run_config_many(scratch, monkeypatch, run, sets):
    import yaml

    (scratch / "fuzzed" / "config.yaml").write_text(run if isinstance(run, str) else yaml.safe_dump(run))
    _train_stubs(monkeypatch)
    _check_train(["--config", str(ROOT / "configs" / "aggregation.yaml"), "--eval-only", "fuzzed/model.zip",
                  "--set", "env.sensing=ideal"] + [x for s in sets for x in ("--set", s)])


def test_train_help_and_listing(scratch, capsys):
    with pytest.raises(SystemExit) as exit_:
        train.main(["--help"])
    assert exit_.value.code == 0 and "--clean-partial" in capsys.readouterr().out
    assert train.main(["--list-partial", "run"]) == 0
    assert "in use by process 1" in capsys.readouterr().out


# -- swarm-demo -------------------------------------------------------------------------------------------
INT_TEXT = st.one_of(st.sampled_from(["-1", "0", "1", "2", "3", "10", "1000000", "1" + "0" * 30, "x", "1.5", "", " 4", "0x10"]),
                     st.integers(-5, 40).map(str))
DEMO_GROUPS = st.one_of(
    st.one_of(st.sampled_from([*SHORT_NAMES, "swarm_envs/Flocking-v0", "herding", "", "swarm_envs/Flocking-v9"]), st.text(max_size=8)).map(
        lambda t: ["--task", t]),
    st.just(["--all"]),
    st.sampled_from(["scripted", "random", "ppo", ""]).map(lambda p: ["--policy", p]),
    PATH.map(lambda m: ["--model", m]),
    st.one_of(PATH, NAME.map(lambda n: n + ".gif"), st.sampled_from(["demo.gif", "folder/demo.gif", "afile/demo.gif"])).map(
        lambda o: ["--out", o]),
    PATH.map(lambda d: ["--out-dir", d]),
    st.sampled_from(["droplet", "epuck", "rone", "roomba", ""]).map(lambda p: ["--platform", p]),
    st.sampled_from(["full", "ideal", "perfect"]).map(lambda s: ["--sensing", s]),
    INT_TEXT.map(lambda n: ["--n-robots", n]),
    INT_TEXT.map(lambda n: ["--steps", n]),
    INT_TEXT.map(lambda n: ["--seed", n]),
    st.tuples(st.one_of(st.sampled_from(sorted(COMMON_SETTINGS)), st.text(max_size=6)), YAML_VALUE).map(
        lambda kv: ["--env", f"{kv[0]}={kv[1]}"]),
    st.one_of(st.just(["--overlay"]), INT_TEXT.map(lambda n: ["--overlay", n])),
    st.just(["--no-overlay"]),
    INT_TEXT.map(lambda n: ["--frame-skip", n]),
    INT_TEXT.map(lambda n: ["--pixels", n]),
    JUNK,
)


def _demo_stubs(monkeypatch) -> None:
    from swarm_envs import demo

    monkeypatch.setattr(demo, "run_demo", _accepted)


@_settings(FAST)
@given(argv=_argv(DEMO_GROUPS))
@example(argv=["--env", "message_bits=&\x00"])  # a value that is not YAML
@example(argv=["--model", "\r"])  # a line break in a path
@example(argv=["--model", "x" * 300])
@example(argv=["--model", "/dev/null"])
@example(argv=["--model", "trained/model.zip", "--task", "aggregation"])  # accepted
def test_demo_arguments(scratch, monkeypatch, argv):
    from swarm_envs import demo

    _demo_stubs(monkeypatch)
    _check(demo.main, argv)


@pytest.mark.slow
@_settings(SLOW)
@given(argv=_argv(DEMO_GROUPS))
def test_demo_arguments_many(scratch, monkeypatch, argv):
    from swarm_envs import demo

    _demo_stubs(monkeypatch)
    _check(demo.main, argv)


# -- swarm-benchmark --------------------------------------------------------------------------------------
BENCHMARK_GROUPS = st.one_of(
    st.one_of(st.sampled_from([*SHORT_NAMES, "flocking,aggregation", ",", "", "herding", "swarm_envs/Flocking-v0"]),
              st.text(max_size=8)).map(lambda t: ["--task", t]),
    # modules that do not exist, fail, or register nothing (never a real module picked at random)
    st.one_of(st.sampled_from(["raises.py", "registers_nothing.py", "missing.py", "", "raises", "registers_nothing", "afile",
                               "x" * 300 + ".py", "zz_" + "x" * 300, "/dev/null"]),
              NAME.map(lambda n: "zz_no_such_module_" + n)).map(lambda m: ["--import", m]),
    INT_TEXT.map(lambda n: ["--episodes", n]),
    st.sampled_from(["full", "ideal", "perfect"]).map(lambda s: ["--sensing", s]),
    INT_TEXT.map(lambda n: ["--max-cycles", n]),
    INT_TEXT.map(lambda n: ["--n-robots", n]),
    st.just(["--json"]),
    JUNK,
)


@_settings(FAST)
@given(argv=_argv(BENCHMARK_GROUPS))
@example(argv=["--import", "x" * 300 + ".py"])
def test_benchmark_arguments(scratch, monkeypatch, argv, forget_registered_ids):
    monkeypatch.setattr(benchmark, "run_benchmark", _accepted)
    _check(benchmark.main, argv)


@pytest.mark.slow
@_settings(SLOW)
@given(argv=_argv(BENCHMARK_GROUPS))
def test_benchmark_arguments_many(scratch, monkeypatch, argv, forget_registered_ids):
    monkeypatch.setattr(benchmark, "run_benchmark", _accepted)
    _check(benchmark.main, argv)


# -- swarm-validate ---------------------------------------------------------------------------------------
#: each experiment's options (the work each one stubs out is in _validate_stubs)
VALIDATE_OPTIONS = {
    "range-bearing": ["--json", "--noise", "--platform", "--out", "--repeats", "--seed", "--no-plots", "--near-model", "--variation",
                      "--env-steps", "--no-env"],
    "swarmcom": ["--experiment", "--fit-response", "--quick", "--json", "--out", "--no-plots", "--fig21-mtr", "--seed"],
    "scale-free": ["--json", "--trials", "--configs", "--populations", "--ks", "--workspace", "--arc-range", "--env-steps", "--no-env",
                   "--extra-bearing-noise-deg", "--seed", "--out", "--no-plots"],
    "centroid": ["--json", "--polygons", "--starts", "--rounds", "--polygon-radius", "--heading-noise-deg", "--step-noise",
                 "--pause-rounds", "--no-env", "--no-motion-noise", "--seed", "--out", "--no-plots"],
    "behaviours": ["--out", "--seed", "--seeds", "--only", "--max-cycles", "--message-range", "--json"],
}
VALUE = st.one_of(INT_TEXT, st.sampled_from(["0.5", "-0.5", "nan", "inf", "1e400", "droplet", "epuck", "a", "all", "e", "63", "74",
                                             "hw_variation=false", "rb_noise=2", "bogus=1", "=", "x="]), st.text(max_size=6))


def _validate_argv(experiment: str) -> st.SearchStrategy:
    option = st.tuples(st.sampled_from(VALIDATE_OPTIONS.get(experiment, ["--json"])), st.lists(VALUE, max_size=3)).map(
        lambda ov: [ov[0], *ov[1]])
    return _argv(st.one_of(option, JUNK)).map(lambda rest: [experiment, *rest])


VALIDATE_ARGV = st.one_of(
    st.sampled_from(sorted(VALIDATE_OPTIONS)).flatmap(_validate_argv),
    st.one_of(st.sampled_from(["", "range_bearing", "--json", "-h", "--help", "bogus"]), st.text(max_size=6)).map(lambda e: [e]),
    st.just([]),
)


def _validate_stubs(monkeypatch) -> None:
    from swarm_envs.validate import behaviours, centroid, range_bearing, scale_free, swarmcom

    monkeypatch.setattr(range_bearing, "run", _accepted)
    for name in ("fit_response_c", "experiment_a", "experiment_b", "experiment_c", "experiment_d", "experiment_e"):
        monkeypatch.setattr(swarmcom, name, _accepted)
    monkeypatch.setattr(scale_free, "rigidity_experiment", _accepted)
    monkeypatch.setattr(centroid, "experiment", _accepted)
    monkeypatch.setattr(behaviours, "evaluate", _accepted)


@_settings(FAST)
@given(argv=VALIDATE_ARGV)
@example(argv=[""])  # an unknown experiment: the error is one line
def test_validate_arguments(scratch, monkeypatch, argv):
    from swarm_envs.validate.__main__ import main

    _validate_stubs(monkeypatch)
    _check(main, argv)


@pytest.mark.slow
@_settings(SLOW)
@given(argv=VALIDATE_ARGV)
def test_validate_arguments_many(scratch, monkeypatch, argv):
    from swarm_envs.validate.__main__ import main

    _validate_stubs(monkeypatch)
    _check(main, argv)


def test_nothing_is_written_outside_the_scratch_folder(scratch):
    """The scratch folder is the current directory while the commands run (checked by the fixture)."""
    assert Path(os.getcwd()).resolve() == scratch.resolve()
