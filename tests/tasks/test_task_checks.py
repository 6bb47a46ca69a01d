"""A user's Task is checked like a user's keywords: its class attributes when the class is made, and what its
hooks return into the env (rewards, terms, metrics, spawn, markers, robot groups, masks, counts) when they
return. Each malformed one raises a one-line ``TypeError`` or ``ValueError`` naming the task class, the
attribute or hook and the key; well-formed returns of every real dtype are taken and cast to float64."""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("hypothesis")
from hypothesis import HealthCheck, event, given, settings  # noqa: E402
from hypothesis import strategies as st  # noqa: E402
from hypothesis.extra import numpy as hnp  # noqa: E402

import swarm_envs  # noqa: E402
from swarm_envs.adapters.env import info_group  # noqa: E402
from swarm_envs.tasks.task import Task  # noqa: E402

B, N = 3, 4  # copies of make_vec, robots


def zero_return(task: Task):
    """A well-formed rewards() return: zero rewards, no terms, metric ``m`` zero."""
    return np.zeros((task.n_copies, task.n_agents)), {}, {"m": np.zeros(task.n_copies)}


def task_class(returns=zero_return, **attrs) -> type:
    """A task class named ``MyTask`` (``METRICS = {"m": "mean"}``) whose rewards() returns ``returns(task)``;
    ``attrs`` override or add class attributes and hooks."""
    def rewards(self, state, first):
        return returns(self)

    return type("MyTask", (Task,), {"METRICS": {"m": "mean"}, "rewards": rewards, **attrs})


def vec(cls, **kwargs):
    return swarm_envs.make_vec(cls, B, n_robots=N, sensing="ideal", **kwargs)


def single(cls, **kwargs):
    return swarm_envs.make(cls, n_robots=N, sensing="ideal", **kwargs)


def refused(make_and_run, error: type, *words: str) -> str:
    """Run ``make_and_run()``; assert it raises ``error`` with a one-line message holding every one of ``words``."""
    with pytest.raises(error) as caught:
        make_and_run()
    message = str(caught.value)
    assert "\n" not in message, message
    for word in words:
        assert word in message, (word, message)
    return message


def rows(fill, dtype=float):
    return lambda t: np.full((t.n_copies, t.n_agents), fill, dtype=dtype)


def copies(fill, dtype=float):
    return lambda t: np.full(t.n_copies, fill, dtype=dtype)


# -- rewards() --------------------------------------------------------------------------------------------
BAD_REWARDS = {
    # case: (reward (task -> array), error, words)
    "nan": (rows(np.nan), ValueError, ["reward is nan", "expected finite numbers"]),
    "inf": (rows(-np.inf), ValueError, ["reward is -inf", "expected finite numbers"]),
    "object": (rows(0.0, object), TypeError, ["reward has dtype object", "expected real numbers"]),
    "complex": (rows(0.0, complex), TypeError, ["reward has dtype complex128", "expected real numbers"]),
    "strings": (rows("1", str), TypeError, ["reward has dtype <U1"]),
    "one robot too many": (lambda t: np.zeros((t.n_copies, t.n_agents + 1)), ValueError, ["reward has shape", f"{N + 1}), expected", f"{N}) (copies, agents)"]),
    "one per copy": (lambda t: np.zeros(t.n_copies), ValueError, ["reward has shape", ",), expected", f"{N}) (copies, agents)"]),
    "ragged list": (lambda t: [[0.0], [0.0, 1.0]], TypeError, ["reward is list", "expected an array of real numbers"]),
}


@pytest.mark.parametrize("maker", [vec, single], ids=["make_vec", "make"])
@pytest.mark.parametrize("case", list(BAD_REWARDS))
def test_bad_rewards_are_refused_naming_the_task_and_hook(case, maker):
    reward, error, words = BAD_REWARDS[case]
    cls = task_class(lambda t: (reward(t), {}, {"m": np.zeros(t.n_copies)}))
    refused(lambda: maker(cls).reset(seed=0), error, "MyTask.rewards(): ", *words)


BAD_TERMS = {
    "shape": ({"spread": copies(0.0)}, ValueError, ["term 'spread' has shape", "(copies, agents)"]),
    "nan": ({"spread": rows(np.nan)}, ValueError, ["term 'spread' is nan", "expected finite numbers"]),
    "inf": ({"spread": rows(np.inf)}, ValueError, ["term 'spread' is inf"]),
    "complex": ({"spread": rows(1.0, complex)}, TypeError, ["term 'spread' has dtype complex128"]),
    "object": ({"spread": rows(None, object)}, TypeError, ["term 'spread' has dtype object"]),
}


@pytest.mark.parametrize("case", list(BAD_TERMS))
def test_bad_terms_are_refused_naming_the_term(case):
    terms, error, words = BAD_TERMS[case]
    cls = task_class(lambda t: (np.zeros((t.n_copies, t.n_agents)), {k: f(t) for k, f in terms.items()}, {"m": np.zeros(t.n_copies)}))
    refused(lambda: vec(cls).reset(seed=0), error, "MyTask.rewards(): ", *words)


BAD_METRICS = {
    "shape": ({"m": rows(0.0)}, ValueError, ["metric 'm' has shape", f", {N}), expected (", ",) (copies,)"]),
    "column": ({"m": lambda t: np.zeros((t.n_copies, 1))}, ValueError, ["metric 'm' has shape (", ", 1), expected ("]),
    "inf": ({"m": copies(np.inf)}, ValueError, ["metric 'm' is inf", "expected finite numbers or NaN"]),
    "complex": ({"m": copies(1.0, complex)}, TypeError, ["metric 'm' has dtype complex128"]),
    "object": ({"m": copies(None, object)}, TypeError, ["metric 'm' has dtype object"]),
    "declared, not returned": ({}, ValueError, ["metric 'm' declared in MyTask.METRICS is missing"]),
    "returned, not declared": ({"m": copies(0.0), "extra": copies(0.0)}, ValueError, ["metric 'extra' is not declared in MyTask.METRICS"]),
}


@pytest.mark.parametrize("maker", [vec, single], ids=["make_vec", "make"])
@pytest.mark.parametrize("case", list(BAD_METRICS))
def test_bad_metrics_are_refused_naming_the_metric(case, maker):
    metrics, error, words = BAD_METRICS[case]
    cls = task_class(lambda t: (np.zeros((t.n_copies, t.n_agents)), {}, {k: f(t) for k, f in metrics.items()}))
    refused(lambda: maker(cls).reset(seed=0), error, "MyTask.rewards(): ", *words)


@pytest.mark.parametrize(
    "result, error, words",
    [
        (None, TypeError, ["MyTask.rewards() returned None, expected a tuple (rewards (B, N)"]),
        ("two", TypeError, ["MyTask.rewards() returned tuple", "expected a tuple (rewards"]),
        ("terms list", TypeError, ["MyTask.rewards(): terms is list [], expected a dict"]),
        ("metrics none", TypeError, ["MyTask.rewards(): metrics is None, expected a dict"]),
        ("term key", TypeError, ["MyTask.rewards(): term name 3 is not a non-empty str"]),
    ],
)
def test_a_malformed_rewards_tuple_is_refused(result, error, words):
    forms = {
        None: lambda t: None,
        "two": lambda t: (np.zeros((t.n_copies, t.n_agents)), {}),
        "terms list": lambda t: (np.zeros((t.n_copies, t.n_agents)), [], {"m": np.zeros(t.n_copies)}),
        "metrics none": lambda t: (np.zeros((t.n_copies, t.n_agents)), {}, None),
        "term key": lambda t: (np.zeros((t.n_copies, t.n_agents)), {3: np.zeros((t.n_copies, t.n_agents))}, {"m": np.zeros(t.n_copies)}),
    }
    refused(lambda: single(task_class(forms[result])).reset(seed=0), error, *words)


def test_term_and_metric_names_stay_those_of_the_first_step():
    def changing(extra_term: bool):
        def returns(t):  # from the second call on, one name more
            t.calls = getattr(t, "calls", 0) + 1
            terms = {"a": np.zeros((t.n_copies, t.n_agents))}
            metrics = {"m": np.zeros(t.n_copies)}
            if t.calls > 1 and extra_term:
                terms["b"] = np.zeros((t.n_copies, t.n_agents))
            elif t.calls > 1:
                metrics["b"] = np.zeros(t.n_copies)
            return np.zeros((t.n_copies, t.n_agents)), terms, metrics
        return returns

    env = vec(task_class(changing(True)))
    env.reset(seed=0)
    refused(lambda: env.step(np.zeros(env.action_space.shape)), ValueError, "MyTask.rewards(): term names ['a', 'b'] differ from the first step's ['a']")
    env = vec(task_class(changing(False), METRICS={}))  # no METRICS: the names of the first step hold
    env.reset(seed=0)
    refused(lambda: env.step(np.zeros(env.action_space.shape)), ValueError, "MyTask.rewards(): metric names ['b', 'm'] differ from the first step's ['m']")


def test_real_dtypes_are_taken_and_cast_to_float64():
    def returns(t):
        r = (np.arange(t.n_copies * t.n_agents).reshape(t.n_copies, t.n_agents) % 3).astype(np.int32)
        return r, {"hit": r > 0, "half": (r / 2).astype(np.float32)}, {"m": np.arange(t.n_copies, dtype=np.uint8) > 0}

    env = vec(task_class(returns))
    _, infos = env.reset(seed=0)
    _, rewards, *_, infos = env.step(np.zeros(env.action_space.shape))
    core = env.core
    assert core.rewards.dtype == np.float64 and all(v.dtype == np.float64 for v in (*core.terms.values(), *core.metrics.values()))
    expected = np.arange(B * N).reshape(B, N) % 3
    np.testing.assert_array_equal(rewards, expected.astype(np.float32))
    np.testing.assert_array_equal(infos["reward_terms"]["hit"], expected > 0)
    np.testing.assert_array_equal(infos["reward_terms"]["half"], expected / 2)
    np.testing.assert_array_equal(infos["metrics"]["m"], [0.0, 1.0, 1.0])
    # lists of numbers are arrays too
    env = single(task_class(lambda t: ([[1.0] * t.n_agents], {}, {"m": [0.5]})))
    _, infos = env.reset(seed=0)
    _, rewards, *_ = env.step({a: np.zeros(2) for a in env.agents})
    assert rewards == dict.fromkeys(env.possible_agents, 1.0) and info_group(infos["robot_0"], "metrics") == {"m": 0.5}


def test_a_nan_metric_is_taken_as_undefined_and_undeclared_metrics_need_no_metrics_declaration():
    env = vec(task_class(lambda t: (np.zeros((t.n_copies, t.n_agents)), {}, {"m": np.array([np.nan, 1.0, np.nan])})))
    _, infos = env.reset(seed=0)
    np.testing.assert_array_equal(infos["metrics"]["m"], [np.nan, 1.0, np.nan])
    free = task_class(lambda t: (np.zeros((t.n_copies, t.n_agents)), {}, {"any": np.ones(t.n_copies), "name": np.zeros(t.n_copies)}), METRICS={})
    _, infos = vec(free).reset(seed=0)
    assert set(infos["metrics"]) == {"any", "name"}


@pytest.mark.parametrize("env_id", [i for i in swarm_envs.list_envs() if i.startswith("swarm_envs/")])
def test_the_suites_own_tasks_pass_their_checks(env_id):
    env = swarm_envs.make_vec(env_id, 2, sensing="ideal", max_cycles=3)
    env.reset(seed=0)
    for _ in range(4):  # through an autoreset
        env.step(np.zeros(env.action_space.shape))
    assert env.states().shape[0] == 2


# -- class attributes ----------------------------------------------------------------------------------------
HEADLINE_FORM = "MyTask.HEADLINE must be None or (a metric of METRICS, +1 or -1)"
BAD_ATTRIBUTES = [
    ({"METRICS": 3.0}, "MyTask.METRICS must be a dict", "got float 3.0"),
    ({"METRICS": ["m"]}, "MyTask.METRICS must be a dict", "got list ['m']"),
    ({"METRICS": {1: "mean"}}, "MyTask.METRICS: metric names must be non-empty str", "got 1"),
    ({"METRICS": {"m": ["mean"]}}, "MyTask.METRICS: reductions must be one of ('final', 'mean')", "got 'm': ['mean']"),
    ({"HEADLINE": "x"}, HEADLINE_FORM, "got str 'x'"),
    ({"HEADLINE": ("m",)}, HEADLINE_FORM, "got tuple ('m',)"),
    ({"HEADLINE": ("m", True)}, HEADLINE_FORM, "the sign is not +1 or -1"),
    ({"HEADLINE": (["m"], 1)}, HEADLINE_FORM, "['m'] is not in METRICS ['m']"),
    ({"SETTINGS": [1]}, "MyTask.SETTINGS must be a dict {name: Int(...)", "got list [1]"),
    ({"SETTINGS": 3}, "MyTask.SETTINGS must be a dict", "got int 3"),
    ({"SCRIPTED_POLICY": 3}, 'MyTask.SCRIPTED_POLICY must be None or "module:Class"', "got int 3"),
    ({"SCRIPTED_POLICY": "module_without_class"}, 'MyTask.SCRIPTED_POLICY must be None or "module:Class"', "got str 'module_without_class'"),
]


@pytest.mark.parametrize("attrs, attribute, got", BAD_ATTRIBUTES, ids=[", ".join(f"{k}={v!r}" for k, v in a[0].items()) for a in BAD_ATTRIBUTES])
def test_bad_class_attributes_are_refused_when_the_class_is_made(attrs, attribute, got):
    refused(lambda: task_class(**attrs), TypeError, attribute, got)


def test_good_class_attributes_are_taken():
    cls = task_class(METRICS={"m": "final", "n": "mean"}, HEADLINE=("n", np.int64(-1)), SCRIPTED_POLICY="my_lab.policies:Still", SETTINGS={"n_robots": 2})
    assert cls.TASK_DEFAULTS == {"n_robots": 2} and cls.HEADLINE[0] == "n"


# -- spawn(), markers(), robot_groups() and the other hooks ---------------------------------------------------
BAD_SPAWNS = {
    "none": (lambda t, rng: None, TypeError, ["MyTask.spawn() returned None, expected a tuple (positions (4, 2) m, headings (4,) rad)"]),
    "positions only": (lambda t, rng: np.zeros((4, 2)), TypeError, ["MyTask.spawn() returned a float64 array of shape (4, 2)"]),
    "shape": (lambda t, rng: (np.zeros((3, 2)), np.zeros(4)), ValueError, ["MyTask.spawn(): positions has shape (3, 2), expected (4, 2)"]),
    "headings": (lambda t, rng: (np.eye(4, 2), np.zeros((4, 1))), ValueError, ["MyTask.spawn(): headings has shape (4, 1), expected (4,)"]),
    "nan": (lambda t, rng: (np.full((4, 2), np.nan), np.zeros(4)), ValueError, ["MyTask.spawn(): positions is nan"]),
    "complex": (lambda t, rng: (np.zeros((4, 2), complex), np.zeros(4)), TypeError, ["MyTask.spawn(): positions has dtype complex128"]),
    "overlap": (lambda t, rng: (np.zeros((4, 2)), np.zeros(4)), ValueError, ["MyTask.spawn(): robots overlap"]),
    "outside": (lambda t, rng: (np.full((4, 2), 50.0) + np.arange(4)[:, None], np.zeros(4)), ValueError, ["MyTask.spawn(): robots [0, 1, 2, 3] are outside"]),
}


@pytest.mark.parametrize("case", list(BAD_SPAWNS))
def test_bad_spawns_are_refused_naming_the_hook(case):
    spawn, error, words = BAD_SPAWNS[case]
    refused(lambda: single(task_class(spawn=spawn)).reset(seed=0), error, *words)


def test_a_spawn_without_headings_gets_them_from_the_spawn_stream():
    spots = np.array([[-0.3, -0.3], [0.3, -0.3], [0.3, 0.3], [-0.3, 0.3]])
    env = single(task_class(spawn=lambda t, rng: (spots, None)), arena_size=1.0)
    env.reset(seed=0)
    np.testing.assert_array_equal(env.world.positions, spots)
    assert np.all(np.abs(env.world.headings) <= np.pi)


BAD_MARKERS = {
    "scalar": (lambda t, p: {"goal": 1.0}, ValueError, "MyTask.markers(): marker 'goal' has shape (), expected (2,)"),
    "three": (lambda t, p: {"goal": np.zeros(3)}, ValueError, "MyTask.markers(): marker 'goal' has shape (3,), expected (2,)"),
    "nan": (lambda t, p: {"goal": np.array([np.nan, 0.0])}, ValueError, "MyTask.markers(): marker 'goal' is nan"),
    "complex": (lambda t, p: {"goal": np.zeros(2, complex)}, TypeError, "MyTask.markers(): marker 'goal' has dtype complex128"),
    "list": (lambda t, p: [p[0]], TypeError, "MyTask.markers(): markers is list"),
    "key": (lambda t, p: {0: p[0]}, TypeError, "MyTask.markers(): marker name 0 is not a non-empty str"),
}


@pytest.mark.parametrize("case", list(BAD_MARKERS))
def test_bad_markers_are_refused_in_the_state_of_both_envs(case):
    markers, error, words = BAD_MARKERS[case]
    cls = task_class(markers=markers)
    env = single(cls)
    env.reset(seed=0)
    refused(env.state, error, words)
    env = vec(cls)
    env.reset(seed=0)
    refused(env.states, error, words)


def test_marker_names_stay_those_of_the_first_call():
    def markers(t, positions):  # from the third call on, one name more
        t.calls = getattr(t, "calls", 0) + 1
        return {"centroid": positions.mean(axis=0)} if t.calls <= 2 else {"centroid": positions.mean(axis=0), "goal": np.zeros(2)}

    env = single(task_class(markers=markers))
    env.reset(seed=0)
    assert env.state().shape == env.state_space.shape  # two calls with the first names
    refused(env.state, ValueError, "MyTask.markers(): marker names ['centroid', 'goal'] differ from the first call's ['centroid']")


def test_bad_robot_groups_are_refused_when_drawn():
    pytest.importorskip("pygame")
    bad = {
        "length": (lambda t: (np.zeros(t.n_world - 1, int), ("a", "b")), ValueError, "MyTask.robot_groups(): groups has shape (3,), expected (4,)"),
        "values": (lambda t: (np.full(t.n_world, 2), ("a", "b")), ValueError, "MyTask.robot_groups(): groups hold 2, expected 0 or 1 per robot"),
        "labels": (lambda t: (np.zeros(t.n_world, int), "ab"), TypeError, "MyTask.robot_groups(): labels are str 'ab', expected two str legend labels"),
        "form": (lambda t: np.zeros(t.n_world, int), TypeError, "MyTask.robot_groups() returned a int64 array of shape (4,)"),
    }
    for groups, error, words in bad.values():
        env = single(task_class(robot_groups=groups), render_mode="rgb_array")
        env.reset(seed=0)
        refused(env.render, error, words)
    env = single(task_class(robot_groups=lambda t: (np.arange(t.n_world) % 2 == 1, ("even", "odd"))), render_mode="rgb_array")
    env.reset(seed=0)
    assert env.render().ndim == 3


def test_static_message_bits_are_flags():
    cls = task_class(
        n_static_robots=lambda t: 1,
        static_messages=lambda t, obs, first: np.ones((t.n_copies, 1, 2)),  # floats, not flags
    )
    refused(
        lambda: single(cls, message_bits=2).reset(seed=0),
        TypeError,
        "MyTask.static_messages() returned a float64 array of shape (1, 1, 2), expected a (1, 1, 2) bool array",
    )


@pytest.mark.parametrize(
    "hook, value, error, words",
    [
        ("n_static_robots", None, TypeError, "MyTask.n_static_robots() returned None, expected an int in [0, 10000]"),
        ("n_static_robots", 1.0, TypeError, "MyTask.n_static_robots() returned float 1.0, expected an int"),
        ("n_static_robots", -1, ValueError, "MyTask.n_static_robots() returned int -1, expected an int in [0, 10000]"),
        ("default_arena_size", None, TypeError, "MyTask.default_arena_size() returned None, expected a finite number of metres > 0"),
        ("default_arena_size", float("nan"), ValueError, "MyTask.default_arena_size() returned float nan"),
        ("default_arena_size", -2.0, ValueError, "MyTask.default_arena_size() returned float -2.0"),
    ],
)
def test_bad_counts_and_sizes_are_refused_when_the_env_is_built(hook, value, error, words):
    refused(lambda: single(task_class(**{hook: lambda t: value})), error, words)


# -- property: any return of rewards() is taken with the right shapes or refused clearly ------------------
DTYPES = ["float64", "float32", "int64", "uint8", "bool", "complex128", "object", "str"]
SPECIAL = [np.nan, np.inf, -np.inf]


@st.composite
def returned_array(draw, shape: tuple[int, ...]) -> object:
    """Mostly a well-formed array (``shape``, a real dtype, finite values); else one of a near shape, of any
    dtype, with NaN or infinite values sometimes; or a list of it, or something that is no array at all."""
    finite = st.floats(-1e3, 1e3, allow_nan=False, width=64)
    if draw(st.integers(0, 9)) < 6:
        arr = draw(hnp.arrays(np.float64, shape, elements=finite)).astype(draw(st.sampled_from(["float64", "float32", "int64", "bool"])))
        return arr.tolist() if draw(st.integers(0, 4)) == 0 else arr
    near = [shape, shape[:-1], shape + (1,), (shape[0] + 1,) + shape[1:], shape[::-1], ()]
    got = draw(st.sampled_from(near[:1] * 4 + near[1:]))
    values = draw(hnp.arrays(np.float64, got, elements=st.one_of(finite, finite, finite, st.sampled_from(SPECIAL))))
    dtype = draw(st.sampled_from(DTYPES[:1] * 4 + DTYPES[1:]))
    if dtype in ("int64", "uint8", "bool"):
        arr = (np.abs(np.nan_to_num(values, posinf=7.0, neginf=7.0)) % 3).astype(dtype)
    else:
        arr = values.astype(dtype)
    form = draw(st.sampled_from(["array"] * 6 + ["list", "none", "text", "ragged"]))
    return {"array": arr, "list": arr.tolist(), "none": None, "text": "0.5", "ragged": [[0.0], [0.0, 1.0]]}[form]


def takes(value: object, shape: tuple[int, ...], nan: bool = False) -> bool:
    """The contract: real numbers (bool, int or float) of ``shape``, finite (``nan``: or NaN)."""
    try:
        arr = np.asarray(value)
    except (TypeError, ValueError):
        return False
    if arr.dtype.kind not in "biuf" or arr.shape != shape:
        return False
    arr = arr.astype(np.float64)
    return not np.isinf(arr).any() if nan else bool(np.isfinite(arr).all())


@st.composite
def returned(draw, declared: bool, b: int) -> tuple[object, bool]:
    """(a return of rewards() for ``b`` copies of N agents, whether the contract takes it)."""
    reward = draw(returned_array((b, N)))
    term_names = draw(st.sampled_from([[], ["a"], ["a"], ["a", "b"], [3]]))
    terms = {k: draw(returned_array((b, N))) for k in term_names}
    metric_names = draw(st.sampled_from([["m"], ["m"], ["m"], [], ["z"], ["m", "z"]]))
    metrics = {k: draw(returned_array((b,))) for k in metric_names}
    form = draw(st.sampled_from(["tuple"] * 12 + ["list", "pair", "none", "terms list"]))
    ok = (
        takes(reward, (b, N))
        and all(isinstance(k, str) and takes(v, (b, N)) for k, v in terms.items())
        and all(takes(v, (b,), nan=True) for v in metrics.values())
        and (set(metrics) == {"m"} or not declared)
        and form in ("tuple", "list")
    )
    result = {
        "tuple": (reward, terms, metrics),
        "list": [reward, terms, metrics],
        "pair": (reward, terms),
        "none": None,
        "terms list": (reward, list(terms.values()), metrics),
    }[form]
    return result, ok


def check_any_return(data) -> None:
    """A drawn rewards() return, in make_vec (B copies) or the single env: taken, with the right shapes and
    the returned values, if the contract takes it; else a one-line TypeError or ValueError naming the hook."""
    declared = data.draw(st.booleans(), label="declared")
    vectorised = data.draw(st.booleans(), label="make_vec")
    b = B if vectorised else 1
    result, ok = data.draw(returned(declared, b), label="result")
    event(f"taken: {ok}")
    cls = task_class(lambda t: result, **({} if declared else {"METRICS": {}}))
    env = vec(cls) if vectorised else single(cls)
    if not ok:
        with pytest.raises((TypeError, ValueError)) as caught:
            env.reset(seed=0)
        message = str(caught.value)
        assert message.startswith("MyTask.rewards()") and "\n" not in message, message
        return
    reward, terms, metrics = np.asarray(result[0], dtype=np.float64), result[1], result[2]
    env.reset(seed=0)
    if vectorised:
        _, rewards, *_, infos = env.step(np.zeros(env.action_space.shape))
        assert rewards.shape == (B, N) and rewards.dtype == np.float32
        np.testing.assert_array_equal(rewards, reward.astype(np.float32))
        got_terms, got_metrics = infos["reward_terms"], infos["metrics"]
    else:
        _, rewards, *_, infos = env.step({a: np.zeros(2) for a in env.agents})
        assert list(rewards) == env.possible_agents
        np.testing.assert_array_equal(list(rewards.values()), reward[0])
        per_agent = [info_group(infos[a], "reward_terms") for a in env.possible_agents]
        got_terms = {k: np.array([[t[k] for t in per_agent]]) for k in per_agent[0]}
        got_metrics = {k: np.array([v]) for k, v in info_group(infos["robot_0"], "metrics").items()}
    assert list(got_terms) == list(terms) and list(got_metrics) == list(metrics)
    for k, v in terms.items():
        assert got_terms[k].shape == (b, N)
        np.testing.assert_array_equal(got_terms[k], np.asarray(v, dtype=np.float64))
    for k, v in metrics.items():
        assert got_metrics[k].shape == (b,)
        np.testing.assert_array_equal(got_metrics[k], np.asarray(v, dtype=np.float64))


@settings(max_examples=40, deadline=None, suppress_health_check=list(HealthCheck), derandomize=True, database=None)
@given(data=st.data())
def test_any_rewards_return_is_taken_with_its_shapes_or_refused_clearly(data):
    check_any_return(data)


@pytest.mark.slow
@settings(max_examples=1000, deadline=None, suppress_health_check=list(HealthCheck), database=None)
@given(data=st.data())
def test_any_rewards_return_is_taken_with_its_shapes_or_refused_clearly_many(data):
    check_any_return(data)
