"""The PettingZoo entry points of a task module, made from its task: :func:`task_module`.

A versioned task module (``swarm_envs/tasks/aggregation_v0.py``) is its :class:`swarm_envs.tasks.task.Task` subclass, the
prose of its documentation, and one line::

    raw_env, parallel_env, env = task_module(AggregationTask, DOC)

``parallel_env`` gets a keyword-only signature with the task's real defaults and type hints (built from its
settings, so ``help()`` and IDEs show them) and a docstring whose ``## Arguments`` table is generated from
the same :class:`swarm_envs.tasks.settings.Setting` objects; nothing is written twice.
"""

from __future__ import annotations

import inspect
import re
from collections.abc import Callable, Mapping
from typing import Any

from pettingzoo import AECEnv
from pettingzoo.utils.conversions import parallel_to_aec

from swarm_envs.adapters.env import SwarmEnv
from swarm_envs.tasks.settings import ordered_settings
from swarm_envs.tasks.settings_tables import arguments_table
from swarm_envs.tasks.task import DT, Task

__all__ = ["task_module", "env_class", "parallel_env_doc", "spaces_doc", "SECTIONS"]

_ACTION_SPACE = """## Action Space

Per agent ``Box(-1, 1, (2 + message_bits,), float32)``: linear and angular velocity as fractions of
the platform's maxima (``Platform.max_speed`` m/s and ``Platform.max_angular_speed`` rad/s; the
wheel speeds are then limited to ``max_speed`` and carry the platform's motion error, ``motion_noise``),
followed by ``message_bits`` payload bits (each entry above 0 is a 1-bit),
broadcast over SwarmCom whenever the robot's transmit queue is empty.
Finite values outside [-1, 1] are clipped; NaN/inf, wrong shapes and actions for unknown or missing
agents raise. Zero actions keep a robot still{still}.
"""

_OBSERVATION_SPACE = """## Observation Space

Per agent a ``Dict`` of ``float32`` boxes, built only from the modelled infrared sensing stack
(never from ground truth), with K = ``n_neighbours``, M = ``n_messages``, b = ``message_bits``:

| key | shape | columns |
|---|---|---|
| ``range_bearing`` | (K, 7) | valid, range (m), cos bearing, sin bearing, cos heading, sin heading, age (steps) [F14]{sectors} |
| ``messages`` | (M, 2 + b) | valid, sender bearing / pi, {payload}: SwarmCom messages decoded since the last step [T20] |
| ``scale_free`` | (K, 3) | valid, x, y of neighbours in the robot's frame, mean neighbour distance 1, clipped to +-10 [L] |
| ``rigid`` | (1,) | 1 when the scale-free coordinates are determined [L Sec. 5.5.1] |
| ``proprio`` | (8 + 2 + b,) | bump flags of 8 45-degree sectors (sector 0 ahead, counter-clockwise), last action |
{id_rows}
Rows are sorted nearest first by *estimated* range; empty rows are all zero. {ids}
``flatten=True`` gives one ``Box`` instead (keys in sorted order; ``env.layout.unflatten(flat)`` gives
the parts back).
"""

#: the sections of a ``parallel_env`` docstring, in order (Gymnasium's environment pages)
SECTIONS = ("Description", "Action Space", "Observation Space", "Rewards", "Starting State", "Episode End", "Arguments", "Version History")

_DEFAULT_START = """Robots are placed uniformly at random in the arena without overlap (random sequential placement with
a gap of 0.1 radius). Headings are uniform in [-pi, pi). ``reset(seed=..., options={"positions": (N, 2) m, "headings": (N,)
rad})`` places the robots exactly instead; overlapping or out-of-arena placements raise. All
randomness flows from the seed through independent child streams."""

_DEFAULT_END = """No termination. Truncation: every agent is truncated after ``max_cycles`` steps (default {cycles} = {seconds} s);
``env.agents`` is then empty."""

_ID_ROWS = """| ``own_id`` | (2,) | own id / (N - 1), own id parity (``observe_ids``) |
| ``range_bearing_ids``, ``scale_free_ids`` | (K, 4) | per row: an id was decoded, decoded id / (N - 1), id < own id, same parity |
| ``message_ids`` | (M, 4) | the same per message row (the header's decoded origin) |
"""
_IDS_ON = """The ids are those the
sensing decoded (a corrupted frame names the wrong robot); ``observe_ids=False`` drops the id parts."""
_IDS_OFF = """``observe_ids=True`` adds
``own_id`` (2,) and, per row of ``range_bearing``, ``messages`` and ``scale_free``, the id the sensing
decoded (``range_bearing_ids``, ``message_ids``, ``scale_free_ids``; see ``docs/observations.md``)."""


def spaces_doc(task: type[Task], payload: str = "payload bits") -> str:
    """The ``## Action Space`` and ``## Observation Space`` sections of a task's ``parallel_env`` docstring,
    from its defaults: the id parts when ``observe_ids`` is on by default, the r-one's sector bearings when it
    is the default platform, and a note on switched-off robots when the task switches robots off. ``payload``
    describes the payload bits of a ``messages`` row."""
    defaults = {key: setting.default for key, setting in ordered_settings(task.settings()).items()}
    switches_off = task.switched_off is not Task.switched_off
    still = ", also with the motion error (a switched-off robot ignores its actions)" if switches_off else " (also with the motion error)"
    observe_ids = defaults["observe_ids"]
    observation = _OBSERVATION_SPACE.format(
        sectors=" (r-one: sector bearings, range 0)" if defaults["platform"] == "rone" else "",
        payload=payload,
        id_rows=_ID_ROWS if observe_ids else "",
        ids=_IDS_ON if observe_ids else _IDS_OFF,
    )
    return _ACTION_SPACE.format(still=still) + "\n" + observation


def env_class(task: type[Task], members: Mapping[str, Any] | None = None) -> type[SwarmEnv]:
    """The env class (PettingZoo's ``raw_env``) of ``task``: a :class:`SwarmEnv` subclass named after it
    (``AggregationTask`` -> ``AggregationEnv``) in the task's module, with ``metadata["name"]`` the module's
    name and the extra ``members`` (e.g. a property). Its instances are made with the settings as keyword
    arguments."""
    module = task.__module__
    name = task.__name__.removesuffix("Task") + "Env"
    short = module.rsplit(".", 1)[-1]
    cls = type(name, (SwarmEnv,), {
        "__module__": module,
        "__qualname__": name,
        "__doc__": f"The {short} env (PettingZoo ``raw_env``): ``{name}(**settings)``; see :func:`parallel_env` for the settings.",
        "metadata": {**SwarmEnv.metadata, "name": short},
        "TASK": task,
        **(members or {}),
    })
    return cls


def parallel_env_doc(task: type[Task], doc: str, payload: str = "payload bits") -> str:
    """The docstring of a task's ``parallel_env`` (:func:`task_module`): Gymnasium's sections in their order,
    ``## Description``, ``## Rewards`` and ``## Version History`` from ``doc``; ``## Action Space`` and ``##
    Observation Space`` generated (:func:`spaces_doc`); ``## Starting State`` and ``## Episode End`` from
    ``doc``, else the default spawn's and truncation's (for a task that keeps :meth:`Task.spawn`);
    ``## Arguments`` generated from the task's settings. ``ValueError`` for a missing or unknown section."""
    parts = re.split(r"^## (.+?)\s*$", inspect.cleandoc(doc), flags=re.M)
    summary, given = parts[0].strip(), dict(zip(parts[1::2], (body.strip() for body in parts[2::2])))
    settings = ordered_settings(task.settings())
    generated = {"Arguments": arguments_table(settings).split("\n", 1)[1].strip()}
    generated.update(dict(re.findall(r"^## (.+?)\n(.*?)(?=^## |\Z)", spaces_doc(task, payload), flags=re.M | re.S)))
    if task.spawn is Task.spawn:
        generated["Starting State"] = _DEFAULT_START
    cycles = settings["max_cycles"].default
    generated["Episode End"] = _DEFAULT_END.format(cycles=cycles, seconds=f"{cycles * DT:g}")
    unknown = sorted(set(given) - set(SECTIONS))
    missing = [name for name in SECTIONS if name not in given and name not in generated]
    if unknown or missing or not summary:
        raise ValueError(f"{task.__module__}: the parallel_env doc needs a summary line and the sections {SECTIONS}; "
                         f"unknown {unknown}, missing {missing}")
    body = "\n\n".join(f"## {name}\n\n{given.get(name, generated.get(name, '')).strip()}" for name in SECTIONS)
    return f"{summary}\n\n{body}\n"


def task_module(
    task: type[Task], doc: str, members: Mapping[str, Any] | None = None, payload: str = "payload bits"
) -> tuple[type[SwarmEnv], Callable[..., SwarmEnv], Callable[..., AECEnv]]:
    """``(raw_env, parallel_env, env)`` of a task module.

    Args:
        task: the task; its env class is made by :func:`env_class`.
        doc: the task's part of the docstring of ``parallel_env``: a summary line and Gymnasium's sections
            ``## Description``, ``## Rewards``, ``## Starting State``, ``## Episode End`` and ``## Version
            History``. The generated sections go in between: ``## Action Space`` and ``## Observation Space``
            (:func:`spaces_doc`) before ``## Rewards``, ``## Arguments`` (from the task's settings,
            :func:`swarm_envs.tasks.settings_tables.arguments_table`) before ``## Version History``.
        members: extra members of the env class (:func:`env_class`).
        payload: what the payload bits of a ``messages`` row carry (:func:`spaces_doc`).

    Returns:
        ``raw_env``: the env class; ``parallel_env(**settings)``: an env of it (a PettingZoo ``ParallelEnv``),
        keyword-only, with the settings' defaults and type hints in its signature and unknown names refused
        with a ``TypeError`` that lists the allowed ones; ``env(**settings)``: its AEC view
        (``parallel_to_aec``).
    """
    raw_env = env_class(task, members)
    settings = ordered_settings(raw_env.TASK.settings())
    defaults = {key: setting.default for key, setting in settings.items()}
    allowed = sorted(settings)
    module = raw_env.__module__

    def parallel_env(**kwargs: Any) -> SwarmEnv:
        unknown = sorted(set(kwargs) - set(allowed))
        if unknown:
            raise TypeError(f"{module}.parallel_env() got unknown keyword argument(s) {unknown}; allowed: {allowed}")
        return raw_env(**{**defaults, **kwargs})

    def env(**kwargs: Any) -> AECEnv:
        return parallel_to_aec(parallel_env(**kwargs))

    parallel_env.__doc__ = parallel_env_doc(task, doc, payload)
    parallel_env.__signature__ = inspect.Signature(  # type: ignore[attr-defined]
        [inspect.Parameter(key, inspect.Parameter.KEYWORD_ONLY, default=s.default, annotation=s.annotation()) for key, s in settings.items()],
        return_annotation=raw_env,
    )
    parallel_env.__annotations__ = {**{key: s.annotation() for key, s in settings.items()}, "return": raw_env}
    env.__doc__ = "The AEC (turn-based) view of :func:`parallel_env` (PettingZoo ``parallel_to_aec``); same keyword arguments."
    env.__signature__ = parallel_env.__signature__.replace(return_annotation=AECEnv)  # type: ignore[attr-defined]
    env.__annotations__ = {**parallel_env.__annotations__, "return": AECEnv}
    for function in (parallel_env, env):
        function.__module__ = module
        function.__qualname__ = function.__name__
    return raw_env, parallel_env, env
