"""Contacts under hostile driving, and the cost of the physics step.

Part 1 (``worst``): for each platform at its default sub-steps and default square arena, the deepest
robot-robot overlap and the deepest reach past a wall (% of the diameter, ground-truth positions) over
600 control steps of every robot at full speed towards the centre, towards one corner, towards its
nearest wall, and of head-on pairs pushing against each other, with 10, 30 and 100 robots and several
seeds (the scenes of ``tests/sim/test_contacts_hostile.py``, which asserts the documented bound on them).

Part 2 (``cost``): median wall-clock and process CPU ms per vector step of ``make_vec`` (Aggregation,
e-puck, 10 robots x 256 copies, random actions, sensing ``full`` and ``ideal``). With ``--against DIR``
(another checkout of the suite, e.g. the commit before a physics change) every round times DIR's code and
this tree's in turn, each in a fresh process, and prints the per-round ratios and their median, so both
sides of a ratio see the same machine load.

    python benchmarks/contacts_hostile.py [--part worst,cost] [--seeds 3] [--against DIR --rounds 5]
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path
from types import ModuleType

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def _hostile_module() -> ModuleType:
    """``tests/sim/test_contacts_hostile.py`` (the scenes and the measurement), loaded from its path."""
    spec = importlib.util.spec_from_file_location("contacts_hostile_scenes", ROOT / "tests" / "sim" / "test_contacts_hostile.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def worst(seeds: int, crowds: tuple[int, ...] = (10, 30, 100)) -> None:
    scenes = _hostile_module()
    from swarm_envs.sim.platforms import PLATFORMS
    from swarm_envs.sim.control import default_substeps

    print(f"\n### Deepest overlap / wall reach (% of the diameter) over {seeds} seeds x {scenes.STEPS} steps at full speed")
    print("| platform (sub-steps) | " + " | ".join(f"{s} {n}" for s in scenes.SCENES for n in crowds) + " | worst |")
    print("|---|" + "---|" * (len(scenes.SCENES) * len(crowds) + 1))
    for name, p in PLATFORMS.items():
        cells, top = [], [0.0, 0.0]
        for scene in scenes.SCENES:
            for n in crowds:
                runs = [scenes.hostile(name, scene, n, seed) for seed in range(seeds)]
                robot, wall = max(r for r, _ in runs), max(w for _, w in runs)
                top = [max(top[0], robot), max(top[1], wall)]
                cells.append(f"{robot:.2%} / {wall:.2%}")
        worst_mm = f"{top[0]:.2%} ({top[0] * p.diameter * 1e3:.1f} mm) / {top[1]:.2%} ({top[1] * p.diameter * 1e3:.1f} mm)"
        print(f"| {name} ({default_substeps(p)}) | " + " | ".join(cells) + f" | {worst_mm} |", flush=True)


def time_step(sensing: str, copies: int = 256, n: int = 10, steps: int = 30) -> tuple[float, float]:
    """Median (wall-clock, process CPU) ms per vector step of ``copies`` Aggregation copies of ``n`` e-pucks."""
    import swarm_envs

    vec = swarm_envs.make_vec("swarm_envs/Aggregation-v0", copies, n_robots=n, sensing=sensing, max_cycles=10**6)
    vec.reset(seed=0)
    rng = np.random.default_rng(0)
    shape = (copies, n, vec.layout.action_size)
    for _ in range(3):  # warm-up: kernels load, caches fill
        vec.step(rng.uniform(-1, 1, shape))
    wall, cpu = [], []
    for _ in range(steps):
        action = rng.uniform(-1, 1, shape)
        t0, c0 = time.perf_counter(), time.process_time()
        vec.step(action)
        wall.append(time.perf_counter() - t0)
        cpu.append(time.process_time() - c0)
    return statistics.median(wall) * 1e3, statistics.median(cpu) * 1e3


def cost(against: str | None, rounds: int) -> None:
    print("\n### ms per vector step, Aggregation e-puck, 10 robots x 256 copies, random actions (median of 30 steps)")
    if against is None:
        for sensing in ("full", "ideal"):
            wall, cpu = time_step(sensing)
            print(f"| {sensing} | wall {wall:.1f} | CPU {cpu:.1f} |", flush=True)
        return
    trees = {"against": str(Path(against).resolve()), "this": str(ROOT)}
    results: dict[tuple[str, str], list[tuple[float, float]]] = {}
    for r in range(rounds):
        for sensing in ("full", "ideal"):
            for label, tree in trees.items():
                env = dict(os.environ, PYTHONPATH=tree, OMP_NUM_THREADS="1")
                code = f"import json, sys; sys.path.insert(0, {str(ROOT / 'benchmarks')!r}); import contacts_hostile as c; print(json.dumps(c.time_step({sensing!r})))"
                out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True).stdout
                results.setdefault((sensing, label), []).append(tuple(json.loads(out.strip().splitlines()[-1])))
        line = ", ".join(
            f"{s}: CPU {results[s, 'this'][-1][1] / results[s, 'against'][-1][1]:.3f}" for s in ("full", "ideal")
        )
        print(f"round {r + 1}: this / against {line}", flush=True)
    print("| sensing | against: wall / CPU ms | this: wall / CPU ms | ratio of medians, wall / CPU | median of per-round CPU ratios |")
    print("|---|---|---|---|---|")
    for sensing in ("full", "ideal"):
        a, t = np.array(results[sensing, "against"]), np.array(results[sensing, "this"])
        ma, mt = np.median(a, axis=0), np.median(t, axis=0)
        per_round = np.median(t[:, 1] / a[:, 1])
        print(f"| {sensing} | {ma[0]:.1f} / {ma[1]:.1f} | {mt[0]:.1f} / {mt[1]:.1f} | {mt[0] / ma[0]:.3f} / {mt[1] / ma[1]:.3f} | {per_round:.3f} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--part", default="worst,cost", help="comma-separated parts to run (worst, cost)")
    parser.add_argument("--seeds", type=int, default=3, help="seeds per scene with random starts (default 3)")
    parser.add_argument("--against", default=None, help="another checkout whose step time this tree's is compared with")
    parser.add_argument("--rounds", type=int, default=5, help="alternating rounds of --against (default 5)")
    args = parser.parse_args()
    parts = args.part.split(",")
    if "worst" in parts:
        worst(args.seeds)
    if "cost" in parts:
        cost(args.against, args.rounds)


if __name__ == "__main__":
    main()
