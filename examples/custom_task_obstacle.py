"""A task with an obstacle: the robots start left of a wall and must gather at a goal on its far side,
passing through the gap the wall leaves at the bottom of the arena. Importing this module registers
``swarm_examples/GatherBeyondWall-v0``::

    import examples.custom_task_obstacle, swarm_envs             # from the repository root
    env = swarm_envs.make("swarm_examples/GatherBeyondWall-v0", n_robots=8)
    swarm-demo --import examples/custom_task_obstacle.py --task swarm_examples/GatherBeyondWall-v0 --policy random --out wall.gif

The wall stops robots and blocks infrared light like any obstacle; the robots still observe the world only
through the sensing stack. Frame: the arena is centred on the origin, x and y in metres.
"""

import numpy as np

import swarm_envs
from swarm_envs.tasks.settings import SettingsError
from swarm_envs.tasks.task import Real, Task
from swarm_envs.sim.spawning import check_capacity, spawn_positions
from swarm_envs.sim.arena import Arena


class GatherBeyondWall(Task):
    """Reward per robot: minus its distance to the goal (m) over the arena size, every step."""

    SETTINGS = {
        "arena_size": 1.2,  # another default for a common setting (m)
        "gap": Real(0.3, "width of the passage below the wall", low=0.0, low_open=True, high=100.0, unit="m"),
    }
    METRICS = {"fraction_across": "final", "mean_goal_distance": "final"}
    HEADLINE = ("fraction_across", +1)

    def _start_square(self) -> Arena:
        """The square (centred on the origin) the robots are spawned in before it is shifted left of the wall."""
        return Arena("square", 0.5 * self.arena.size - 2 * self.platform.diameter)

    def goal(self) -> np.ndarray:
        """The goal (2,) m: the centre of the right half."""
        return np.array([0.25 * self.arena.size, 0.0])

    def obstacles(self) -> np.ndarray:
        """One vertical wall on x = 0 from the top wall down to ``gap`` above the bottom wall: (1, 2, 2) m."""
        half = self.arena.half
        return np.array([[[0.0, -half + self.config["gap"]], [0.0, half]]])

    def check_layout(self) -> None:
        if self.arena.shape != "square":
            raise SettingsError("arena", "GatherBeyondWall needs a square arena")
        if self.config["gap"] >= self.arena.size:
            raise SettingsError("gap", f"the gap ({self.config['gap']} m) must be smaller than the arena ({self.arena.size} m)")
        try:
            check_capacity(self.n_world, self.platform.radius, self._start_square())
        except ValueError as err:
            raise SettingsError(self.size_key, f"the left half cannot hold the robots: {err}") from None

    def spawn(self, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """Robots non-overlapping in a square centred on (-arena/4, 0), clear of the wall; headings uniform."""
        square = self._start_square()
        positions = spawn_positions(rng, self.n_world, self.platform.radius, self.arena, region=square)
        return positions + [-0.25 * self.arena.size, 0.0], rng.uniform(-np.pi, np.pi, self.n_world)

    def markers(self, positions: np.ndarray) -> dict[str, np.ndarray]:
        return {"goal": self.goal()}

    def rewards(self, state, first):
        positions = self.agents_of(state.positions)  # (B, N, 2) m
        distance = np.linalg.norm(positions - self.goal(), axis=-1)  # (B, N) m
        across = (positions[..., 0] > self.platform.radius).mean(axis=1)  # (B,) fraction right of the wall
        rewards = -distance / self.arena.size
        return rewards, {"goal_distance": rewards}, {"fraction_across": across, "mean_goal_distance": distance.mean(axis=1)}


swarm_envs.register("swarm_examples/GatherBeyondWall-v0", GatherBeyondWall)
