"""Hostile driving at the default physics: robots driven at full speed into each other and into the walls
for 600 control steps overlap each other, and reach past a wall, by at most :data:`MAX_OVERLAP` of their
diameter on every platform (ground-truth positions, the platform's default sub-steps and arena size).

Scenes (:func:`hostile`): every robot at full speed towards the arena centre (``centre``), towards one
corner (``corner``: a pile pressed into two walls, the deepest case), towards its nearest wall (``walls``),
and ``pairs`` of robots placed head-on driving straight at each other and then pushing against each other.
``benchmarks/contacts_hostile.py`` prints the same measurement over more seeds and crowds."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial import cKDTree

from swarm_envs.sim.platforms import PLATFORMS
from swarm_envs.tasks.task import SPACING
from swarm_envs.sim.world import MAX_OVERLAP, World
from swarm_envs.sim.spawning import spawn_positions
from swarm_envs.sim.arena import Arena
from swarm_envs.sim.geometry import wrap_angle

SCENES = ("centre", "corner", "walls", "pairs")
STEPS = 600


def _pairs(world: World, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
    """Positions (n, 2) and headings (n,) of head-on pairs on a grid: the two robots of a pair face each other
    (alternately along x and along y) with a random gap of 0.5 to 1.5 diameters, so the pairs meet at
    different points of a sub-step; an odd last robot faces a wall."""
    p, n, half = world.platform, world.n, world.arena.half
    cells = int(np.ceil(np.sqrt((n + 1) // 2)))
    pitch = 2 * half / cells
    positions, headings = [], []
    for k in range((n + 1) // 2):
        centre = -half + pitch * (0.5 + np.array([k % cells, k // cells]))
        axis = np.array([1.0, 0.0]) if k % 2 == 0 else np.array([0.0, 1.0])
        angle = 0.0 if k % 2 == 0 else np.pi / 2
        offset = (p.radius + 0.5 * p.diameter * rng.uniform(0.5, 1.5)) * axis
        positions += [centre - offset, centre + offset]
        headings += [angle, angle + np.pi]
    return np.array(positions[:n]), np.array(headings[:n])


def _targets(world: World, scene: str) -> np.ndarray:
    """(n,) heading (rad) each robot drives towards in ``scene``."""
    pos = world.positions
    if scene == "centre":
        return np.arctan2(-pos[:, 1], -pos[:, 0])
    if scene == "corner":
        return np.full(world.n, np.pi / 4)
    if scene == "walls":
        axis = np.abs(pos).argmax(axis=1)
        sign = np.sign(pos[np.arange(world.n), axis])
        return np.where(axis == 0, np.where(sign > 0, 0.0, np.pi), sign * np.pi / 2)
    return world.headings  # pairs: straight ahead, never turning


def hostile(platform: str, scene: str, n: int, seed: int = 0, steps: int = STEPS) -> tuple[float, float]:
    """Deepest robot-robot overlap and deepest reach past a wall (fractions of the diameter, >= 0) over
    ``steps`` control steps of ``scene`` (:data:`SCENES`) with ``n`` robots of ``platform`` at full speed, at
    the platform's default sub-steps in its default square arena (``SPACING`` x sqrt(n))."""
    p = PLATFORMS[platform]
    arena = Arena("square", SPACING[platform] * np.sqrt(n))
    world = World(p, n, arena)  # substeps=None: the platform's default
    rng = np.random.default_rng(seed)
    if scene == "pairs":
        world.place(*_pairs(world, rng))
    else:
        world.place(spawn_positions(rng, n, p.radius, arena), rng.uniform(-np.pi, np.pi, n))
    robot = wall = 0.0
    for _ in range(steps):
        turn = np.clip(5.0 * wrap_angle(_targets(world, scene) - world.headings), -p.max_angular_speed, p.max_angular_speed)
        world.step(np.full(n, p.max_speed), turn, 0.1)  # full speed (the wheels limit it while turning)
        gaps, _ = cKDTree(world.positions).query(world.positions, k=2)
        robot = max(robot, p.diameter - float(gaps[:, 1].min()))
        wall = max(wall, float(arena.wall_depth(world.positions, p.radius).max()))
    return robot / p.diameter, wall / p.diameter


@pytest.mark.parametrize("platform", sorted(PLATFORMS))
@pytest.mark.parametrize("scene,n", [("corner", 100), ("centre", 10), ("walls", 10), ("pairs", 10)])
def test_full_speed_driving_into_robots_and_walls_stays_within_the_bound(platform: str, scene: str, n: int) -> None:
    """600 steps of each scene: the corner pile of 100 robots is the deepest case (its robots press into each
    other and into two walls for hundreds of steps)."""
    robot, wall = hostile(platform, scene, n)
    assert robot <= MAX_OVERLAP and wall <= MAX_OVERLAP, f"overlap {robot:.2%}, wall {wall:.2%} of the diameter"
    assert robot > 0.001, "the scene must press robots together"
    if scene in ("corner", "walls"):
        assert wall > 0.001, "the scene must press robots into the walls"


@pytest.mark.slow
@pytest.mark.parametrize("platform", sorted(PLATFORMS))
@pytest.mark.parametrize("scene", SCENES)
@pytest.mark.parametrize("n", [10, 30, 100])
def test_full_speed_driving_stays_within_the_bound_many_seeds(platform: str, scene: str, n: int) -> None:
    worst = np.array([hostile(platform, scene, n, seed) for seed in range(3)]).max(axis=0)
    assert worst.max() <= MAX_OVERLAP, f"overlap {worst[0]:.2%}, wall {worst[1]:.2%} of the diameter"
