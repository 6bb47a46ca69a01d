"""The native PettingZoo ``ParallelEnv`` all swarm tasks share.

Data flows one way each control step (``DT`` = 0.1 s):
physics (:mod:`swarm_envs.sim.world`) -> sensing stack (IR channel -> range & bearing, messages,
scale-free coordinates) -> observation (:mod:`swarm_envs.sensing.observation`) -> reward (the task subclass).
Ground truth goes to ``infos`` (group ``"ground_truth"``) and :meth:`SwarmEnv.state` only.

``infos[agent]`` is a nested dict, one dict per group of :data:`INFO_GROUPS`, e.g.
``infos["robot_0"]["metrics"]["polarisation"]``; the values are plain Python numbers and ``(x, y)``
tuples (position, velocity), so ``json.dumps(infos)`` works. TorchRL's stock ``PettingZooWrapper`` makes
one tensor per info key and reads flat dicts only: wrap the env in :class:`FlatInfos` (keys
``(group, name)``, the key paths TensorDict nests) for it.
"""

from __future__ import annotations

import functools
from collections.abc import Iterable, Mapping
from typing import Any

import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv
from pettingzoo.utils import BaseParallelWrapper

from swarm_envs.tasks._task_checks import checked_markers
from swarm_envs.core import DT, SwarmCore
from swarm_envs.sim.platforms import Platform, get_platform
from swarm_envs.sensing.base import SensorFrame
from swarm_envs.tasks.task import Task
from swarm_envs.adapters.views import check_finite_actions, check_reset_options, check_seed, info_arrays, make_layout, real_actions, resolve_config
from swarm_envs.sim.world import World

__all__ = [
    "SwarmEnv", "DT", "INFO_GROUPS", "STATE_ROBOT_FIELDS", "info_group", "flat_info", "FlatInfos",
]

#: The groups of ``infos[agent]``, in order: ``infos[agent][group][name]``.
INFO_GROUPS = ("ground_truth", "reward_terms", "metrics", "sensing")
#: Per-robot fields of :meth:`SwarmEnv.state`, in order (arena frame, SI units).
STATE_ROBOT_FIELDS = ("x", "y", "cos_heading", "sin_heading", "vx", "vy", "angular_velocity")


class SwarmEnv(ParallelEnv):
    """A swarm of disc robots whose observations come from a modelled infrared sensing stack.

    A thin PettingZoo view of the batched core (:class:`swarm_envs.core.SwarmCore`) with one copy, for
    any task: ``SwarmEnv(TaskClass, **settings)``, or a subclass that sets ``TASK`` (the suite's task
    modules do: ``AggregationEnv(**settings)``). See :data:`swarm_envs.tasks.settings.COMMON_SETTINGS` for the
    keyword arguments every task takes, and the task's ``SETTINGS`` for its own.

    Actions are ``Box(-1, 1, (2 + message_bits,))``: (linear, angular) velocity as fractions of the
    platform maxima, then the message bits (entries > 0 are 1-bits). Finite values outside [-1, 1] are
    clipped; NaN/inf, wrong shapes and unknown agents raise. The wheels deliver the commands with the
    platform's motion error (``motion_noise``); zero actions keep a robot still all the same.

    Envs can be copied (``copy.deepcopy``) and pickled, before a reset or mid-episode: the copy continues
    bit for bit like the original under the same actions.
    """

    metadata = {"name": "swarm_v0", "render_modes": ["human", "rgb_array"], "render_fps": int(1 / DT), "is_parallelizable": True}
    TASK: type[Task] = Task

    def __init__(self, task: type[Task] | None = None, /, **kwargs: Any) -> None:
        task_cls = self.TASK if task is None else task
        if not (isinstance(task_cls, type) and issubclass(task_cls, Task)) or task_cls is Task:
            raise TypeError(f"{type(self).__name__} needs a swarm_envs.tasks.task.Task subclass (SwarmEnv(TaskClass, ...)), got {task_cls!r:.80}")
        if task is not None and task is not self.TASK:
            self.metadata = {**self.metadata, "name": _snake_case(task_cls.__name__)}
        # every setting is checked here, whatever the sensing mode (swarm_envs.tasks.settings)
        cfg = resolve_config(task_cls, kwargs)
        self.config = cfg
        self.platform: Platform = get_platform(cfg["platform"])
        self.render_mode = cfg["render_mode"]
        self.task = task_cls(cfg, self.platform, n_copies=1)
        self.max_cycles = self.task.max_cycles
        self.reward_mode = self.task.reward_mode
        self.n_static = self.task.n_static
        self.n_agents = self.task.n_agents
        self.n_world = self.task.n_world
        self.arena = self.task.arena
        self.possible_agents = [f"robot_{i}" for i in range(self.n_agents)]
        self.agents: list[str] = []
        self._agent_index = {a: i for i, a in enumerate(self.possible_agents)}
        self.agent_robots = self.task.agent_robots  # robot index of each agent
        self.layout = make_layout(cfg, self.platform, self.n_world)
        self._obs_space = self.layout.space()
        self._act_space = self.layout.action_space()
        self.core = SwarmCore(self.task, self.layout)
        self._renderer = None
        self.num_cycles = 0

    # -- copies ----------------------------------------------------------------------------------------
    def __getstate__(self) -> dict[str, Any]:
        state = dict(self.__dict__)
        state["_renderer"] = None  # a pygame surface or window is not copied; the copy draws anew
        return state

    # -- the core's single copy ----------------------------------------------------------------------
    @property
    def world(self) -> World:
        """The physics of the env's one copy."""
        return self.core.worlds[0]

    @property
    def sensing(self):
        """The sensing stack (one copy)."""
        return self.core.sensing

    @property
    def _frame(self) -> SensorFrame | None:
        return self.core.frame

    def _markers(self) -> dict[str, np.ndarray]:
        """Task markers (name -> world point (2,) m, sorted by name): drawn by the renderer and part of
        :meth:`state`. Checked (:func:`swarm_envs.tasks._task_checks.checked_markers`): a task returns the same
        names every step (the state has a fixed size)."""
        names, points = checked_markers(self.task, [self.task.markers(self.world.positions)])
        return dict(zip(names, points[0]))

    # -- spaces ----------------------------------------------------------------------------------------
    def observation_space(self, agent: str) -> spaces.Space:
        self._check_agent(agent)
        return self._obs_space

    def action_space(self, agent: str) -> spaces.Box:
        self._check_agent(agent)
        return self._act_space

    @property
    def observation_spaces(self) -> dict[str, spaces.Space]:
        """Every possible agent's observation space (PettingZoo API); all agents share one space."""
        return {a: self._obs_space for a in self.possible_agents}

    @property
    def action_spaces(self) -> dict[str, spaces.Box]:
        """Every possible agent's action space (PettingZoo API); all agents share one space."""
        return {a: self._act_space for a in self.possible_agents}

    @functools.cached_property
    def state_space(self) -> spaces.Box:
        """Space of :meth:`state`: ``Box`` of shape ``(7 n_world + 2 n_markers + 1,)``, float32.

        Bounds are hard limits, not typical ranges: positions within the arena's half size (m),
        velocities at most the arena size per control step (m/s), angular velocity at most pi per step
        (rad/s, headings are wrapped), progress in [0, 1].
        """
        half, v, w = self.arena.half, self.arena.size / DT, np.pi / DT
        robot_high = np.array([half, half, 1.0, 1.0, v, v, w])
        high = np.concatenate([np.tile(robot_high, self.n_world), np.full(2 * len(self._markers()), half), [1.0]])
        low = np.concatenate([-high[:-1], [0.0]])
        return spaces.Box(low.astype(np.float32), high.astype(np.float32), dtype=np.float32)

    def _check_agent(self, agent: str) -> int:
        try:
            return self._agent_index[agent]
        except (KeyError, TypeError):
            raise KeyError(
                f"unknown agent {agent!r}; this env's agents are {self.possible_agents[0]!r} .. {self.possible_agents[-1]!r}"
            ) from None

    # -- reset / step ------------------------------------------------------------------------------------
    def reset(self, seed: int | None = None, options: dict | None = None):
        """Start an episode. ``seed`` (int >= 0) reseeds the env's generator; ``None`` continues its stream.

        ``options`` (dict or None): ``"positions"`` (n, 2) m places the robots there and the task's
        spawner does not run; ``"headings"`` (n,) rad sets the headings. Positions alone: headings drawn
        uniformly from the spawn stream. Headings alone: the task spawns the positions as usual and its
        headings are replaced. Anything wrong (seed, options, placement) raises ``TypeError`` or
        ``ValueError`` before the env changes. Every reset builds a new physics space and new sensing
        state, so ``reset(seed=s)`` behaves the same on a fresh env and on a reused one.
        """
        seed = check_seed(seed)
        pose = check_reset_options(options, self.world)
        self.core.seed(0, seed)
        self.core.start([0], [pose])
        self.core.step(None)
        self.agents = list(self.possible_agents)
        self.num_cycles = 0
        obs = self._observations()
        infos = self._infos()
        if self.render_mode == "human":
            self.render()
        return obs, infos

    def _action_array(self, actions: dict[str, Any]) -> np.ndarray:
        """(n_world, action_size) float64 actions of the live agents, checked and clipped to [-1, 1]."""
        if not isinstance(actions, dict):
            raise TypeError(f"actions must be a dict mapping agent names to arrays, got {type(actions).__name__}")
        live = set(self.agents)
        if len(actions) != len(live) or not live.issuperset(actions):
            unknown = [a for a in actions if a not in live]
            if unknown:
                raise KeyError(f"actions given for unknown or finished agent(s) {unknown[:5]}; live agents: {len(self.agents)} named robot_0..")
            missing = [a for a in self.agents if a not in actions]
            raise KeyError(f"missing actions for agent(s) {missing[:5]}; every live agent needs an action")
        size = self.layout.action_size
        # numeric arrays of the right shape are stacked at once; anything else is checked agent by agent,
        # which also names the agent in an error
        values = [actions[a] for a in self.agents]
        if all(type(v) is np.ndarray and v.dtype.kind in "iuf" and v.shape == (size,) for v in values) and values:
            arr = np.stack(values).astype(np.float64)
        else:
            bits = self.layout.message_bits
            expected = f"({size},) = (linear, angular" + (f", {bits} message bits)" if bits else ")")
            arr = np.stack([real_actions(v, (size,), f"action for {a}", expected) for a, v in zip(self.agents, values)]) if values else np.zeros((0, size))
        out = np.zeros((self.n_world, size))
        out[self.agent_robots[[self._agent_index[a] for a in self.agents]]] = check_finite_actions(arr, self.agents.__getitem__)
        return out

    def step(self, actions: dict[str, Any]):
        if not self.agents:
            raise RuntimeError("step() called on a finished episode; call reset() first")
        act = self._action_array(actions)
        self.core.step(act)
        self.num_cycles = int(self.core.num_cycles[0])
        rewards_arr = self.core.rewards[0]
        obs = self._observations()
        infos = self._infos()
        rewards = dict(zip(self.agents, np.asarray(rewards_arr, dtype=float)[[self._agent_index[a] for a in self.agents]].tolist()))
        truncated = self.num_cycles >= self.max_cycles
        terminations = {a: False for a in self.agents}
        truncations = {a: truncated for a in self.agents}
        if truncated:
            self.agents = []
        if self.render_mode == "human":
            self.render()
        return obs, rewards, terminations, truncations, infos

    # -- observations and infos ----------------------------------------------------------------------------
    def batched_observations(self) -> dict[str, np.ndarray]:
        """Observation parts of every robot (leading axis = world robot), from the last sensor frame."""
        return self.core.observations()

    def _observations(self) -> dict[str, Any]:
        """Per live agent its observation: rows of this step's batched arrays (one array operation per part)."""
        batched = self.batched_observations()
        rows = self.agent_robots[[self._agent_index[a] for a in self.agents]]
        if self.layout.flatten:  # as gymnasium.spaces.flatten per agent: the parts' rows concatenated, float32
            parts = [np.asarray(batched[name])[rows].reshape(len(rows), -1) for name in self.layout.dict_space().spaces]
            return dict(zip(self.agents, np.concatenate(parts, axis=1).astype(np.float32, copy=False)))
        names = list(batched)
        parts = [np.asarray(batched[name])[rows] for name in names]
        return {agent: dict(zip(names, values)) for agent, values in zip(self.agents, zip(*parts))}

    def state(self) -> np.ndarray:
        """Global ground-truth state for centralised critics (never part of any observation).

        Float32 vector: for every robot in world order (static robots such as anchors first, then the
        agents) ``STATE_ROBOT_FIELDS`` = x, y (m), cos, sin heading, vx, vy (m/s, achieved over the last
        step), angular velocity (rad/s), all in the arena frame; then the task's markers (x, y in m,
        sorted by name, e.g. the centroid); then episode progress ``num_cycles / max_cycles``.
        Lies in :attr:`state_space`. Call after :meth:`reset`.
        """
        if self._frame is None:
            raise RuntimeError("state() needs a started episode; call reset() first")
        w = self.world
        robots = np.column_stack(
            [w.positions, np.cos(w.headings), np.sin(w.headings), w.velocities, w.angular_velocities]
        ).ravel()
        markers = self._markers()
        points = np.concatenate([markers[name] for name in sorted(markers)]) if markers else np.zeros(0)
        progress = min(self.num_cycles / self.max_cycles, 1.0)
        return np.concatenate([robots, points, [progress]]).astype(np.float32)

    def _infos(self) -> dict[str, dict[str, dict[str, Any]]]:
        """Per agent, one dict per group of :data:`INFO_GROUPS` (all four, ``"sensing"`` empty under ideal
        sensing); values are Python numbers, position and velocity ``(x, y)`` tuples.

        Built column by column over all agents (one array operation and one ``tolist`` per name), then one
        small dict per agent and group."""
        agents = self.agents
        index = [self._agent_index[a] for a in agents]
        arrays = info_arrays(self.core, self.agent_robots[None, index])  # one copy: (1, n, ...) arrays
        truth, n = arrays["ground_truth"], len(agents)
        ground_truth = _row_dicts(
            ("position", "heading", "velocity"), [_pairs(truth["position"][0]), truth["heading"][0].tolist(), _pairs(truth["velocity"][0])], n
        )
        terms = _row_dicts(arrays["reward_terms"], [v[0, index].tolist() for v in arrays["reward_terms"].values()], n)
        sensing = _row_dicts(arrays["sensing"], [v[0].tolist() for v in arrays["sensing"].values()], n)
        metrics = {name: float(v[0]) for name, v in arrays["metrics"].items()}  # one value per copy: the same for every agent
        return {
            agent: {"ground_truth": g, "reward_terms": t, "metrics": dict(metrics), "sensing": s}
            for agent, g, t, s in zip(agents, ground_truth, terms, sensing)
        }

    # -- rendering -----------------------------------------------------------------------------------
    def render(self) -> np.ndarray | None:
        """Draw the whole arena: robots with headings, the IR links that carried a reading this step, task markers.

        ``render_mode="rgb_array"``: returns a (480, 480, 3) uint8 RGB image; ``"human"``: draws in a window and
        returns None (:mod:`swarm_envs.adapters.render`; ``swarm-demo`` draws GIFs with a view that follows the robots)."""
        if self.render_mode is None:
            import gymnasium

            gymnasium.logger.warn("render() called without render_mode; pass render_mode='rgb_array' or 'human'")
            return None
        from swarm_envs.adapters.render import Renderer, render_env

        if self._renderer is None:
            self._renderer = Renderer(
                self.arena, self.platform, human=self.render_mode == "human", fps=self.metadata["render_fps"], obstacles=self.task.obstacle_segments
            )
        if self._frame is None:  # before the first reset: the robots where they are, no links
            return self._renderer.draw(self.world.positions, self.world.headings, None, self._markers(), static=np.arange(self.n_world) < self.n_static)
        return render_env(self, self._renderer, legend=False)  # the IR links that carried a reading this step

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def __repr__(self) -> str:
        return f"{type(self).__name__}(n_robots={self.n_agents}, platform={self.platform.name!r}, sensing={self.config['sensing']!r})"


def _snake_case(name: str) -> str:
    """``"MyTask"`` -> ``"my_task"`` (the PettingZoo ``metadata["name"]`` of a task's env)."""
    return "".join(f"_{c.lower()}" if c.isupper() and i else c.lower() for i, c in enumerate(name))


def _pairs(xy: np.ndarray) -> list[tuple[float, float]]:
    """Rows of an (n, 2) array as ``(x, y)`` tuples of Python floats.

    Tuples rather than lists: CPython's collector stops tracking tuples of numbers, so the infos of 1000
    agents leave few tracked objects behind and full collections stay rare (with lists, one every ~16 steps
    of a 1000-robot env, ~5 ms per step)."""
    return list(zip(xy[:, 0].tolist(), xy[:, 1].tolist()))


def _row_dicts(names: Iterable[str], columns: list[list[Any]], n: int) -> list[dict[str, Any]]:
    """``n`` dicts name -> value, the i-th from the i-th entry of every column (one column per name)."""
    if not columns:
        return [{} for _ in range(n)]
    names = tuple(names)
    return [dict(zip(names, values)) for values in zip(*columns)]


def info_group(info: Mapping[Any, Any], group: str) -> dict[str, Any]:
    """One group of an agent's info, ``info[group]``, e.g. ``info_group(infos["robot_0"], "metrics")``; also
    reads the flat ``(group, name)`` form of :func:`flat_info`. ``KeyError`` for a group not in
    :data:`INFO_GROUPS`."""
    if group not in INFO_GROUPS:
        raise KeyError(f"unknown info group {group!r}; groups: {list(INFO_GROUPS)}")
    if group in info:
        return info[group]
    return {key[1]: value for key, value in info.items() if isinstance(key, tuple) and key[0] == group}


def flat_info(info: Mapping[str, Mapping[str, Any]]) -> dict[tuple[str, str], Any]:
    """An agent's nested info as one flat dict keyed by ``(group, name)``, e.g. ``("metrics", "n_clusters")``."""
    return {(group, name): value for group, values in info.items() for name, value in values.items()}


class FlatInfos(BaseParallelWrapper):
    """A swarm env whose ``infos[agent]`` are flat dicts keyed by ``(group, name)`` (:func:`flat_info`).

    For TorchRL's stock ``PettingZooWrapper``, which makes one tensor per info key and does not read nested
    dicts; tuple keys are the key paths TensorDict nests, so the wrapper's ``(group, "info")`` entry holds
    ``("metrics", name)`` and the other groups as nested tensors::

        from torchrl.envs.libs.pettingzoo import PettingZooWrapper
        env = PettingZooWrapper(FlatInfos(swarm_envs.make("swarm_envs/Flocking-v0")), return_state=True)

    Everything else (spaces, ``state()``, ``agents``, attributes) is the wrapped env's.
    """

    def reset(
        self, seed: int | None = None, options: dict[str, Any] | None = None
    ) -> tuple[dict[str, Any], dict[str, dict[tuple[str, str], Any]]]:
        obs, infos = self.env.reset(seed=seed, options=options)
        return obs, {agent: flat_info(info) for agent, info in infos.items()}

    def step(self, actions: dict[str, Any]) -> tuple[dict, dict, dict, dict, dict[str, dict[tuple[str, str], Any]]]:
        obs, rewards, terminations, truncations, infos = self.env.step(actions)
        return obs, rewards, terminations, truncations, {agent: flat_info(info) for agent, info in infos.items()}


from swarm_envs.tasks.task import bump_any  # noqa: E402,F401  (kept importable from here)
