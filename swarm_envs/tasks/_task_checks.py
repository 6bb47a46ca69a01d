"""Checks of what a :class:`swarm_envs.tasks.task.Task` declares (class attributes) and returns into the env (hooks).

Every check raises a one-line ``TypeError`` (wrong type or dtype) or ``ValueError`` (wrong shape, value or
name) that names the task class, the hook or class attribute, the key, and what was expected against what
came. Accepted numbers (bool, integer or float dtypes) are cast to float64; a float64 array passes through
as it is. The per-step check of :meth:`Task.rewards <swarm_envs.tasks.task.Task.rewards>` (:class:`RewardsCheck`)
costs one dtype and shape comparison and one finiteness reduction per returned array.
"""

from __future__ import annotations

import numbers
from collections.abc import Mapping
from typing import Any

import numpy as np

from swarm_envs._text import shown

__all__ = [
    "REAL_KINDS",
    "REDUCTIONS",
    "RewardsCheck",
    "checked_array",
    "check_declarations",
    "checked_spawn",
    "checked_markers",
    "checked_robot_groups",
    "checked_mask",
    "checked_count",
    "checked_length",
]

#: numpy dtype kinds a task may return where numbers are meant: bool, signed and unsigned integer, float
REAL_KINDS = "biuf"

#: how a metric is reduced over an episode for evaluation: its value after the last step, or its mean
#: over the steps after the reset
REDUCTIONS = ("final", "mean")

_REWARDS_FORM = "a tuple (rewards (B, N), reward terms {name: (B, N)}, metrics {name: (B,)})"


def _one_line(text: str) -> str:
    return " ".join(text.split())


def _described(value: Any) -> str:
    """A short one-line description of a returned value: dtype and shape of an array, else type and repr."""
    if isinstance(value, np.ndarray):
        return f"a {value.dtype} array of shape {value.shape}"
    if value is None:
        return "None"
    return f"{type(value).__name__} {_one_line(shown(value, 60))}"


def _names(names: Any) -> str:
    return _one_line(shown(sorted(names, key=str), 120))


def checked_array(value: Any, owner: str, what: str, shape: tuple[int, ...], axes: str, nan: bool = False) -> np.ndarray:
    """``value`` as a float64 array of ``shape``: ``TypeError`` unless it holds real numbers (bool, integer or
    float dtype), ``ValueError`` for another shape or a value that is not finite (``nan=True``: NaN allowed,
    +-inf not). Errors read ``"{owner}: {what} has ..., expected {shape} {axes}"``."""
    arr = value
    if type(arr) is not np.ndarray:
        try:
            arr = np.asarray(value)
        except (TypeError, ValueError):  # ragged nesting and the like
            raise TypeError(f"{owner}: {what} is {_described(value)}, expected an array of real numbers of shape {shape} {axes}") from None
    kind = arr.dtype.kind
    if kind not in REAL_KINDS:
        raise TypeError(f"{owner}: {what} has dtype {arr.dtype}, expected real numbers (bool, int or float) of shape {shape} {axes}")
    if arr.shape != shape:
        raise ValueError(f"{owner}: {what} has shape {arr.shape}, expected {shape} {axes}")
    if arr.dtype != np.float64:
        with np.errstate(over="ignore"):  # a value too large for float64 becomes inf and is refused below
            arr = arr.astype(np.float64)
    if kind == "f":  # bools and integers are finite
        bad = np.isinf(arr).any() if nan else not np.isfinite(arr).all()
        if bad:
            wrong = np.isinf(arr) if nan else ~np.isfinite(arr)
            first = tuple(int(i) for i in np.argwhere(wrong)[0])
            allowed = "finite numbers or NaN (undefined)" if nan else "finite numbers"
            where = f" at index {first} of {axes}" if first else ""
            raise ValueError(f"{owner}: {what} is {arr[first]}{where} ({int(wrong.sum())} of {arr.size} values), expected {allowed}")
    return arr


def _checked_keys(group: Any, owner: str, what: str) -> None:
    """``TypeError`` unless ``group`` is a dict whose keys are non-empty strings."""
    if not isinstance(group, Mapping):
        raise TypeError(f"{owner}: {what}s is {_described(group)}, expected a dict {{name: array}}")
    for key in group:
        if not isinstance(key, str) or not key:
            raise TypeError(f"{owner}: {what} name {_one_line(shown(key, 60))} is not a non-empty str")


class RewardsCheck:
    """Checks and casts each ``(rewards, terms, metrics)`` returned by ``task.rewards(state, first)``.

    Rewards and terms: ``(B, N)`` finite real numbers; metrics: ``(B,)`` real numbers, finite or NaN (a
    metric undefined in a copy at that step). Metric names: exactly ``METRICS``'s when the task declares
    ``METRICS``, else those of the first call; term names: those of the first call.

    Args:
        task: the task (its class, ``n_copies`` and ``n_agents``).
    """

    def __init__(self, task: Any) -> None:
        cls = type(task)
        self.task_name = cls.__name__
        self.owner = f"{cls.__name__}.rewards()"
        self.rows = (int(task.n_copies), int(task.n_agents))
        self.copies = (int(task.n_copies),)
        self.declared = dict(cls.METRICS)
        self.metric_names: frozenset[str] | None = frozenset(self.declared) if self.declared else None
        self.term_names: frozenset[str] | None = None

    def __call__(self, result: Any) -> tuple[np.ndarray, dict[str, np.ndarray], dict[str, np.ndarray]]:
        """``result`` checked: (rewards (B, N), terms {name: (B, N)}, metrics {name: (B,)}) as float64 arrays."""
        owner = self.owner
        if not isinstance(result, (tuple, list)) or len(result) != 3:
            raise TypeError(f"{owner} returned {_described(result)}, expected {_REWARDS_FORM}")
        rewards, terms, metrics = result
        rewards = checked_array(rewards, owner, "reward", self.rows, "(copies, agents)")
        if not isinstance(terms, dict) or terms.keys() != self.term_names:
            self._check_term_names(terms)
        terms = {k: checked_array(v, owner, f"term {k!r}", self.rows, "(copies, agents)") for k, v in terms.items()}
        if not isinstance(metrics, dict) or metrics.keys() != self.metric_names:
            self._check_metric_names(metrics)
        metrics = {k: checked_array(v, owner, f"metric {k!r}", self.copies, "(copies,)", nan=True) for k, v in metrics.items()}
        return rewards, terms, metrics

    def _check_term_names(self, terms: Any) -> None:
        _checked_keys(terms, self.owner, "term")
        if self.term_names is None:
            self.term_names = frozenset(terms)
        elif terms.keys() != self.term_names:
            raise ValueError(f"{self.owner}: term names {_names(terms)} differ from the first step's {_names(self.term_names)}; return the same names every step")

    def _check_metric_names(self, metrics: Any) -> None:
        _checked_keys(metrics, self.owner, "metric")
        if self.declared and metrics.keys() != self.declared.keys():
            missing = sorted(set(self.declared) - set(metrics))
            if missing:
                raise ValueError(
                    f"{self.owner}: metric {missing[0]!r} declared in {self.task_name}.METRICS is missing from the returned metrics {_names(metrics)}"
                )
            extra = sorted(set(metrics) - set(self.declared))
            raise ValueError(
                f"{self.owner}: metric {extra[0]!r} is not declared in {self.task_name}.METRICS {_names(self.declared)}; "
                "declare it with its reduction (\"final\" or \"mean\")"
            )
        if self.metric_names is None:
            self.metric_names = frozenset(metrics)
        elif metrics.keys() != self.metric_names:
            raise ValueError(f"{self.owner}: metric names {_names(metrics)} differ from the first step's {_names(self.metric_names)}; return the same names every step")


def checked_spawn(task: Any, result: Any) -> tuple[np.ndarray, np.ndarray | None]:
    """``task.spawn(rng)``'s return checked: (positions (n_world, 2) m, headings (n_world,) rad or None),
    finite float64 arrays."""
    owner = f"{type(task).__name__}.spawn()"
    n = int(task.n_world)
    if not isinstance(result, (tuple, list)) or len(result) != 2:
        raise TypeError(f"{owner} returned {_described(result)}, expected a tuple (positions ({n}, 2) m, headings ({n},) rad)")
    positions = checked_array(result[0], owner, "positions", (n, 2), "(robots, xy) m")
    headings = None if result[1] is None else checked_array(result[1], owner, "headings", (n,), "(robots,) rad")
    return positions, headings


def checked_markers(task: Any, markers: list[Any]) -> tuple[list[str], np.ndarray]:
    """(sorted names, points (C, M, 2) m float64) of the markers ``markers`` that ``task.markers`` returned
    for C copies: each a dict of str names -> finite (2,) points, with the names of the task's first call
    (kept on the task)."""
    owner = f"{type(task).__name__}.markers()"
    expected = task.__dict__.get("_marker_names")
    for m in markers:
        if not isinstance(m, dict) or m.keys() != expected:
            _checked_keys(m, owner, "marker")
            if expected is None:
                expected = task._marker_names = frozenset(m)
            elif m.keys() != expected:
                raise ValueError(f"{owner}: marker names {_names(m)} differ from the first call's {_names(expected)}; return the same names every step")
    names = sorted(expected or ())
    if not names:
        return names, np.zeros((len(markers), 0, 2))
    values = [[m[k] for k in names] for m in markers]
    shape = (len(markers), len(names), 2)
    try:
        points = np.asarray(values)
        ok = points.dtype.kind in REAL_KINDS and points.shape == shape
    except (TypeError, ValueError):
        ok = False
    if ok and points.dtype != np.float64:
        points = points.astype(np.float64)
    if not ok or not np.isfinite(points).all():  # one point at a time: the error names the marker
        points = np.array([[checked_array(v, owner, f"marker {k!r}", (2,), "(xy) m") for k, v in zip(names, row)] for row in values])
    return names, points


def checked_robot_groups(task: Any, groups: Any) -> tuple[np.ndarray, tuple[str, str]] | None:
    """``task.robot_groups()``'s return checked: None, or ((n_world,) 0/1 groups, (label 0, label 1))."""
    if groups is None:
        return None
    owner = f"{type(task).__name__}.robot_groups()"
    n = int(task.n_world)
    if not isinstance(groups, (tuple, list)) or len(groups) != 2:
        raise TypeError(f"{owner} returned {_described(groups)}, expected None or a tuple (({n},) groups 0 or 1, (label 0, label 1))")
    which = checked_array(groups[0], owner, "groups", (n,), "(robots,)")
    other = np.unique(which[~np.isin(which, (0, 1))])
    if len(other):
        raise ValueError(f"{owner}: groups hold {', '.join(f'{v:g}' for v in other[:5])}, expected 0 or 1 per robot")
    labels = groups[1]
    if not isinstance(labels, (tuple, list)) or len(labels) != 2 or not all(isinstance(s, str) for s in labels):
        raise TypeError(f"{owner}: labels are {_described(labels)}, expected two str legend labels")
    return which.astype(np.int64), (labels[0], labels[1])


def checked_mask(task: Any, hook: str, value: Any, shape: tuple[int, ...], axes: str) -> np.ndarray:
    """A bool array of ``shape`` returned by ``task.{hook}()``: ``TypeError`` for another dtype, ``ValueError``
    for another shape."""
    owner = f"{type(task).__name__}.{hook}()"
    expected = f"expected a {shape} bool array {axes} or None"
    arr = value
    if type(arr) is not np.ndarray:
        try:
            arr = np.asarray(value)
        except (TypeError, ValueError):
            raise TypeError(f"{owner} returned {_described(value)}, {expected}") from None
    if arr.dtype != bool:
        raise TypeError(f"{owner} returned {_described(arr)}, {expected}")
    if arr.shape != shape:
        raise ValueError(f"{owner} returned {_described(arr)}, {expected}")
    return arr


def checked_count(task: Any, hook: str, value: Any, high: int) -> int:
    """An integer in [0, high] returned by ``task.{hook}()``."""
    message = f"{type(task).__name__}.{hook}() returned {_described(value)}, expected an int in [0, {high}]"
    if not isinstance(value, numbers.Integral) or isinstance(value, (bool, np.bool_)):
        raise TypeError(message)
    if not 0 <= value <= high:
        raise ValueError(message)
    return int(value)


def checked_length(task: Any, hook: str, value: Any) -> float:
    """A finite length (m) > 0 returned by ``task.{hook}()``."""
    message = f"{type(task).__name__}.{hook}() returned {_described(value)}, expected a finite number of metres > 0"
    if not isinstance(value, numbers.Real) or isinstance(value, (bool, np.bool_)):
        raise TypeError(message)
    if not (np.isfinite(value) and value > 0):
        raise ValueError(message)
    return float(value)


def check_declarations(cls: type, owner: str) -> None:
    """``TypeError`` naming ``owner`` (the class) and the attribute for a malformed ``SETTINGS``, ``METRICS``,
    ``HEADLINE`` or ``SCRIPTED_POLICY`` of the task class ``cls``."""
    settings = cls.__dict__.get("SETTINGS", {})
    if not isinstance(settings, Mapping):
        raise TypeError(
            f"{owner}.SETTINGS must be a dict {{name: Int(...) | Real(...) | Choice(...) | Flag(...) or a common setting's default}}, "
            f"got {_described(settings)}"
        )
    metrics = cls.METRICS
    if not isinstance(metrics, Mapping):
        raise TypeError(f"{owner}.METRICS must be a dict {{metric name: \"final\" or \"mean\"}}, got {_described(metrics)}")
    for name, how in metrics.items():
        if not isinstance(name, str) or not name:
            raise TypeError(f"{owner}.METRICS: metric names must be non-empty str, got {_one_line(shown(name, 60))}")
        if not isinstance(how, str) or how not in REDUCTIONS:
            raise TypeError(f"{owner}.METRICS: reductions must be one of {REDUCTIONS}, got {name!r}: {_one_line(shown(how, 60))}")
    headline = cls.HEADLINE
    if headline is not None:
        form = f"{owner}.HEADLINE must be None or (a metric of METRICS, +1 or -1)"
        if not isinstance(headline, (tuple, list)) or len(headline) != 2:
            raise TypeError(f"{form}, got {_described(headline)}")
        name, sign = headline
        if not isinstance(name, str) or name not in metrics:
            raise TypeError(f"{form}, got {_one_line(shown(headline, 80))}: {_one_line(shown(name, 40))} is not in METRICS {_names(metrics)}")
        if not isinstance(sign, numbers.Real) or isinstance(sign, (bool, np.bool_)) or sign not in (1, -1):
            raise TypeError(f"{form}, got {_one_line(shown(headline, 80))}: the sign is not +1 or -1")
    scripted = cls.SCRIPTED_POLICY
    if scripted is not None and (not isinstance(scripted, str) or not all(scripted.partition(":")[::2])):
        raise TypeError(f"{owner}.SCRIPTED_POLICY must be None or \"module:Class\" of a scripted baseline, got {_described(scripted)}")
