"""The native PettingZoo ``ParallelEnv`` all swarm tasks share.

Data flows one way each control step (``DT`` = 0.1 s):
physics (:mod:`swarm_envs.world`) -> sensing stack (IR channel -> range & bearing, messages,
scale-free coordinates) -> observation (:mod:`swarm_envs.observation`) -> reward (the task subclass).
Ground truth goes to ``infos[agent]["ground_truth"]`` only.
"""

from __future__ import annotations

import numbers
from collections.abc import Mapping
from typing import Any

import numpy as np
from gymnasium import spaces
from pettingzoo import ParallelEnv

from swarm_envs.observation import ObservationLayout, pack_nearest
from swarm_envs.platforms import Platform, get_platform
from swarm_envs.sensing.base import SensorFrame
from swarm_envs.settings import COMMON_DEFAULTS, validate_settings
from swarm_envs.world import N_BUMP_SECTORS, Arena, World, as_real_array, check_capacity, spawn_positions

__all__ = ["SwarmEnv", "DT", "COMMON_DEFAULTS"]

DT = 0.1  # s, one control step = the Droplet R&B update rate [F14 Sec. V]

# default centre spacing (m) used to size the arena when arena_size is None
_SPACING = {"droplet": 0.15, "epuck": 0.25, "rone": 0.45}


class SwarmEnv(ParallelEnv):
    """A swarm of disc robots whose observations come from a modelled infrared sensing stack.

    Subclasses set ``TASK_DEFAULTS`` (extra kwargs and task-specific defaults) and implement
    :meth:`_spawn` and :meth:`_rewards`. See :data:`COMMON_DEFAULTS` for the shared keyword arguments.

    Actions are ``Box(-1, 1, (2 + message_bits,))``: (linear, angular) velocity as fractions of the
    platform maxima, then the message bits (entries > 0 are 1-bits). Finite values outside [-1, 1] are
    clipped; NaN/inf, wrong shapes and unknown agents raise. Zero actions keep a robot still.
    """

    metadata = {"name": "swarm_v0", "render_modes": ["human", "rgb_array"], "render_fps": int(1 / DT), "is_parallelizable": True}
    TASK_DEFAULTS: dict[str, Any] = {}

    def __init__(self, **kwargs: Any) -> None:
        # every setting is checked here, whatever the sensing mode (swarm_envs.settings)
        cfg = validate_settings(type(self), kwargs)
        self.config = cfg
        self.platform: Platform = get_platform(cfg["platform"])
        self.render_mode = cfg["render_mode"]
        self.max_cycles = int(cfg["max_cycles"])
        self.reward_mode = cfg["reward_mode"]
        self.n_static = self._n_static()
        self.n_agents = int(cfg["n_robots"])
        self.n_world = self.n_static + self.n_agents
        size = cfg["arena_size"] if cfg["arena_size"] is not None else self._default_arena_size()
        self.arena = Arena(cfg["arena"], float(size))
        # robots that cannot fit even touching fail here; the random spawner also keeps a gap of 0.1
        # radius, so an arena within ~10 % of a full packing can still fail at reset (without positions)
        check_capacity(self.n_world, self.platform.radius, self.arena, gap=0.0)
        self._check_layout()
        self.possible_agents = [f"robot_{i}" for i in range(self.n_agents)]
        self.agents: list[str] = []
        self._agent_index = {a: i for i, a in enumerate(self.possible_agents)}
        self.agent_robots = np.arange(self.n_static, self.n_world)  # robot index of each agent
        self.layout = ObservationLayout(
            n_neighbours=cfg["n_neighbours"],
            n_messages=cfg["n_messages"],
            message_bits=cfg["message_bits"],
            max_range=self.platform.ir_range,
            max_age=cfg["rb_max_age"],
            flatten=cfg["flatten"],
        )
        self._obs_space = self.layout.space()
        self._act_space = self.layout.action_space()
        self.world = World(self.platform, self.n_world, self.arena, substeps=cfg["physics_substeps"])
        self.sensing = self._make_sensing()
        self._rng = np.random.default_rng()
        self._renderer = None
        self._last_actions = np.zeros((self.n_world, self.layout.action_size))
        self._frame: SensorFrame | None = None
        self.num_cycles = 0

    # -- hooks for tasks -----------------------------------------------------------------------------
    def _n_static(self) -> int:
        """Number of non-agent (static) robots; they sense and emit but are never commanded."""
        return 0

    def _check_layout(self) -> None:
        """Task hook, run by the constructor once the arena is built: raise ``ValueError`` when the
        task's initial layout cannot fit (e.g. too many anchors on their circle)."""

    def _default_arena_size(self) -> float:
        """Arena size (m) when ``arena_size=None``: the platform's spacing times sqrt(robots)."""
        return _SPACING.get(self.platform.name, 4 * self.platform.diameter) * float(np.sqrt(self.n_world))

    def _spawn(self, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        """Task's initial (positions (n_world, 2) m, headings (n_world,) rad)."""
        positions = spawn_positions(rng, self.n_world, self.platform.radius, self.arena)
        return positions, rng.uniform(-np.pi, np.pi, self.n_world)

    def _rewards(self, first: bool) -> tuple[np.ndarray, dict[str, np.ndarray], dict[str, float]]:
        """(reward per agent (n_agents,), reward terms per agent, swarm metrics). ``first`` on reset."""
        raise NotImplementedError

    def _markers(self) -> dict[str, np.ndarray]:
        """Task markers to draw (name -> world point)."""
        return {}

    # -- sensing ---------------------------------------------------------------------------------------
    def _make_sensing(self):
        cfg = self.config
        if cfg["sensing"] == "ideal":
            from swarm_envs.sensing.ideal import IdealSensing

            return IdealSensing(self.platform, self.n_world, cfg["n_neighbours"], cfg["message_bits"])
        try:
            from swarm_envs.sensing.full import FullSensing
        except ImportError as err:  # pragma: no cover - only while a sensing module is missing
            raise NotImplementedError(
                f"sensing='full' needs the module {err.name!r}, which is not available; use sensing='ideal'"
            ) from err
        return FullSensing(self.platform, self.n_world, cfg)

    # -- spaces ----------------------------------------------------------------------------------------
    def observation_space(self, agent: str) -> spaces.Space:
        self._check_agent(agent)
        return self._obs_space

    def action_space(self, agent: str) -> spaces.Box:
        self._check_agent(agent)
        return self._act_space

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
        seed = _check_seed(seed)
        given_positions, given_headings = self._check_options(options)
        if seed is not None:
            self._rng = np.random.default_rng(seed)
        # independent child streams: spawn, and sensing (which splits it into noise, channel and MAC)
        streams = np.random.SeedSequence(int(self._rng.integers(2**63))).spawn(2)
        self._spawn_rng, sensing_rng = (np.random.default_rng(s) for s in streams)
        if given_positions is None:
            positions, headings = self._spawn(self._spawn_rng)
        else:
            positions, headings = given_positions, None
        if given_headings is not None:
            headings = given_headings
        elif headings is None:
            headings = self._spawn_rng.uniform(-np.pi, np.pi, self.n_world)
        self.world.place(positions, headings)
        self.sensing.reset(sensing_rng)
        self.agents = list(self.possible_agents)
        self.num_cycles = 0
        self._last_actions = np.zeros((self.n_world, self.layout.action_size))
        self._frame = self.sensing.step(self.world.positions, self.world.headings, None)
        _, terms, metrics = self._rewards(first=True)
        obs = self._observations()
        infos = self._infos(terms, metrics)
        if self.render_mode == "human":
            self.render()
        return obs, infos

    def _check_options(self, options: Any) -> tuple[np.ndarray | None, np.ndarray | None]:
        """Validated (positions, headings) from reset ``options`` (None where not given); changes nothing."""
        if options is None:
            return None, None
        if not isinstance(options, Mapping):
            raise TypeError(
                f"reset options must be a dict (keys 'positions', 'headings') or None, got {type(options).__name__}: {options!r:.80}"
            )
        unknown = sorted((k for k in options if k not in ("positions", "headings")), key=str)
        if unknown:  # a warning, not an error: PettingZoo's API test passes arbitrary options
            import gymnasium

            gymnasium.logger.warn(f"ignoring unknown reset option(s) {unknown}; allowed: ['headings', 'positions']")
        positions = headings = None
        if "headings" in options:
            headings = as_real_array(options["headings"], "options['headings']")
            if headings.shape != (self.n_world,):
                raise ValueError(f"options['headings'] must have shape ({self.n_world},) radians, got {headings.shape}")
            if not np.all(np.isfinite(headings)):
                raise ValueError("options['headings'] must be finite")
        if "positions" in options:
            positions = as_real_array(options["positions"], "options['positions']")
            if positions.shape != (self.n_world, 2):
                raise ValueError(f"options['positions'] must have shape ({self.n_world}, 2) metres, got {positions.shape}")
            positions, _ = self.world.check_placement(positions, np.zeros(self.n_world) if headings is None else headings)
        return positions, headings

    def _action_array(self, actions: dict[str, Any]) -> np.ndarray:
        if not isinstance(actions, dict):
            raise TypeError(f"actions must be a dict mapping agent names to arrays, got {type(actions).__name__}")
        unknown = [a for a in actions if a not in self._agent_index or a not in self.agents]
        if unknown:
            raise KeyError(f"actions given for unknown or finished agent(s) {unknown[:5]}; live agents: {len(self.agents)} named robot_0..")
        missing = [a for a in self.agents if a not in actions]
        if missing:
            raise KeyError(f"missing actions for agent(s) {missing[:5]}; every live agent needs an action")
        size = self.layout.action_size
        out = np.zeros((self.n_world, size))
        for agent, action in actions.items():
            try:
                arr = np.asarray(action)
            except (TypeError, ValueError):
                arr = np.asarray(None)
            if arr.dtype.kind not in "iuf":  # not bool, complex, strings (even of digits) or objects
                raise TypeError(
                    f"action for {agent} must be a real-valued numeric array of shape ({size},) "
                    f"(int or float dtype), got {action!r:.80} of dtype {arr.dtype}"
                )
            arr = arr.astype(np.float64)
            if arr.shape != (size,):
                raise ValueError(
                    f"action for {agent} has shape {arr.shape}; expected ({size},) = (linear, angular"
                    + (f", {self.layout.message_bits} message bits)" if self.layout.message_bits else ")")
                )
            if not np.all(np.isfinite(arr)):
                raise ValueError(f"action for {agent} contains NaN or inf: {arr}")
            out[self.agent_robots[self._agent_index[agent]]] = arr
        return np.clip(out, -1.0, 1.0)

    def step(self, actions: dict[str, Any]):
        if not self.agents:
            raise RuntimeError("step() called on a finished episode; call reset() first")
        act = self._action_array(actions)
        self._last_actions = act
        linear = act[:, 0] * self.platform.max_speed
        angular = act[:, 1] * self.platform.max_angular_speed
        self.world.step(linear, angular, DT)
        payloads = act[:, 2:] > 0 if self.layout.message_bits else None
        if payloads is not None:
            payloads[: self.n_static] = False  # static robots send no application messages
        self._frame = self.sensing.step(self.world.positions, self.world.headings, payloads)
        self.num_cycles += 1
        rewards_arr, terms, metrics = self._rewards(first=False)
        obs = self._observations()
        infos = self._infos(terms, metrics)
        rewards = {a: float(rewards_arr[i]) for i, a in enumerate(self.agents)}
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
        frame = self._frame
        n, k, m, b = self.n_world, self.layout.n_neighbours, self.layout.n_messages, self.layout.message_bits
        nb = frame.neighbours
        rb_values = np.stack(
            [np.ones(len(nb.rx)), nb.range, np.cos(nb.bearing), np.sin(nb.bearing), np.cos(nb.heading), np.sin(nb.heading), nb.age],
            axis=-1,
        ) if len(nb.rx) else np.zeros((0, 7))
        range_bearing, _ = pack_nearest(n, nb.rx, nb.range, rb_values, k)
        msg = frame.messages
        if len(msg.receiver):
            key = msg.distance_hint if msg.distance_hint is not None else np.arange(len(msg.receiver), dtype=float)
            msg_values = np.concatenate([np.ones((len(msg.receiver), 1)), msg.bearing[:, None] / np.pi, msg.payload.reshape(len(msg.receiver), b)], axis=1)
            messages, _ = pack_nearest(n, msg.receiver, key, msg_values, m)
        else:
            messages = np.zeros((n, m, 2 + b))
        sf = frame.scale_free
        scale_free = np.concatenate([sf.valid[..., None].astype(float), np.where(sf.valid[..., None], sf.xy, 0.0)], axis=-1)
        proprio = np.concatenate([self.world.bumps.astype(float), self._last_actions], axis=1)
        return self.layout.build(range_bearing, messages, scale_free, sf.rigid.astype(float), proprio)

    def _observations(self) -> dict[str, Any]:
        batched = self.batched_observations()
        return {a: self.layout.per_robot(batched, self.agent_robots[i]) for i, a in enumerate(self.agents)}

    def _infos(self, terms: dict[str, np.ndarray], metrics: dict[str, float]) -> dict[str, dict]:
        world = self.world
        stats = self._frame.stats if self._frame is not None else {}
        infos = {}
        for i, agent in enumerate(self.agents):
            r = self.agent_robots[i]
            infos[agent] = {
                "ground_truth": {
                    "position": world.positions[r].copy(),
                    "heading": float(world.headings[r]),
                    "velocity": world.velocities[r].copy(),
                },
                "reward_terms": {name: float(v[i]) for name, v in terms.items()},
                "metrics": dict(metrics),
                "sensing": {name: (v[r].item() if np.ndim(v) == 1 else v[r].copy()) for name, v in stats.items()},
            }
        return infos

    # -- rendering -----------------------------------------------------------------------------------
    def render(self):
        if self.render_mode is None:
            import gymnasium

            gymnasium.logger.warn("render() called without render_mode; pass render_mode='rgb_array' or 'human'")
            return None
        from swarm_envs.render import Renderer

        if self._renderer is None:
            self._renderer = Renderer(self.arena, self.platform, human=self.render_mode == "human", fps=self.metadata["render_fps"])
        links = (self._frame.neighbours.rx, self._frame.neighbours.tx) if self._frame is not None else None
        return self._renderer.draw(
            self.world.positions, self.world.headings, links, self._markers(), static=np.arange(self.n_world) < self.n_static
        )

    def close(self) -> None:
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None

    def __repr__(self) -> str:
        return f"{type(self).__name__}(n_robots={self.n_agents}, platform={self.platform.name!r}, sensing={self.config['sensing']!r})"


def _check_seed(seed: Any) -> int | None:
    """``seed`` as an int (or None); ``ValueError`` for a negative, ``TypeError`` for a non-integer seed."""
    if seed is None:
        return None
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, numbers.Integral):
        raise TypeError(f"seed must be a non-negative integer or None, got {seed!r} ({type(seed).__name__})")
    if seed < 0:
        raise ValueError(f"seed must be a non-negative integer or None, got {seed}")
    return int(seed)


def bump_any(bumps: np.ndarray) -> np.ndarray:
    """True per robot in contact with anything this step."""
    return bumps.reshape(len(bumps), N_BUMP_SECTORS).any(axis=1)
