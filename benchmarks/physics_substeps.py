"""Accuracy of the physics sub-step count (``physics_substeps``) against a 32-sub-step reference.

For each scene the same seeded commands drive worlds with 1, 2, 4, 8 and 16 pymunk sub-steps per 0.1 s
control step and a 32-sub-step reference; printed per sub-step count: the position error against the
reference after 1, 10 and 50 control steps (median and max over robots, mm; contact scenes are chaotic,
so compare with the 16-sub-step row, whose error is the floor any count can reach), the deepest
robot-robot and robot-wall penetration seen (mm), the fraction of robots bumping per step, and the time
per control step. Scenes: a full-speed crush towards the centre (dense contacts), random
flocking commands at the default density (occasional contacts), and a free robot on an arc (no
contacts; its end point is analytic).

    python benchmarks/physics_substeps.py
"""

from __future__ import annotations

import time

import numpy as np

from swarm_envs.platforms import PLATFORMS
from swarm_envs.task import SPACING
from swarm_envs.world import Arena, World, spawn_positions, wrap_angle

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


def main() -> None:
    free_arc()
    p = PLATFORMS["epuck"]
    scene("crush", "epuck", 40, Arena("square", 0.8), 1)
    scene("crush (droplet)", "droplet", 40, Arena("square", 0.5), 2)
    size = SPACING["epuck"] * np.sqrt(10)
    scene("random commands, flocking density", "epuck", 10, Arena("square", size), 3)
    scene("random commands, dense", "epuck", 40, Arena("square", 0.9), 4)
    del p


if __name__ == "__main__":
    main()
