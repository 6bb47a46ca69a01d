"""The physics sub-step count (``physics_substeps``): overlaps, wall penetration, cost and accuracy.

Part 1, the worst case of the defaults: for each platform at its default sub-steps (``physics_substeps=None``,
:func:`swarm_envs.sim.control.default_substeps`), at 8 and at its minimum, the deepest robot-robot overlap and
the deepest reach past a wall (the real wall polygon), in % of the diameter, over many seeds and 10 s
scenes: everyone at full speed towards the centre (a crush) or towards the nearest wall, at the default
density (``arena_size=None``: the platform's spacing x sqrt(N)) with 10, 30 and 100 robots, and dense
(40 and 100 robots covering 35 % and 50 % of the arena). Part 2, the cost: ms per control step of random
commands at the default density, N = 10 and 1000, default sub-steps against 8 (same run).

Part 3, accuracy against a 32-sub-step reference (e-puck and Droplet crushes, random commands):

For each scene the same seeded commands drive worlds with 1, 2, 4, 8 and 16 pymunk sub-steps per 0.1 s
control step and a 32-sub-step reference; printed per sub-step count: the position error against the
reference after 1, 10 and 50 control steps (median and max over robots, mm; contact scenes are chaotic,
so compare with the 16-sub-step row, whose error is the floor any count can reach), the deepest
robot-robot and robot-wall penetration seen (mm), the fraction of robots bumping per step, and the time
per control step. Scenes: a full-speed crush towards the centre (dense contacts), random
flocking commands at the default density (occasional contacts), and a free robot on an arc (no
contacts; its end point is analytic).

    python benchmarks/physics_substeps.py [--seeds 10] [--part worst,cost,accuracy]
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from scipy.spatial import cKDTree

from swarm_envs.sim.platforms import PLATFORMS
from swarm_envs.tasks.task import SPACING
from swarm_envs.sim.world import World, wrap_angle
from swarm_envs.sim.control import default_substeps, min_substeps
from swarm_envs.sim.spawning import spawn_positions
from swarm_envs.sim.arena import Arena

STEPS = 50
COUNTS = (1, 2, 4, 8, 16)
REFERENCE = 32


def commands(kind: str, world: World, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    p, n = world.platform, world.n
    if kind == "crush":
        to_centre = np.arctan2(-world.positions[:, 1], -world.positions[:, 0]) - world.headings
        return np.full(n, p.max_speed), 3 * wrap_angle(to_centre)
    return rng.uniform(-1, 1, n) * p.max_speed, rng.uniform(-1, 1, n) * p.max_angular_speed


def penetration(world: World) -> tuple[float, float]:
    """Deepest robot-robot overlap and robot-wall overlap now (m, >= 0)."""
    p, pos = world.platform, world.positions
    d = np.linalg.norm(pos[:, None] - pos[None], axis=-1)
    d[np.diag_indices(world.n)] = np.inf
    robot = max(0.0, 2 * p.radius - d.min())
    half = world.arena.half
    if world.arena.shape == "square":
        wall = max(0.0, float((np.abs(pos) + p.radius - half).max()))
    else:
        wall = max(0.0, float((np.linalg.norm(pos, axis=1) + p.radius - half).max()))
    return robot, wall


def scene(name: str, platform: str, n: int, arena: Arena, seed: int) -> None:
    p = PLATFORMS[platform]
    rng = np.random.default_rng(seed)
    pos = spawn_positions(rng, n, p.radius, arena)
    head = rng.uniform(-np.pi, np.pi, n)
    kind = "crush" if name.startswith("crush") else "random"
    worlds = {k: World(p, n, arena, substeps=k) for k in COUNTS + (REFERENCE,)}
    for w in worlds.values():
        w.place(pos, head)
    ref = worlds[REFERENCE]
    errs = {k: {} for k in COUNTS}
    pen = {k: [0.0, 0.0] for k in worlds}
    bumped = {k: 0.0 for k in worlds}
    cost = {k: 0.0 for k in worlds}
    for step in range(1, STEPS + 1):
        lin, ang = commands(kind, ref, rng)  # every world gets the reference's commands
        for k, w in worlds.items():
            t0 = time.perf_counter()
            w.step(lin, ang, 0.1)
            cost[k] += time.perf_counter() - t0
            r, wl = penetration(w)
            pen[k] = [max(pen[k][0], r), max(pen[k][1], wl)]
            bumped[k] += w.bumps.any(axis=1).mean() / STEPS
        if step in (1, 10, STEPS):
            for k in COUNTS:
                errs[k][step] = np.linalg.norm(worlds[k].positions - ref.positions, axis=1)
    print(f"\n### {name}: {n} {platform} robots, {arena.shape} arena {arena.size:.2f} m, {STEPS} steps of 0.1 s")
    print(
        f"reference ({REFERENCE} sub-steps): deepest overlap robot-robot {pen[REFERENCE][0] * 1e3:.3f} mm, "
        f"robot-wall {pen[REFERENCE][1] * 1e3:.3f} mm; robots bumping per step {bumped[REFERENCE]:.3f}; {cost[REFERENCE] / STEPS * 1e3:.2f} ms / step"
    )
    print(
        "| sub-steps | pos. error after 1 step, median / max (mm) | after 10 steps | after 50 steps | "
        "deepest overlap robot / wall (mm) | robots bumping per step | ms / step |"
    )
    print("|---|---|---|---|---|---|---|")
    for k in COUNTS:
        e = errs[k]
        cols = " | ".join(f"{np.median(e[s]) * 1e3:.3g} / {e[s].max() * 1e3:.3g}" for s in (1, 10, STEPS))
        print(f"| {k} | {cols} | {pen[k][0] * 1e3:.3f} / {pen[k][1] * 1e3:.3f} | {bumped[k]:.3f} | {cost[k] / STEPS * 1e3:.2f} |")


def free_arc() -> None:
    print("\n### free robot on an arc (analytic end point), e-puck, v = 0.5 max, w = 0.3 max, 1 s")
    print("| sub-steps | end-point error (m) |")
    print("|---|---|")
    p = PLATFORMS["epuck"]
    for k in COUNTS + (REFERENCE,):
        w = World(p, 1, Arena("square", 4.0), substeps=k)
        w.place(np.array([[0.1, -0.2]]), np.array([0.7]))
        v, om = (x.item() for x in w.wheel_limited(np.array([0.5 * p.max_speed]), np.array([0.3 * p.max_angular_speed])))
        for _ in range(10):
            w.step(np.array([v]), np.array([om]), 0.1)
        expected = np.array([0.1, -0.2]) + v / om * np.array([np.sin(0.7 + om) - np.sin(0.7), -np.cos(0.7 + om) + np.cos(0.7)])
        print(f"| {k} | {np.linalg.norm(w.positions[0] - expected):.2e} |")


def heading_commands(kind: str, world: World) -> tuple[np.ndarray, np.ndarray]:
    """Full speed towards the centre (``crush``) or the nearest wall (``wall``), turning towards it."""
    p, pos = world.platform, world.positions
    if kind == "crush":
        target = np.arctan2(-pos[:, 1], -pos[:, 0])
    elif world.arena.shape == "square":
        axis = np.abs(pos).argmax(axis=1)
        sign = np.sign(pos[np.arange(len(pos)), axis])
        target = np.where(axis == 0, np.where(sign > 0, 0.0, np.pi), sign * np.pi / 2)
    else:
        target = np.arctan2(pos[:, 1], pos[:, 0])
    err = wrap_angle(target - world.headings)
    return np.where(np.abs(err) < 0.5, p.max_speed, 0.3 * p.max_speed), 5 * err


def deepest(world: World) -> tuple[float, float]:
    """Deepest robot-robot overlap and reach past the wall polygon now (m, >= 0)."""
    p, pos = world.platform, world.positions
    d, _ = cKDTree(pos).query(pos, k=2)
    return max(0.0, p.diameter - d[:, 1].min()), max(0.0, float(world.arena.wall_depth(pos, p.radius).max()))


WORST_SCENES = [  # (kind, shape, robots, packing fraction or None for the default arena size)
    ("crush", "square", 10, None), ("wall", "square", 10, None), ("crush", "circle", 30, None), ("wall", "circle", 30, None),
    ("crush", "square", 100, None), ("crush", "square", 40, 0.35), ("wall", "square", 40, 0.35), ("crush", "circle", 40, 0.35),
    ("crush", "square", 100, 0.5),
]


def worst_case(seeds: int, steps: int = 100) -> None:
    print(f"\n### Worst overlap / wall reach (% of the diameter) over {seeds} seeds x {steps} steps of 0.1 s; ms per step")
    print("| platform | sub-steps | " + " | ".join(f"{k} {sh} {n} {'default' if f is None else f'{f:.0%}'}" for k, sh, n, f in WORST_SCENES) + " |")
    print("|---|---|" + "---|" * len(WORST_SCENES))
    for name, p in PLATFORMS.items():
        for substeps in sorted({default_substeps(p), 8, min_substeps(p)}, reverse=True):
            cells = []
            for kind, shape, n, fraction in WORST_SCENES:
                if fraction is None:
                    size = SPACING[name] * np.sqrt(n)
                else:
                    size = np.sqrt(n * np.pi * p.radius**2 / fraction) * (1.0 if shape == "square" else 2 / np.sqrt(np.pi))
                arena = Arena(shape, size)
                robot = wall = cost = 0.0
                for seed in range(seeds):
                    rng = np.random.default_rng(seed)
                    world = World(p, n, arena, substeps=substeps)
                    world.place(spawn_positions(rng, n, p.radius, arena), rng.uniform(-np.pi, np.pi, n))
                    for _ in range(steps):
                        lin, ang = heading_commands(kind, world)
                        t0 = time.perf_counter()
                        world.step(lin, ang, 0.1)
                        cost += time.perf_counter() - t0
                        r, w = deepest(world)
                        robot, wall = max(robot, r), max(wall, w)
                cells.append(f"{robot / p.diameter:.2%} / {wall / p.diameter:.2%} ({cost / (seeds * steps) * 1e3:.1f})")
            label = f"{substeps} (default)" if substeps == default_substeps(p) else str(substeps)
            print(f"| {name} | {label} | " + " | ".join(cells) + " |", flush=True)


def cost(repeats: int = 5) -> None:
    print(f"\n### Cost: ms per control step, random commands at the default density (median of {repeats} runs)")
    print("| platform | N | 8 sub-steps | default sub-steps | ratio |")
    print("|---|---|---|---|---|")
    for name, p in PLATFORMS.items():
        for n in (10, 1000):
            arena = Arena("square", SPACING[name] * np.sqrt(n))
            steps = 30 if n < 100 else 10
            times = {}
            for substeps in (8, default_substeps(p)):
                rng = np.random.default_rng(0)
                world = World(p, n, arena, substeps=substeps)
                world.place(spawn_positions(rng, n, p.radius, arena), rng.uniform(-np.pi, np.pi, n))
                cmds = [(rng.uniform(-1, 1, n) * p.max_speed, rng.uniform(-1, 1, n) * p.max_angular_speed) for _ in range(steps)]
                runs = []
                for _ in range(repeats):
                    t0 = time.perf_counter()
                    for lin, ang in cmds:
                        world.step(lin, ang, 0.1)
                    runs.append((time.perf_counter() - t0) / steps * 1e3)
                times[substeps] = float(np.median(runs))
            d = default_substeps(p)
            print(f"| {name} | {n} | {times[8]:.2f} | {times[d]:.2f} ({d}) | {times[d] / times[8]:.2f} |", flush=True)


def accuracy() -> None:
    free_arc()
    scene("crush", "epuck", 40, Arena("square", 0.8), 1)
    scene("crush (droplet)", "droplet", 40, Arena("square", 0.5), 2)
    size = SPACING["epuck"] * np.sqrt(10)
    scene("random commands, flocking density", "epuck", 10, Arena("square", size), 3)
    scene("random commands, dense", "epuck", 40, Arena("square", 0.9), 4)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--seeds", type=int, default=10, help="seeds per worst-case scene (default 10)")
    parser.add_argument("--part", default="worst,cost,accuracy", help="comma-separated parts to run")
    args = parser.parse_args()
    parts = args.part.split(",")
    if "worst" in parts:
        worst_case(args.seeds)
    if "cost" in parts:
        cost()
    if "accuracy" in parts:
        accuracy()


if __name__ == "__main__":
    main()
