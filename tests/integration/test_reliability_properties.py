"""Property test (hypothesis): random sequences of valid and invalid calls.

A rejected call (bad action, reset argument or setting) raises its documented exception type and leaves
the env unchanged and usable: afterwards the env steps exactly like a twin that never saw the bad call.
Documented types: ``TypeError`` (wrong type), ``ValueError`` (bad value), ``KeyError`` (unknown or missing
agent), ``RuntimeError`` (step on a finished episode).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, event, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402

from swarm_envs import flocking_v0  # noqa: E402
from tests.conftest import assert_tree_equal, dotted_keys  # noqa: E402

CONFIGS = [
    {"n_robots": 3, "sensing": "ideal", "max_cycles": 8},
    {"n_robots": 2, "sensing": "ideal", "message_bits": 2, "max_cycles": 8, "arena": "circle"},
    {"n_robots": 3, "sensing": "full", "max_cycles": 8},
]


def bad_step(env, k: int):
    """(actions, expected exception) for bad variant ``k``."""
    size = env.layout.action_size
    good = {a: np.zeros(size) for a in env.agents}
    first = env.agents[0]
    variants = [
        ({**good, first: np.full(size, np.nan)}, ValueError),
        ({**good, first: np.zeros(size + 1)}, ValueError),
        ({**good, first: ["1"] * size}, TypeError),
        ({**good, first: np.ones(size, complex)}, TypeError),
        ({**good, first: [True] * size}, TypeError),
        ({a: v for a, v in good.items() if a != first}, KeyError),
        ({**good, "robot_99": np.zeros(size)}, KeyError),
        (list(good.values()), TypeError),
    ]
    return variants[k % len(variants)]


def bad_reset(env, k: int):
    """(reset kwargs, expected exception) for bad variant ``k``."""
    n = env.n_world
    variants = [
        ({"seed": -1}, ValueError),
        ({"seed": 2.5}, TypeError),
        ({"options": "positions"}, TypeError),
        ({"options": {"positions": np.zeros((n, 2))}}, ValueError),  # all on one spot: overlap
        ({"options": {"positions": np.full((n, 2), 1e3)}}, ValueError),  # outside
        ({"options": {"headings": np.zeros(n + 1)}}, ValueError),
        ({"options": {"positions": [["0", "1"]] * n}}, ValueError),
        ({"seed": 3, "options": {"headings": np.full(n, np.inf)}}, ValueError),
    ]
    return variants[k % len(variants)]


BAD_SETTINGS = [
    ({"rb_noise": math.nan}, ValueError),
    ({"relative_threshold": math.inf}, ValueError),
    ({"code": (15, 9)}, ValueError),
    ({"message_bits": 256}, ValueError),
    ({"n_robots": True}, ValueError),
    ({"n_robot": 3}, TypeError),
    ({"n_robots": 500, "arena_size": 0.3}, ValueError),
]


def snapshot(env) -> dict:
    w = env.world
    snap = {
        "world": [w.positions.copy(), w.headings.copy(), w.velocities.copy(), w.angular_velocities.copy(), w.bumps.copy()],
        "cycles": env.num_cycles,
        "agents": list(env.agents),
        "last_actions": env.core.last_actions.copy(),
        "rng": repr(env.core.generators[0].bit_generator.state),
    }
    if env._frame is not None:
        snap["obs"] = env.batched_observations()
    return snap


OPS = st.lists(
    st.tuples(st.sampled_from(["step", "step", "reset", "bad_step", "bad_reset", "bad_settings"]), st.integers(0, 40)),
    min_size=1,
    max_size=12,
)


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow], derandomize=True, database=None)
@given(config=st.sampled_from([0, 0, 0, 1, 1, 2]), ops=OPS)
def test_rejected_calls_change_nothing(config, ops):
    kwargs = CONFIGS[config]
    env, twin = flocking_v0.parallel_env(**kwargs), flocking_v0.parallel_env(**kwargs)
    assert_tree_equal(env.reset(seed=0), twin.reset(seed=0))
    for kind, k in ops:
        if kind == "step":
            if not env.agents:
                for e in (env, twin):
                    with pytest.raises(RuntimeError, match="reset"):
                        e.step({})
                continue
            rng = np.random.default_rng(k)
            actions = {a: rng.uniform(-1.5, 1.5, env.layout.action_size) for a in env.agents}
            assert_tree_equal(env.step(actions), twin.step(actions))
        elif kind == "reset":
            seed = None if k % 4 == 0 else k
            assert_tree_equal(env.reset(seed=seed), twin.reset(seed=seed))
        elif kind == "bad_settings":
            bad, error = BAD_SETTINGS[k % len(BAD_SETTINGS)]
            with pytest.raises(error):
                flocking_v0.parallel_env(**{**kwargs, **bad})
        else:
            before = snapshot(env)
            if kind == "bad_step":
                if env.agents:
                    actions, error = bad_step(env, k)
                else:
                    actions, error = {}, RuntimeError
                with pytest.raises(error):
                    env.step(actions)
            else:
                call, error = bad_reset(env, k)
                with pytest.raises(error):
                    env.reset(**call)
            assert_tree_equal(snapshot(env), before)
    # still usable, and still the twin of the env that never saw a bad call
    if not env.agents:
        assert_tree_equal(env.reset(), twin.reset())
    actions = {a: np.full(env.layout.action_size, 0.7) for a in env.agents}
    assert_tree_equal(env.step(actions), twin.step(actions))


# -- every keyword of every env and of make_vec: a clear error naming the key, or an env that works ---------
import fractions  # noqa: E402

import swarm_envs  # noqa: E402
from swarm_envs.sim.platforms import PLATFORMS, get_platform  # noqa: E402
from swarm_envs.registry import task_class  # noqa: E402
from swarm_envs.tasks.settings import COMMON_SETTINGS, Choice, Flag, Int, Real  # noqa: E402
from tests.property_worker import EnvWorker  # noqa: E402

#: seconds one example may take in the worker (build, reset and 3 steps of a small env)
EXAMPLE_TIME_LIMIT = 120.0
#: the settings every example starts from (a small, fast env); the drawn keys override them
BASE = {"n_robots": 3, "sensing": "ideal", "max_cycles": 5}
#: a valid value is drawn from at most this range for these keys, so that an accepted env stays small
SMALL = {"n_robots": 12, "n_neighbours": 16, "n_messages": 16, "max_cycles": 20, "physics_substeps": 40, "n_anchors": 12,
         "message_bits": 32}

JUNK = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-(2**70), 2**70),
    st.sampled_from([0, -1, 2**31, 2**63, 2**64, 10**18]),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([math.nan, math.inf, -math.inf, 1e300, -0.0, 5e-324]),
    st.text(max_size=6),
    st.lists(st.integers(-3, 20), max_size=3),
    st.tuples(st.integers(-3, 20), st.integers(-3, 20)),
    st.builds(np.float32, st.floats(-1e3, 1e3, width=32)),
    st.builds(np.int64, st.integers(-(2**63), 2**63 - 1)),
    st.builds(np.bool_, st.booleans()),
    st.just(fractions.Fraction(1, 2)),
    st.just(np.array([1.0, 2.0])),
    st.dictionaries(st.text(max_size=3), st.integers(), max_size=2),
    st.just(object()),
)


def valid_values(key: str, rule) -> st.SearchStrategy:
    """Values the rule accepts (numpy scalars and fractions included where a number is meant)."""
    if isinstance(rule, Flag):
        return st.one_of(st.booleans(), st.builds(np.bool_, st.booleans()))
    if isinstance(rule, Choice):
        return st.sampled_from(list(rule.choices))
    if isinstance(rule, Int):
        high = min(rule.high if rule.high is not None else rule.low + 100, SMALL.get(key, 10**6))
        ints = st.integers(rule.low, max(rule.low, high))
        return st.one_of(ints, ints.map(np.int64), st.none()) if rule.allow_none else st.one_of(ints, ints.map(np.int64))
    if isinstance(rule, Real):
        low = rule.low + (1e-3 if rule.low_open else 0.0)
        floats = st.floats(low, min(rule.high, 100.0), allow_nan=False)
        out = st.one_of(floats, floats.map(np.float32), floats.map(np.float64), st.integers(math.ceil(low), int(min(rule.high, 100.0))))
        return st.one_of(out, st.none()) if rule.allow_none else out
    if key == "platform":
        base = st.sampled_from(sorted(PLATFORMS))
        return st.one_of(base, base.map(get_platform))
    if key == "code":
        from swarm_envs.comm.bch import SUPPORTED

        return st.sampled_from(sorted(SUPPORTED)).flatmap(lambda c: st.sampled_from([c, list(c), (np.int64(c[0]), c[1])]))
    raise AssertionError(f"no strategy for {key}")


def settings_draw(env_id: str, junk: bool) -> st.SearchStrategy:
    """1-3 keyword arguments of ``env_id``: valid values only, or (``junk``) each a valid or a junk value,
    and sometimes an unknown name."""
    rules = {**COMMON_SETTINGS, **task_class(env_id).settings()}
    rules.pop("render_mode")  # rendering opens windows; it has its own tests
    keys = sorted(rules) + (["n_robot", "bogus"] if junk else [])
    value = lambda key: valid_values(key, rules[key]) if key in rules else JUNK  # noqa: E731
    pick = (lambda k: st.one_of(value(k), JUNK)) if junk else value
    one = st.sampled_from(keys).flatmap(lambda k: st.tuples(st.just(k), pick(k)))
    return st.lists(one, min_size=1, max_size=3, unique_by=lambda kv: kv[0]).map(dict)


@pytest.fixture(scope="module")
def env_worker():
    worker = EnvWorker()
    yield worker
    worker.close()


def check_example(worker: EnvWorker, env_id: str, drawn: dict, num_envs) -> None:
    kind, name, detail = worker.run(env_id, {**BASE, **drawn}, num_envs, EXAMPLE_TIME_LIMIT)
    event(f"{kind} {name}")
    assert kind in ("ok", "error"), f"{env_id} {drawn!r:.300} num_envs={num_envs!r}: {kind} {name}\n{detail}"
    if kind == "error":
        named = list(drawn) + ([] if isinstance(num_envs, str) and num_envs == "single" else ["num_envs"])
        assert any(key in detail for key in named), f"{env_id} {drawn!r:.300}: {name}: {detail!r} names none of {named}"
        assert "\n" not in detail, detail


ENV_IDS = sorted(swarm_envs.list_envs())


@settings(max_examples=30, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True, database=None)
@given(data=st.data())
@pytest.mark.parametrize("env_id", ENV_IDS)
def test_every_env_keyword_is_checked_or_works(env_worker, env_id, data):
    junk = data.draw(st.booleans(), label="junk")
    check_example(env_worker, env_id, data.draw(settings_draw(env_id, junk), label="settings"), "single")


GOOD_NUM_ENVS = st.one_of(st.integers(1, 3), st.builds(np.int64, st.integers(1, 3)))
NUM_ENVS = st.one_of(GOOD_NUM_ENVS, JUNK)


@settings(max_examples=30, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True, database=None)
@given(data=st.data())
@pytest.mark.parametrize("env_id", ENV_IDS)
def test_every_make_vec_keyword_is_checked_or_works(env_worker, env_id, data):
    junk = data.draw(st.booleans(), label="junk")
    num_envs = data.draw(NUM_ENVS if junk else GOOD_NUM_ENVS, label="num_envs")
    check_example(env_worker, env_id, data.draw(settings_draw(env_id, junk), label="settings"), num_envs)


@pytest.mark.slow
@settings(max_examples=400, deadline=None, suppress_health_check=list(HealthCheck), database=None)
@given(data=st.data())
@pytest.mark.parametrize("env_id", ENV_IDS)
def test_every_env_keyword_is_checked_or_works_many(env_worker, env_id, data):
    junk = data.draw(st.booleans(), label="junk")
    num_envs = data.draw(st.one_of(st.just("single"), NUM_ENVS if junk else GOOD_NUM_ENVS), label="num_envs")
    check_example(env_worker, env_id, data.draw(settings_draw(env_id, junk), label="settings"), num_envs)


def test_the_worker_reports_crashes_and_hangs(env_worker, monkeypatch):
    """The harness itself: a crash of the child and a hang are reported, and the worker recovers."""
    import dataclasses

    epuck = get_platform("epuck")
    # a platform whose checks are bypassed (object.__new__ skips __post_init__): pymunk aborts on its mass
    broken = object.__new__(type(epuck))
    for f in dataclasses.fields(epuck):
        object.__setattr__(broken, f.name, getattr(epuck, f.name))
    object.__setattr__(broken, "mass", -1.0)
    kind, code, _ = env_worker.run("swarm_envs/Flocking-v0", {**BASE, "platform": broken}, "single", EXAMPLE_TIME_LIMIT)
    assert kind == "crash" and code != "0"
    assert env_worker.run("swarm_envs/Flocking-v0", BASE, "single", EXAMPLE_TIME_LIMIT)[0] == "ok"
    # an example slower than its time limit is a hang
    assert env_worker.run("swarm_envs/Flocking-v0", {**BASE, "n_robots": 2000}, "single", 0.05)[0] == "hang"
    assert env_worker.run("swarm_envs/Flocking-v0", BASE, "single", EXAMPLE_TIME_LIMIT)[0] == "ok"


# -- train.py configs: a one-line error naming the key and exit code 2, or a run that starts -----------------
import contextlib  # noqa: E402
import io  # noqa: E402
import tempfile  # noqa: E402
from pathlib import Path  # noqa: E402

import signal  # noqa: E402

from swarm_envs.agents import train as train_cli  # noqa: E402
from swarm_envs.agents.config import DEFAULTS  # noqa: E402
from swarm_envs.agents.scripted import KWARG_RULES  # noqa: E402
from swarm_envs.agents.tasks import SHORT_NAMES  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]


CONFIG_KEYS = sorted(
    set(dotted_keys(DEFAULTS))
    | {f"env.{k}" for k in COMMON_SETTINGS if k != "render_mode"}
    | {f"env.{k}" for name in SHORT_NAMES for k in task_class(SHORT_NAMES[name]).settings()}
    | {f"agent.scripted_kwargs.{k}" for k in KWARG_RULES}
    | {"agent.scripted_kwargs.bogus", "bogus", "train.bogus"}
)
#: seconds an example may take: the config check builds the env once (no training: it is stubbed)
CONFIG_TIME_LIMIT = 60
YAML_TEXT = st.one_of(
    st.integers(-(2**70), 2**70).map(str),
    st.floats().map(lambda x: {math.inf: ".inf", -math.inf: "-.inf"}.get(x, ".nan" if math.isnan(x) else repr(x))),
    st.sampled_from([
        "null", "true", "false", "[]", "{}", "[1, 2]", "[15, 7]", "{a: 1}", "{1: a, foo: b}", "''", "ideal", "full", "rone", "circle",
        "flocking", "centroid_seeking", "swarm_envs/Flocking-v0", "0", "-1", "1", "3", "4294967296", "1e9", "1e400", "0.5", "1000000",
        "!!binary aGVsbG8=", "[", ":", "2020-01-01", "[64, 64]", "relu", "9" * 5000, "-" + "9" * 5000, "1" + "0" * 30,
        "9223372036854775807", "18446744073709551616", *SHORT_NAMES,
    ]),
    st.text(max_size=8),
)
TRAIN_BASE = [
    "env.sensing=ideal", "env.n_robots=4", "env.max_cycles=20", "train.total_timesteps=256", "train.n_envs=1",
    "train.checkpoint_freq=0", "train.progress_bar=false", "agent.n_steps=64", "agent.batch_size=128", "agent.n_epochs=1",
    "eval.n_seeds=1",
]


class _TrainingStarted(BaseException):
    """Raised by the stubbed trainer: the whole config passed and training would start."""


def check_config_example(monkeypatch, overrides: list[tuple[str, str]], eval_only: bool) -> None:
    def started(*args, **kwargs):
        raise _TrainingStarted

    def hang(*args):
        raise AssertionError(f"the config check took more than {CONFIG_TIME_LIMIT} s: {overrides}")

    monkeypatch.setattr(train_cli, "train", started)
    monkeypatch.setattr(train_cli, "load_checkpoint", started)
    previous = signal.signal(signal.SIGALRM, hang)
    signal.alarm(CONFIG_TIME_LIMIT)
    try:
        _check_config_example(overrides, eval_only)
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, previous)


def _check_config_example(overrides: list[tuple[str, str]], eval_only: bool) -> None:
    sets = [x for key, text in overrides for x in ("--set", f"{key}={text}")]
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp) / "out"
        argv = ["--config", str(ROOT / "configs" / "aggregation.yaml"), "--output", str(out)]
        argv += [x for o in TRAIN_BASE for x in ("--set", o)] + sets
        if eval_only:
            (Path(tmp) / "model.zip").write_bytes(b"PK\x05\x06" + bytes(18))  # an empty zip: checked after the config
            argv += ["--eval-only", str(Path(tmp) / "model.zip")]
        stderr = io.StringIO()
        try:
            with contextlib.redirect_stderr(stderr), contextlib.redirect_stdout(io.StringIO()):
                code = train_cli.main(argv)
        except _TrainingStarted:
            event("config accepted")
            return
        err = stderr.getvalue()
        event(f"exit {code}")
        assert code == 2 and err.count("\n") == 1 and "Traceback" not in err, (overrides, code, err)
        named = {part for key, _ in overrides for part in (key, key.split(".")[-1])}
        assert any(name in err for name in named), (overrides, err)
        assert sorted(p.name for p in Path(tmp).iterdir()) == (["model.zip"] if eval_only else []), "nothing is written"


def _leaf(key: str):
    node = DEFAULTS
    for part in key.split("."):
        node = node[part]
    return node


def valid_text(key: str) -> st.SearchStrategy:
    """YAML text of a value the key accepts (most of the time), for configs that pass."""
    import json

    if key.startswith("env."):
        name = key[4:]
        rule = {**COMMON_SETTINGS, **task_class("swarm_envs/Aggregation-v0").settings()}.get(name)
        if rule is None or name == "platform":
            return st.just("null") if rule is None else st.sampled_from(sorted(PLATFORMS))
        plain = valid_values(name, rule).map(lambda v: v.item() if isinstance(v, np.generic) else v)
        return plain.map(lambda v: json.dumps(list(v) if isinstance(v, tuple) else v, default=lambda o: o.item()))
    if key == "task":
        return st.sampled_from(sorted(SHORT_NAMES))
    if key.startswith("agent.scripted_kwargs.") and key.rsplit(".", 1)[1] in KWARG_RULES:
        return st.just(json.dumps(KWARG_RULES[key.rsplit(".", 1)[1]].default))
    default = _leaf(key) if key in set(dotted_keys(DEFAULTS)) else None
    if isinstance(default, bool) or default is None or isinstance(default, (str, list, dict)):
        return st.just(json.dumps(default))
    if isinstance(default, int):
        return st.integers(max(1, default // 2), default * 2 + 1).map(str)
    return st.floats(default / 2, min(default * 2, 1.0) if default <= 1 else default * 2).map(repr) if default > 0 else st.just(repr(default))


CONFIG_DRAW = st.lists(
    st.one_of(
        st.tuples(st.sampled_from(CONFIG_KEYS), YAML_TEXT),
        st.sampled_from(CONFIG_KEYS).flatmap(lambda k: st.tuples(st.just(k), valid_text(k))),
    ),
    min_size=1,
    max_size=3,
)


@settings(max_examples=80, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True, database=None)
@given(overrides=CONFIG_DRAW, eval_only=st.booleans())
def test_train_config_is_checked_or_starts(monkeypatch, overrides, eval_only):
    check_config_example(monkeypatch, overrides, eval_only)


@pytest.mark.slow
@settings(max_examples=1000, deadline=None, suppress_health_check=list(HealthCheck), database=None)
@given(overrides=CONFIG_DRAW, eval_only=st.booleans())
def test_train_config_is_checked_or_starts_many(monkeypatch, overrides, eval_only):
    check_config_example(monkeypatch, overrides, eval_only)
