"""Physics at the default settings: robots overlap, and reach past a wall, by at most 2 % of their diameter
on every platform, free robots stay on their exact arcs, and any state read from ``infos`` is accepted by
``reset(options=...)``. (``benchmarks/physics_substeps.py`` prints the same worst cases over more seeds,
denser scenes and other sub-step counts.)"""

from __future__ import annotations

import numpy as np
import pytest

import swarm_envs
from swarm_envs.sim.platforms import PLATFORMS
from swarm_envs.tasks.settings import SettingsError
from swarm_envs.tasks.task import SPACING
from swarm_envs.sim.world import MAX_OVERLAP, World
from swarm_envs.sim.control import default_substeps, min_substeps
from swarm_envs.sim.spawning import spawn_positions
from swarm_envs.sim.arena import Arena
from swarm_envs.sim.geometry import wrap_angle


def drive(world: World, kind: str) -> tuple[np.ndarray, np.ndarray]:
    """Full speed towards the centre (``crush``) or towards the nearest wall (``wall``)."""
    pos = world.positions
    if kind == "crush":
        target = np.arctan2(-pos[:, 1], -pos[:, 0])
    else:
        axis = np.abs(pos).argmax(axis=1)
        sign = np.sign(pos[np.arange(len(pos)), axis])
        target = np.where(axis == 0, np.where(sign > 0, 0.0, np.pi), sign * np.pi / 2)
    err = wrap_angle(target - world.headings)
    return np.where(np.abs(err) < 0.5, world.platform.max_speed, 0.3 * world.platform.max_speed), 5 * err


def worst(platform: str, n: int, kind: str, seeds: range, shape: str = "square", steps: int = 100) -> tuple[float, float]:
    """Deepest overlap and wall reach (fractions of the diameter) at the default sub-steps and arena size."""
    p = PLATFORMS[platform]
    arena = Arena(shape, SPACING[platform] * np.sqrt(n))
    robot = wall = 0.0
    for seed in seeds:
        rng = np.random.default_rng(seed)
        world = World(p, n, arena)  # substeps=None: the platform's default
        world.place(spawn_positions(rng, n, p.radius, arena), rng.uniform(-np.pi, np.pi, n))
        for _ in range(steps):
            world.step(*drive(world, kind), 0.1)
            d = np.linalg.norm(world.positions[:, None] - world.positions[None], axis=-1) + np.eye(n) * 1e9
            robot = max(robot, p.diameter - d.min())
            wall = max(wall, float(arena.wall_depth(world.positions, p.radius).max()))
    return robot / p.diameter, wall / p.diameter


@pytest.mark.parametrize("platform", sorted(PLATFORMS))
@pytest.mark.parametrize("kind,n", [("crush", 10), ("wall", 10), ("crush", 30)])
def test_default_physics_overlaps_at_most_two_percent(platform, kind, n):
    robot, wall = worst(platform, n, kind, range(3))
    assert robot <= MAX_OVERLAP and wall <= MAX_OVERLAP, f"overlap {robot:.2%}, wall {wall:.2%} of the diameter"
    if kind == "crush":
        assert robot > 0.002, "the crush must press robots together"


@pytest.mark.slow
@pytest.mark.parametrize("platform", sorted(PLATFORMS))
@pytest.mark.parametrize("kind,n,shape", [("crush", 10, "square"), ("wall", 10, "square"), ("crush", 100, "square"), ("crush", 30, "circle")])
def test_default_physics_overlaps_at_most_two_percent_many_seeds(platform, kind, n, shape):
    robot, wall = worst(platform, n, kind, range(10), shape)
    assert robot <= MAX_OVERLAP and wall <= MAX_OVERLAP, f"overlap {robot:.2%}, wall {wall:.2%} of the diameter"


def test_default_substeps_per_platform_and_the_minimum_is_enforced():
    assert {name: default_substeps(p) for name, p in PLATFORMS.items()} == {"droplet": 8, "epuck": 21, "rone": 32}
    env = swarm_envs.make("swarm_envs/Flocking-v0", platform="rone", sensing="ideal")
    assert env.config["physics_substeps"] is None and env.world.substeps == 32
    assert swarm_envs.make("swarm_envs/Flocking-v0", physics_substeps=12, sensing="ideal").world.substeps == 12
    with pytest.raises(SettingsError, match=r"physics_substeps=10 is too few for platform 'rone': at least 11") as err:
        swarm_envs.make("swarm_envs/Flocking-v0", platform="rone", physics_substeps=10)
    assert err.value.key == "physics_substeps"
    assert {name: min_substeps(p) for name, p in PLATFORMS.items()} == {"droplet": 3, "epuck": 8, "rone": 11}
    swarm_envs.make("swarm_envs/Flocking-v0", platform="epuck", physics_substeps=8, sensing="ideal").reset(seed=0)


@pytest.mark.parametrize("platform", sorted(PLATFORMS))
@pytest.mark.parametrize("which", ["minimum", "8", "default"])
def test_free_robot_reverses_onto_its_exact_arc_at_any_allowed_substeps(platform, which):
    """The motors reach any commanded velocity within one sub-step: a free robot reversing at full speed and
    turning ends every control step on its differential-drive arc."""
    p = PLATFORMS[platform]
    substeps = {"minimum": min_substeps(p), "8": 8, "default": default_substeps(p)}[which]
    world = World(p, 1, Arena("square", 10.0), substeps=substeps)
    world.place(np.zeros((1, 2)), np.zeros(1))
    pos, heading = np.zeros(2), 0.0
    for k in range(12):
        v, w = world.wheel_limited(np.array([p.max_speed * (-1) ** k]), np.array([0.3 * p.max_angular_speed * (-1) ** (k // 3)]))
        world.step(v, w, 0.1)
        v, w = v.item(), w.item()
        pos = pos + v / w * np.array([np.sin(heading + w * 0.1) - np.sin(heading), np.cos(heading) - np.cos(heading + w * 0.1)])
        heading += w * 0.1
        np.testing.assert_allclose(world.positions[0], pos, atol=1e-9)


@pytest.mark.parametrize("platform", sorted(PLATFORMS))
@pytest.mark.parametrize("substeps", [None, "minimum"])
def test_states_from_infos_are_always_accepted_by_reset(platform, substeps):
    """Every step of a dense full-speed crush and of a wall rush: the ground truth in ``infos`` is a valid
    ``reset(options=...)`` placement, and that reset places the robots exactly there."""
    p = PLATFORMS[platform]
    kwargs = {"platform": platform, "sensing": "ideal", "n_robots": 30, "arena_size": 0.55 * p.diameter / 0.07, "max_cycles": 1000,
              "physics_substeps": None if substeps is None else min_substeps(p)}
    env, twin = swarm_envs.make("swarm_envs/Aggregation-v0", **kwargs), swarm_envs.make("swarm_envs/Aggregation-v0", **kwargs)
    deepest = 0.0
    for seed, kind in ((0, "crush"), (1, "wall")):
        _, infos = env.reset(seed=seed)
        for _ in range(60):
            gt = {k: np.array([infos[a]["ground_truth"][k] for a in env.agents]) for k in ("position", "heading")}
            twin.reset(seed=seed, options={"positions": gt["position"], "headings": gt["heading"]})
            np.testing.assert_array_equal(twin.world.positions, gt["position"])
            d = np.linalg.norm(gt["position"][:, None] - gt["position"][None], axis=-1) + np.eye(env.n_world)
            deepest = max(deepest, p.diameter - d.min())
            lin, ang = drive(env.world, kind)
            _, _, _, _, infos = env.step({a: np.array([lin[i] / p.max_speed, ang[i] / p.max_angular_speed])
                                          for i, a in enumerate(env.agents)})
    assert deepest > 0.001 * p.diameter, "the scene must press robots together"
