"""The batched simulation core: ``B`` independent copies of one task stepped as one array program.

Every per-step array covers all ``B x n_world`` robots (robot ``b * n_world + i`` is robot ``i`` of copy
``b``). Data flows one way each control step (``DT`` = 0.1 s): the commands through the platform's motion error
(:class:`swarm_envs.sim.motion.MotionError`, ``motion_noise``) -> physics (one pymunk ``Space`` per copy,
:func:`swarm_envs.sim.world.step_worlds`) -> sensing stack over all robots at once (IR links, range & bearing, SwarmCom,
bearing exchange, scale-free coordinates; no link, message or random draw crosses copies) -> observation
arrays -> rewards (the task, on ``(B, ...)`` views).

Thin views sit on top: :class:`swarm_envs.adapters.env.SwarmEnv` (a PettingZoo ``ParallelEnv``) is the core with
``B = 1``; :func:`swarm_envs.make_vec` (:mod:`swarm_envs.adapters.vector`) exposes ``B`` copies as arrays. Because each copy draws from
its own generators in the order a single env would, copy ``b`` seeded with ``s`` reproduces a single env
seeded with ``s`` bit for bit.

Episode starts: a copy is (re)started by :meth:`SwarmCore.start` before a sensing step; that step is the
copy's reset step (its first observation), while the other copies take an ordinary step. So resetting
one copy never advances or re-draws anything of another.
"""

from __future__ import annotations

from collections.abc import Sequence
from concurrent.futures import Future
from typing import Any, NamedTuple

import numpy as np

from swarm_envs.tasks._task_checks import RewardsCheck, checked_mask, checked_spawn
from swarm_envs._compile._worker import worker
from swarm_envs.sensing.observation import ObservationLayout, assemble_observation
from swarm_envs.sensing.base import SensorFrame
from swarm_envs.sensing.stacks import build_stack
from swarm_envs.tasks.task import BatchState, Task
from swarm_envs.sim.world import N_BUMP_SECTORS, World, step_worlds
from swarm_envs.sim.motion import MotionError
from swarm_envs.sim.control import DT

__all__ = ["SwarmCore", "DT"]


class _Command(NamedTuple):
    """What the act phase hands to physics and sensing (rows: all robots of all copies)."""

    act: np.ndarray  #: (n_total, action_size) actions after the switches, in [-1, 1]
    moving: np.ndarray  #: (B,) bool copies that move this step (not in their reset step)
    row_moving: np.ndarray  #: (n_total,) bool robots of the moving copies
    linear: np.ndarray  #: (moving robots,) commanded linear speed after motion error, m/s
    angular: np.ndarray  #: (moving robots,) commanded angular speed after motion error, rad/s
    payloads: np.ndarray | None  #: (n_total, message_bits) bool message bits, None without messages
    sending: np.ndarray | None  #: (n_total,) bool robots that queue their payload
    off: np.ndarray  #: (n_total,) bool robots switched off (Task.switched_off)
    emit_off: np.ndarray  #: (n_total,) bool transmitters off (Task.transmit_off)
    detect_off: np.ndarray  #: (n_total,) bool receivers off (Task.receive_off)


class SwarmCore:
    """``n_copies`` copies of ``task`` (module docstring).

    Args:
        task: the task (its config, platform, arena and robots); built for ``n_copies`` copies.
        layout: observation layout of one robot.
    """

    def __init__(self, task: Task, layout: ObservationLayout) -> None:
        cfg = task.config
        self.task = task
        self.layout = layout
        self.platform = task.platform
        self.B = task.n_copies
        self.n_world = task.n_world
        self.n_total = self.B * self.n_world
        self.copy_of_robot = np.repeat(np.arange(self.B), self.n_world)
        obstacles = task.obstacle_segments
        self.worlds = [World(self.platform, self.n_world, task.arena, substeps=cfg["physics_substeps"], obstacles=obstacles) for _ in range(self.B)]
        from swarm_envs._compile._first_run import prepare  # (not at import: ``python -m swarm_envs._compile._first_run`` runs it)

        prepare(type(task).__name__, self.platform.name, cfg["sensing"])  # a cold numba cache: the notice, a second core
        self.sensing = build_stack(cfg["sensing"], self.platform, self.n_world, cfg, self.B, obstacles)
        self.generators = [np.random.default_rng() for _ in range(self.B)]
        #: the motion error (``motion_noise``): each copy's stream of standard normal draws and the wheel gains
        self.motion_noise = bool(cfg["motion_noise"])
        self._motion = MotionError(self.platform, self.B, self.n_world) if self.motion_noise else None
        #: (n_total, 2) every robot's per-wheel gains of its episode (ones without motion error)
        self.wheel_gains = self._motion.gains if self._motion is not None else np.ones((self.n_total, 2))
        self.static = (np.arange(self.n_total) % self.n_world) < task.n_static
        self.last_actions = np.zeros((self.n_total, layout.action_size))
        self.num_cycles = np.zeros(self.B, dtype=np.int64)
        self.positions = np.zeros((self.n_total, 2))
        self.headings = np.zeros(self.n_total)
        self.velocities = np.zeros((self.n_total, 2))
        self.bumps = np.zeros((self.n_total, N_BUMP_SECTORS), dtype=bool)
        self.frame: SensorFrame | None = None
        self.rewards = np.zeros((self.B, task.n_agents))
        self.terms: dict[str, np.ndarray] = {}
        self.metrics: dict[str, np.ndarray] = {}
        #: checks (shapes, dtypes, finiteness, names) and casts every return of task.rewards to float64
        self._check_rewards = RewardsCheck(task)
        self._starting = np.zeros(self.B, dtype=bool)
        #: robots switched off in the last step (Task.switched_off), (n_total,) bool
        self.switched_off = np.zeros(self.n_total, dtype=bool)
        # the static robots' firmware (Task.static_messages): what they queue next, (n_total, b) bool
        self._firmware = type(task).static_messages is not Task.static_messages and task.n_static > 0 and layout.message_bits > 0
        self._static_payloads = np.zeros((self.n_total, layout.message_bits), dtype=bool)
        self._observation_cache: tuple[Any, dict[str, np.ndarray], dict[str, np.ndarray] | None] | None = None

    # -- episodes ------------------------------------------------------------------------------------
    def seed(self, copy: int, seed: int | None) -> None:
        """Re-seed copy ``copy``'s episode generator (``None``: keep its generator running)."""
        if seed is not None:
            self.generators[copy] = np.random.default_rng(seed)

    def start(self, copies: Sequence[int], poses: Sequence[tuple[np.ndarray | None, np.ndarray | None]] | None = None) -> None:
        """Begin new episodes in ``copies``: fresh physics and sensing state, robots spawned by the task or
        placed from ``poses[k] = (positions (n_world, 2) m or None, headings (n_world,) rad or None)``
        (checked by :func:`swarm_envs.adapters.views.check_reset_options`). Given positions skip the task's spawner
        (headings then come from the spawn stream unless given); given headings alone replace the spawned
        ones. The copies' first observation comes from the next :meth:`step` (which does not move them).
        """
        copies = np.asarray(copies, dtype=np.int64).reshape(-1)
        poses = list(poses) if poses is not None else [(None, None)] * len(copies)
        sensing_rngs = []
        for b, (given_positions, given_headings) in zip(copies, poses):
            # independent child streams: spawn, sensing (which splits it into noise, channel and MAC), motion error
            streams = np.random.SeedSequence(int(self.generators[b].integers(2**63))).spawn(3)
            spawn_rng, sensing_rng, motion_rng = (np.random.default_rng(s) for s in streams)
            if self._motion is not None:
                self._motion.start(b, motion_rng)
            if given_positions is None:
                positions, headings = checked_spawn(self.task, self.task.spawn(spawn_rng))
            else:
                positions, headings = given_positions, None
            if given_headings is not None:
                headings = given_headings
            elif headings is None:
                headings = spawn_rng.uniform(-np.pi, np.pi, self.n_world)
            try:
                self.worlds[b].place(positions, headings)  # a new physics space: nothing survives a reset
            except ValueError as err:  # overlapping robots or robots outside the walls
                if given_positions is not None:
                    raise
                raise ValueError(f"{type(self.task).__name__}.spawn(): {err}") from None
            sensing_rngs.append(sensing_rng)
        self.sensing.reset(copies, sensing_rngs)
        rows = np.flatnonzero(np.isin(self.copy_of_robot, copies))
        self.last_actions[rows] = 0.0
        self.num_cycles[copies] = 0
        self._starting[copies] = True

    # -- stepping ------------------------------------------------------------------------------------
    def step(self, actions: np.ndarray | None) -> None:
        """One control step of every copy, in the phases of the data flow: act (commands, payloads, switches,
        motion error) -> physics -> sense -> reward; the observation is built from the new frame when it is
        first read (:meth:`observations`).

        Copies started since the last step do not move: this step senses their initial state (their reset
        observation). The others apply ``actions`` (n_total, action_size), already checked and clipped to
        [-1, 1] (rows of static robots are ignored), through the platform's motion error (``motion_noise``).

        Thread plan (numba's thread count, ``NUMBA_NUM_THREADS``, default all cores): the copies' spaces
        step on threads (:func:`swarm_envs.sim.world.step_worlds`). In a large scene, one env or a batch
        (the sensing's last step said so), the part of the sensing step that reads nothing the physics
        changes (queueing messages, drawing the channel's random numbers) runs on the worker thread during
        the physics, the task's rewards (ground truth only) during the sensing, and inside the sensing the
        gain kernel in chunks and range & bearing beside SwarmCom. The compiled sub-steps and kernels release
        the GIL; the results are the same as in sequence, for any thread count.
        """
        starting = self._starting.copy()
        command = self._act(actions, starting)
        overlap = bool(getattr(self.sensing, "large_scene", False))
        prepared = self._physics(command, overlap)
        self._sense_and_reward(command, prepared, starting, overlap)
        self._starting[:] = False
        if self._firmware:
            self._run_firmware(starting)

    def _act(self, actions: np.ndarray | None, starting: np.ndarray) -> _Command:
        """The act phase: the step's wheel commands after switches and motion error, the message payloads and
        the infrared switches (``starting`` (B,) marks the copies whose reset step this is)."""
        moving = ~starting
        size = self.layout.action_size
        act = np.zeros((self.n_total, size)) if actions is None else np.asarray(actions, dtype=float).reshape(self.n_total, size)
        off = self._switched_off(np.where(starting, 0, self.num_cycles + 1))
        act = np.where((self.static | off)[:, None], 0.0, act)
        p = self.platform
        row_moving = moving[self.copy_of_robot]
        payloads = None
        if self.layout.message_bits:
            # static robots send what their firmware says (Task.static_messages), by default nothing
            payloads = np.where(self.static[:, None], self._static_payloads, act[:, 2:] > 0)
        emit_off, detect_off = self._switch_mask("transmit_off", starting), self._switch_mask("receive_off", starting)
        sending = row_moving & ~off & ~emit_off if payloads is not None else None
        linear, angular = act[row_moving, 0] * p.max_speed, act[row_moving, 1] * p.max_angular_speed
        if self._motion is not None and moving.any():  # two draws per robot of every moving copy, whatever its command
            linear, angular = self._motion.apply(row_moving, self.copy_of_robot[row_moving], linear, angular)
        return _Command(act, moving, row_moving, linear, angular, payloads, sending, off, emit_off, detect_off)

    def _physics(self, command: _Command, overlap: bool) -> Future | None:
        """The physics phase: the moving copies' worlds advance one control step and the ground truth is
        gathered. With ``overlap``, the sensing's preparation runs on the worker thread meanwhile; returns
        its future."""
        prepared = worker().submit(self.sensing.prepare_step, command.payloads, command.sending) if overlap else None
        try:
            step_worlds([self.worlds[b] for b in np.flatnonzero(command.moving)], command.linear, command.angular, DT)
        finally:  # never leave the worker running on the sensing's state
            if prepared is not None:
                prepared.exception()  # waits
        self.last_actions[command.row_moving] = command.act[command.row_moving]
        self._gather()
        self.num_cycles[command.moving] += 1
        return prepared

    def _sense_and_reward(self, command: _Command, prepared: Future | None, starting: np.ndarray, overlap: bool) -> None:
        """The sense phase (a new :class:`SensorFrame` from the sensing stack) and the reward phase (the task
        on the ground truth), the rewards on the worker thread during the sensing with ``overlap``."""
        state = self.state()
        rewards = worker().submit(self.task.rewards, state, starting) if overlap else None
        silent = command.off if command.off.any() else None
        switches = {
            "emit_off": command.emit_off if command.emit_off.any() else None,
            "detect_off": command.detect_off if command.detect_off.any() else None,
        }
        try:
            if prepared is None:
                self.frame = self.sensing.step(self.positions, self.headings, command.payloads, command.sending, silent=silent, **switches)
            else:
                self.frame = self.sensing.step(self.positions, self.headings, prepared=prepared.result(), silent=silent, **switches)
        finally:  # never leave the worker running on the task's state
            if rewards is not None:
                rewards.exception()  # waits
        self.rewards, self.terms, self.metrics = self._check_rewards(self.task.rewards(state, starting) if rewards is None else rewards.result())

    def _switched_off(self, cycles: np.ndarray) -> np.ndarray:
        """(n_total,) bool robots the task switches off during the step ``cycles`` (B,) (Task.switched_off)."""
        mask = self.task.switched_off(cycles)
        if mask is None:
            self.switched_off = np.zeros(self.n_total, dtype=bool)
        else:
            mask = checked_mask(self.task, "switched_off", mask, (self.B, self.n_world), "(copies, world robots)")
            self.switched_off = mask.reshape(-1).copy()
        return self.switched_off

    def _switch_mask(self, hook: str, starting: np.ndarray) -> np.ndarray:
        """(n_total,) bool robots whose infrared ``hook`` (``Task.transmit_off`` or ``Task.receive_off``)
        switches off during the coming step; ``starting`` (B,) marks the reset steps."""
        if getattr(type(self.task), hook) is getattr(Task, hook):
            return np.zeros(self.n_total, dtype=bool)
        mask = getattr(self.task, hook)(np.where(starting, 0, self.num_cycles + 1))
        if mask is None:
            return np.zeros(self.n_total, dtype=bool)
        return checked_mask(self.task, hook, mask, (self.B, self.n_world), "(copies, world robots)").reshape(-1).copy()

    def _run_firmware(self, first: np.ndarray) -> None:
        """The static robots' payloads for the next step, from their observation of this one."""
        parts, ids = self._observation_parts()
        B, n_static, b = self.B, self.task.n_static, self.layout.message_bits
        rows = self.static
        obs = {k: v[rows].reshape(B, n_static, *v.shape[1:]) for k, v in {**parts, **ids}.items()}
        bits = self.task.static_messages(obs, first)
        if bits is None:
            self._static_payloads[:] = False
            return
        bits = checked_mask(self.task, "static_messages", bits, (B, n_static, b), "(copies, static robots, message bits)")
        self._static_payloads[rows] = bits.reshape(B * n_static, b)

    def _gather(self) -> None:
        w = self.worlds
        self.positions = np.concatenate([x.positions for x in w]) if self.B > 1 else w[0].positions
        self.headings = np.concatenate([x.headings for x in w]) if self.B > 1 else w[0].headings
        self.velocities = np.concatenate([x.velocities for x in w]) if self.B > 1 else w[0].velocities
        self.bumps = np.concatenate([x.bumps for x in w]) if self.B > 1 else w[0].bumps

    def state(self) -> BatchState:
        """Ground truth of all copies as (B, n_world, ...) arrays."""
        B, n = self.B, self.n_world
        return BatchState(
            self.positions.reshape(B, n, 2),
            self.headings.reshape(B, n),
            self.velocities.reshape(B, n, 2),
            self.bumps.reshape(B, n, N_BUMP_SECTORS),
            self.num_cycles.copy(),
        )

    # -- observations ---------------------------------------------------------------------------------
    def observations(self) -> dict[str, np.ndarray]:
        """Observation parts of every robot (leading axis = robot of all copies), from the last frame."""
        return self._observation_parts()[0]

    def _observation_parts(self) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
        """(the layout's parts, the id parts (built when the layout or the static firmware reads them)) of the
        last frame, built once per frame."""
        cache = self._observation_cache
        if cache is not None and cache[0] is self.frame:
            return cache[1], cache[2]
        with_ids = self.layout.observe_ids or self._firmware
        parts, ids = assemble_observation(self.frame, self.layout, self.bumps, self.last_actions, self.n_world, with_ids)
        self._observation_cache = (self.frame, parts, ids)
        return parts, ids

    def agent_rows(self) -> np.ndarray:
        """(B, n_agents) row index of every agent of every copy."""
        return np.arange(self.B)[:, None] * self.n_world + self.task.agent_robots[None, :]

