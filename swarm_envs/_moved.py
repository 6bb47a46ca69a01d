"""The old import paths of modules that moved into subpackages, served without a file per path.

The six task modules stay public at the package root (PettingZoo's ``from swarm_envs import aggregation_v0``):
``swarm_envs.<task>_v0`` is the module in :mod:`swarm_envs.tasks`, silently. Every other old path in
``DEPRECATED`` imports its new module with one ``DeprecationWarning``; these paths are removed in 0.3.0.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
import warnings
from types import ModuleType

#: old module (under ``swarm_envs``) -> its module now: the public task aliases
ALIASES: dict[str, str] = {'aggregation_v0': 'tasks.aggregation_v0', 'flocking_v0': 'tasks.flocking_v0', 'centroid_seeking_v0': 'tasks.centroid_seeking_v0', 'sorted_following_v0': 'tasks.sorted_following_v0', 'parity_clustering_v0': 'tasks.parity_clustering_v0', 'mid_angle_navigation_v0': 'tasks.mid_angle_navigation_v0'}
#: old module -> its module now: deprecated paths, removed in 0.3.0
DEPRECATED: dict[str, str] = {'world': 'sim.world', 'platforms': 'sim.platforms', 'geometry': 'sim.geometry', 'copies': 'sim.copies', 'observation': 'sensing.observation', 'task': 'tasks.task', 'settings': 'tasks.settings', 'metrics': 'tasks.metrics', 'factories': 'tasks.factories', 'views': 'adapters.views', 'render': 'adapters.render', 'env': 'adapters.env', 'vector': 'adapters.vector', 'torchrl_env': 'adapters.torchrl_env', 'benchmarl_tasks': 'adapters.benchmarl_tasks', 'torch_threads': 'adapters.torch_threads', 'reference': '_compile.reference'}
#: deprecated old module -> the modules its names were split into besides its new path: the old path offers
#: the names of all of them (``from swarm_envs.world import Arena`` still works)
SPLIT: dict[str, tuple[str, ...]] = {
    "world": ("sim.arena", "sim.spawning", "sim.control", "sim.motion"),
    "vector": ("adapters.memory",),
}
REMOVAL_VERSION = "0.3.0"


def _union_module(name: str, parts: list[ModuleType]) -> ModuleType:
    """A module ``name`` whose attributes are those of ``parts`` (the first that has the name wins)."""
    union = ModuleType(name, parts[0].__doc__)

    def __getattr__(attr: str):
        for part in parts:
            if hasattr(part, attr):
                return getattr(part, attr)
        raise AttributeError(f"module {name!r} has no attribute {attr!r}")

    union.__getattr__ = __getattr__  # type: ignore[method-assign]
    union.__all__ = [n for part in parts for n in getattr(part, "__all__", ())]
    return union


class _OldPathFinder(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Imports ``swarm_envs.<old>`` as the moved module itself (the same object, so classes and pickles agree)."""

    def __init__(self) -> None:
        self._specs: dict[str, object] = {}

    def find_spec(self, fullname: str, path=None, target=None):
        old = fullname.removeprefix("swarm_envs.")
        if fullname.startswith("swarm_envs.") and (old in ALIASES or old in DEPRECATED):
            return importlib.util.spec_from_loader(fullname, self)
        return None

    def create_module(self, spec) -> ModuleType:
        old = spec.name.removeprefix("swarm_envs.")
        new = ALIASES.get(old) or DEPRECATED[old]
        if old in DEPRECATED:
            warnings.warn(f"swarm_envs.{old} moved to swarm_envs.{new}; the old path is removed in 0.3.0",
                          DeprecationWarning, stacklevel=2)
        module = importlib.import_module(f"swarm_envs.{new}")
        if old in SPLIT:  # the module and the ones split off it, under the old name
            return _union_module(spec.name, [module] + [importlib.import_module(f"swarm_envs.{m}") for m in SPLIT[old]])
        self._specs[module.__name__] = module.__spec__  # the import system sets __spec__ to the old path's
        return module

    def exec_module(self, module: ModuleType) -> None:
        """Nothing to run (the moved module is already imported): give the module back its own spec."""
        if module.__name__ in self._specs:
            module.__spec__ = self._specs[module.__name__]


if not any(isinstance(finder, _OldPathFinder) for finder in sys.meta_path):
    sys.meta_path.insert(0, _OldPathFinder())  # first: another finder (an editable install elsewhere) may not see these as moved
