"""The old import paths of the modules that moved into sim/, tasks/, adapters/, _compile/ and sensing/: the
six task modules are public aliases (the same module object, no warning); every other old path imports the
moved module and raises one DeprecationWarning naming the new path."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
ALIASES = {'aggregation_v0': 'tasks.aggregation_v0', 'flocking_v0': 'tasks.flocking_v0', 'centroid_seeking_v0': 'tasks.centroid_seeking_v0', 'sorted_following_v0': 'tasks.sorted_following_v0', 'parity_clustering_v0': 'tasks.parity_clustering_v0', 'mid_angle_navigation_v0': 'tasks.mid_angle_navigation_v0'}
DEPRECATED = {'world': 'sim.world', 'platforms': 'sim.platforms', 'geometry': 'sim.geometry', 'copies': 'sim.copies', 'observation': 'sensing.observation', 'task': 'tasks.task', 'settings': 'tasks.settings', 'metrics': 'tasks.metrics', 'factories': 'tasks.factories', 'views': 'adapters.views', 'render': 'adapters.render', 'env': 'adapters.env', 'vector': 'adapters.vector', 'torchrl_env': 'adapters.torchrl_env', 'benchmarl_tasks': 'adapters.benchmarl_tasks', 'torch_threads': 'adapters.torch_threads', 'reference': '_compile.reference'}

PROBE = """
import importlib, json, sys, warnings
import swarm_envs
from swarm_envs._moved import SPLIT
out = {}
for old, new in json.loads(sys.argv[1]).items():
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        try:
            module = importlib.import_module("swarm_envs." + old)
        except ModuleNotFoundError as error:  # an optional extra (torchrl, benchmarl) not installed
            if (error.name or "").startswith("swarm_envs"):
                raise
            continue
        again = importlib.import_module("swarm_envs." + old)
    parts = [importlib.import_module("swarm_envs." + m) for m in [new, *SPLIT.get(old, ())]]
    # the moved module itself, or (a module split in several) one offering every public name of the parts
    same = module is parts[0] or all(getattr(module, n) is getattr(p, n) for p in parts for n in p.__all__)
    out[old] = [same, again is module, [str(w.message) for w in caught if issubclass(w.category, DeprecationWarning)]]
print(json.dumps(out))
"""


def _probe(mapping: dict[str, str]) -> dict[str, list]:
    result = subprocess.run([sys.executable, "-c", PROBE, json.dumps(mapping)], cwd=ROOT, capture_output=True, text=True,
                            timeout=300, env={"PYTHONPATH": str(ROOT), "PATH": ""})
    assert result.returncode == 0, result.stderr[-3000:]
    return json.loads(result.stdout.strip().splitlines()[-1])


def test_task_modules_are_silent_aliases():
    found = _probe(ALIASES)
    assert set(found) == set(ALIASES)
    for old, (same, again, warned) in found.items():
        assert same and again, old
        assert warned == [], (old, warned)


def test_old_paths_warn_once_and_resolve():
    found = _probe(DEPRECATED)
    assert set(DEPRECATED) - set(found) <= {"torchrl_env", "benchmarl_tasks"}  # these need their extras
    for old, (same, again, warned) in found.items():
        assert same and again, old
        assert len(warned) == 1 and f"swarm_envs.{DEPRECATED[old]}" in warned[0], (old, warned)


def test_names_of_a_split_module_stay_importable_from_its_old_path():
    code = ("import warnings; warnings.simplefilter('ignore');"
            "from swarm_envs.world import Arena, World, DT, spawn_positions, motion_error, motor_limits;"
            "from swarm_envs.sim.arena import Arena as A; from swarm_envs.sim.spawning import spawn_positions as s;"
            "from swarm_envs.vector import SwarmVectorEnv, copy_memory; from swarm_envs.adapters.memory import copy_memory as c;"
            "assert Arena is A and spawn_positions is s and copy_memory is c; print('ok')")
    result = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=300, env={"PYTHONPATH": str(ROOT), "PATH": ""})
    assert result.stdout.strip() == "ok", result.stderr[-2000:]
