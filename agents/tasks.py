"""What the trainers and evaluators know about a task: its env id, metric reductions, headline metric and
scripted baseline, read from the task class itself (``Task.METRICS``, ``HEADLINE``, ``SCRIPTED_POLICY``),
so a user's registered task works everywhere the suite's own do.

A task is named by a registered env id (``"swarm_envs/Flocking-v0"``, ``"my_lab/Spread-v0"``) or by one of
the suite's short names (``"flocking"``). :func:`import_modules` imports the modules that register a user's
tasks (module names such as ``my_lab.tasks`` or paths to ``.py`` files) before a task is looked up.
"""

from __future__ import annotations

import importlib
import sys
from pathlib import Path

from swarm_envs.registry import list_envs, spec, task_class

__all__ = ["SHORT_NAMES", "env_id", "metric_reductions", "headline", "scripted_policy", "import_modules", "import_task"]

#: the suite's short task names (accepted wherever a task is named)
SHORT_NAMES = {
    "aggregation": "swarm_envs/Aggregation-v0",
    "flocking": "swarm_envs/Flocking-v0",
    "centroid_seeking": "swarm_envs/CentroidSeeking-v0",
    "sorted_following": "swarm_envs/SortedFollowing-v0",
    "parity_clustering": "swarm_envs/ParityClustering-v0",
    "mid_angle_navigation": "swarm_envs/MidAngleNavigation-v0",
}


def env_id(task: str) -> str:
    """The registered env id of ``task`` (a short name or an id); ``ValueError`` naming the choices."""
    if not isinstance(task, str):
        raise ValueError(f"a task is named by a string (an env id or one of {sorted(SHORT_NAMES)}), got {task!r:.80}")
    name = SHORT_NAMES.get(task, task)
    try:
        spec(name)
    except ValueError:
        raise ValueError(
            f"unknown task {task!r}; use a registered env id ({', '.join(list_envs())}) or a short name "
            f"({', '.join(SHORT_NAMES)}); a task of your own needs the module that registers it imported first"
        ) from None
    return name


def metric_reductions(task: str) -> dict[str, str]:
    """``{metric: "final" | "mean"}`` of the task (``Task.METRICS``)."""
    return dict(task_class(env_id(task)).METRICS)


def headline(task: str) -> tuple[str, int] | None:
    """``(metric, +1 if higher is better else -1)`` of the task (``Task.HEADLINE``), or None."""
    return task_class(env_id(task)).HEADLINE


def scripted_policy(task: str) -> str | None:
    """The task's scripted baseline (``Task.SCRIPTED_POLICY``, ``"module:Class"``), or None."""
    return task_class(env_id(task)).SCRIPTED_POLICY


def import_modules(names: list[str]) -> None:
    """Import each module (``"my_lab.tasks"``, looked up from the current directory too) or Python file
    (``"path/to/tasks.py"``, imported as module ``tasks`` with its folder put on ``sys.path``) of ``names``,
    e.g. the modules that register a user's tasks. ``ImportError`` naming the module when one fails."""
    for name in names:
        if not isinstance(name, str) or not name:
            raise ImportError(f"a module to import is a module name or a .py path, got {name!r:.80}")
        module_name, folder = name, Path.cwd()
        if name.endswith(".py"):
            try:
                path = Path(name).resolve()
                if not path.is_file():
                    raise ImportError(f"cannot import {name!r}: no such file")
            except OSError as err:  # e.g. a name too long for the file system
                raise ImportError(f"cannot import {name!r}: {err.strerror or err}") from None
            module_name, folder = path.stem, path.parent
        if str(folder) not in sys.path:
            sys.path.insert(0, str(folder))
        try:
            importlib.import_module(module_name)
        except Exception as err:
            raise ImportError(f"cannot import {name!r}: {type(err).__name__}: {err}") from err


def import_task(imports: list[str], task: str) -> None:
    """Import ``imports`` (:func:`import_modules`, e.g. the module that registers a task of your own), then
    check that ``task`` is a registered env id: ``ImportError`` or ``ValueError`` with one line otherwise."""
    import_modules(imports)
    if task not in list_envs():
        raise ValueError(f"--task {task!r} is not a registered env id; registered: {list_envs()} (--import registers yours)")
