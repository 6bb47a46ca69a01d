"""The registry of environment ids: :func:`register`, :func:`spec`, :func:`list_envs`, :func:`task_class`.

An id names a task and, optionally, default settings, as in Gymnasium: ``"namespace/Name-vN"`` (the
namespace is optional, the version is not: any change that can alter results gets a new version). The
entry point is a :class:`swarm_envs.tasks.task.Task` subclass, a :class:`swarm_envs.adapters.env.SwarmEnv` subclass, or a
``"module:Class"`` string naming one, imported only when an env is made, so a package can register its
tasks on import without importing the task's module. Every id is registered in PettingZoo's registry too
(``pettingzoo.make("parallel", id)`` and ``pettingzoo.make("aec", id)``). :func:`make` and :func:`make_vec`
build envs of an id or a class (``swarm_envs.make`` and ``swarm_envs.make_vec`` are these).
"""

from __future__ import annotations

import difflib
import functools
import importlib
import re
import warnings
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np

from swarm_envs._text import shown
from swarm_envs.adapters.env import SwarmEnv
from swarm_envs.tasks.task import Task
from swarm_envs.adapters.batch import CoreBatch
from swarm_envs.adapters.vector import AgentsAsEnvs, SwarmVectorEnv

__all__ = ["EnvSpec", "register", "spec", "list_envs", "task_class", "resolve", "make", "make_vec", "ENV_IDS", "ID_PATTERN"]

#: ``[namespace/]Name-vN``, the whole string (``fullmatch``): a namespace of letters, digits, ``_``, ``.`` and
#: ``-`` that does not start with ``.`` (so never ``..``), one ``/``, and a versioned name of letters, digits,
#: ``_`` and ``.`` that starts with a letter or ``_``; no whitespace, control characters or other separators.
ID_PATTERN = re.compile(r"(?:[A-Za-z0-9_-][A-Za-z0-9_.-]*/)?[A-Za-z_][A-Za-z0-9_.]*-v(?:0|[1-9][0-9]*)")


@dataclass(frozen=True)
class EnvSpec:
    """A registered id.

    Attributes:
        id: the id, ``"[namespace/]Name-vN"``.
        entry_point: a ``Task`` subclass, a ``SwarmEnv`` subclass, or ``"module:Class"`` naming one.
        kwargs: default settings of the id (keyword arguments given at ``make`` override them).
    """

    id: str
    entry_point: Any
    kwargs: Mapping[str, Any] = field(default_factory=dict)

    def load(self) -> type:
        """The entry point as a class (imported on first use): a ``Task`` or ``SwarmEnv`` subclass."""
        target = self.entry_point
        if isinstance(target, str):
            module_name, _, attr = target.partition(":")
            try:
                module = importlib.import_module(module_name)
            except ImportError as err:
                raise ImportError(f"{self.id}: cannot import the entry point's module {module_name!r}: {err}") from err
            try:
                target = functools.reduce(getattr, attr.split("."), module)
            except AttributeError:
                raise ImportError(f"{self.id}: module {module_name!r} has no {attr!r} (entry point {self.entry_point!r})") from None
        _check_entry_class(target, self.id)
        return target


_REGISTRY: dict[str, EnvSpec] = {}

#: Read-only view of the registry: id -> :class:`EnvSpec`.
ENV_IDS: Mapping[str, EnvSpec] = MappingProxyType(_REGISTRY)


def _check_entry_class(target: Any, env_id: str) -> None:
    if not (isinstance(target, type) and issubclass(target, (Task, SwarmEnv))):
        raise TypeError(f"{env_id}: the entry point must be a swarm_envs.tasks.task.Task or swarm_envs.adapters.env.SwarmEnv subclass, got {target!r}")
    _check_concrete(target, f"{env_id}: the entry point")


def _check_concrete(target: type, what: str) -> None:
    """``TypeError`` for the abstract base ``Task`` itself (or a ``SwarmEnv`` class whose task it is): it has no
    rewards, so an env of it would only fail at its first reset."""
    if (target.TASK if issubclass(target, SwarmEnv) else target) is Task:
        base = "the abstract base class swarm_envs.Task"
        name = base if target is Task else f"{target.__qualname__}, whose TASK is {base}"
        raise TypeError(
            f"{what} is {name}: an env needs a subclass of swarm_envs.Task that implements its hooks (at least rewards(state, first))"
        )


def register(env_id: str, entry_point: type | str, *, kwargs: Mapping[str, Any] | None = None) -> EnvSpec:
    """Register ``env_id`` for ``entry_point`` (a ``Task`` subclass, a ``SwarmEnv`` subclass, or a
    ``"module:Class"`` string, imported lazily), with default settings ``kwargs``.

    Afterwards :func:`swarm_envs.make`, :func:`swarm_envs.make_vec`, ``pettingzoo.make`` and ``train.py``
    accept the id. Registering an id again with the same entry point and settings does nothing; with
    another one it replaces the old entry and warns (as Gymnasium does). Settings are checked when an env
    is made. Returns the :class:`EnvSpec`.
    """
    if not isinstance(env_id, str) or not ID_PATTERN.fullmatch(env_id):
        raise ValueError(
            "env id must look like 'namespace/Name-v0' (a versioned name, namespace optional; letters, digits, '_', '.' "
            f"and '-' in the namespace, not starting with '.'; no spaces or other separators), got {shown(env_id)}"
        )
    if isinstance(entry_point, str):
        if ":" not in entry_point or not all(entry_point.partition(":")[::2]):
            raise ValueError(f"a string entry point must be 'module:Class', got {entry_point!r}")
    else:
        _check_entry_class(entry_point, env_id)
    if kwargs is not None and not isinstance(kwargs, Mapping):
        raise TypeError(f"kwargs must be a dict of default settings, got {type(kwargs).__name__}")
    clash = next((other for other in _REGISTRY if other != env_id and other.lower() == env_id.lower()), None)
    if clash is not None:
        raise ValueError(f"env id {env_id!r} differs from the registered id {clash!r} only in letter case; use {clash!r} or another name")
    new = EnvSpec(env_id, entry_point, MappingProxyType(dict(kwargs or {})))
    old = _REGISTRY.get(env_id)
    if old is not None:
        if old.entry_point == new.entry_point and dict(old.kwargs) == dict(new.kwargs):
            return old
        warnings.warn(f"re-registering {env_id!r}: {old.entry_point!r} is replaced by {new.entry_point!r}", stacklevel=2)
    _REGISTRY[env_id] = new
    _register_in_pettingzoo(env_id)
    return new


def _register_in_pettingzoo(env_id: str) -> None:
    import pettingzoo

    with warnings.catch_warnings():  # PettingZoo warns on every re-registration; register() warned already
        warnings.simplefilter("ignore")
        pettingzoo.register("parallel", env_id, entry_point=functools.partial(_make_parallel, env_id))
        pettingzoo.register("aec", env_id, entry_point=functools.partial(_make_aec, env_id))


def _make_parallel(env_id: str, **kwargs: Any) -> SwarmEnv:
    return make(env_id, **kwargs)


def _make_aec(env_id: str, **kwargs: Any) -> Any:
    from pettingzoo.utils.conversions import parallel_to_aec

    return parallel_to_aec(make(env_id, **kwargs))


def spec(env_id: str) -> EnvSpec:
    """The :class:`EnvSpec` of a registered id; ``ValueError`` naming close matches for an unknown one."""
    try:
        return _REGISTRY[env_id]
    except (KeyError, TypeError):
        close = difflib.get_close_matches(str(env_id), list(_REGISTRY), n=3, cutoff=0.8)
        hint = f"; did you mean {close}?" if close else ""
        raise ValueError(
            f"unknown environment id {env_id!r}{hint} Registered: {list_envs()}. "
            "Register your own with swarm_envs.register(id, TaskClass) (import the module that does so first)."
        ) from None


def list_envs() -> list[str]:
    """Every registered id, in registration order (the suite's own first)."""
    return list(_REGISTRY)


def task_class(task: Any) -> type:
    """The ``Task`` subclass of ``task``: a registered id, a ``Task`` subclass, or a ``SwarmEnv`` subclass
    (its ``TASK``)."""
    if isinstance(task, str):
        task = spec(task).load()
    if isinstance(task, type) and issubclass(task, SwarmEnv):
        return task.TASK
    if isinstance(task, type) and issubclass(task, Task):
        return task
    raise TypeError(f"expected an env id, a swarm_envs.tasks.task.Task subclass or a SwarmEnv subclass, got {task!r:.80}")


def resolve(env: Any) -> tuple[type, dict[str, Any]]:
    """(entry class, default settings) of ``env``: a registered id (its loaded entry point and settings),
    or a ``Task`` / ``SwarmEnv`` subclass (itself, no settings)."""
    if isinstance(env, str):
        env_spec = spec(env)
        return env_spec.load(), dict(env_spec.kwargs)
    task_class(env)  # TypeError for anything else
    _check_concrete(env, "the env")
    return env, {}


def make(env: str | type, **kwargs: Any) -> SwarmEnv:
    """A PettingZoo ``ParallelEnv`` of a registered id (``make("swarm_envs/Aggregation-v0", n_robots=20)``),
    a ``Task`` subclass or a ``SwarmEnv`` subclass; keyword arguments override the id's default settings."""
    entry, defaults = resolve(env)
    settings = {**defaults, **kwargs}
    if issubclass(entry, SwarmEnv):
        return entry(**settings)
    return SwarmEnv(entry, **settings)


def make_vec(env: str | type, num_envs: int, *, agents_as_envs: bool = False, **kwargs: Any) -> SwarmVectorEnv | AgentsAsEnvs:
    """``num_envs`` copies of a registered id (or a ``Task`` / ``SwarmEnv`` subclass) stepped by one batched
    core: a Gymnasium ``VectorEnv`` with ``(num_envs, n_agents, ...)`` arrays (:mod:`swarm_envs.adapters.vector`).
    ``agents_as_envs=True``: every robot of every copy as one sub-env (``num_envs x n_agents`` rows,
    :class:`swarm_envs.adapters.vector.AgentsAsEnvs`), for Gymnasium's vector wrappers. ``SettingsError`` naming
    ``num_envs`` when the copies' estimated memory exceeds the machine's available memory."""
    if not isinstance(agents_as_envs, (bool, np.bool_)):
        raise TypeError(f"agents_as_envs must be True or False, got {agents_as_envs!r:.80}")
    entry, defaults = resolve(env)
    settings = {**defaults, **kwargs}
    return AgentsAsEnvs(CoreBatch(entry, num_envs, **settings)) if bool(agents_as_envs) else SwarmVectorEnv(entry, num_envs, **settings)
