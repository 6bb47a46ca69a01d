"""Physics: disc robots with velocity-controlled differential drive in a walled arena (pymunk).

One :class:`pymunk.Space` per world, robots as dynamic circles, arena walls as static segments.
Each control step (``dt`` = 0.1 s) is split into physics sub-steps. Every robot has a *control velocity*
(vx, vy, omega) per step, and its motors drive it there with bounded force and torque: before each
sub-step the robot gets the force and torque that change its velocity towards the control velocity by at
most force x h / mass (torque x h / moment) within the sub-step (:func:`swarm_envs.sim.substep_kernel.motor_forces`),
which chipmunk applies in its velocity integration, after moving the bodies and before solving the
contacts. Contacts, which have unbounded force, win over the motors: robots push each other and walls
hold; bump sensing reads the contacts pymunk's solver processed in each sub-step (the contacts its
post-solve collision callbacks would report, see :func:`_substeps`).

Contacts and sub-steps. pymunk finds a contact only once two discs overlap, so two robots driving
head-on at full speed overlap by up to the distance they close within one sub-step before their contact
stops them (and chains of pushing robots add a little). :func:`swarm_envs.sim.control.default_substeps` therefore sizes the
sub-step to the platform: the smallest count (at least 8) at which two robots close at most
:data:`swarm_envs.sim.control.DEFAULT_CLOSING` (1.75 %) of a diameter per sub-step -- 8 for the Droplet, 21 for the e-puck, 32
for the r-one -- which keeps every overlap and every wall penetration within :data:`MAX_OVERLAP` (2 %) of
a diameter (``benchmarks/physics_substeps.py`` measures the worst case over dense crushes,
``benchmarks/contacts_hostile.py`` over 600 steps of full-speed driving into each other and the walls).
The env settings refuse fewer sub-steps than :func:`swarm_envs.sim.control.min_substeps` (robots closing more than
:data:`swarm_envs.sim.control.MAX_CLOSING` of a diameter per sub-step).

Motor force. A robot's velocity changes only when a command arrives, once per control step: the motors
make that change within the first sub-step, with the force of :func:`swarm_envs.sim.control.motor_limits` (the largest change a
command can ask for, within one sub-step, with a 25 % margin), and a free robot needs no force for the
rest of the step (the model has no rolling friction or drag). Only a robot pushing against another robot
or a wall keeps its motors working after the first sub-step, and there they push with at most
:func:`swarm_envs.sim.control.push_force`, the same velocity change made over the whole control step: 0.53 N for the e-puck,
2.4 N for the r-one, 0.02 N for the Droplet, each less than the robot's weight and so within what its
wheels (or legs) can transmit to the floor (at most friction coefficient x weight). The first sub-step's
force held throughout would be 11 N for the e-puck and 77 N for the r-one, 7 and 26 times their weight:
no wheel transmits that, and a pile of robots pressed with it is pushed through itself faster than the
solver's iterations (which carry a push one contact further per iteration) and the contact correction
push it apart, up to 10 % of a diameter of overlap in a corner. Contacts between frictionless discs act
through the discs' centres and exert no torque, so the motors' torque keeps its first sub-step bound.

A placement (:meth:`World.check_placement`) may overlap as deep as :data:`PLACEMENT_OVERLAP`, far beyond
what the physics produces, so a state read back from ``infos`` is always accepted by ``reset(options=...)``.

The control velocities are set once per control step: translation along the chord of the differential-drive
arc, ``D = v dt sinc(w dt / 2)`` towards ``heading + w dt / 2``, and rotation at ``w``. pymunk moves a
body with its previous velocity during the first sub-step (the motors' force acts after that move), so the
control velocities are set to ``(D - h u) / (dt - h)`` and ``(w dt - h omega) / (dt - h)`` (h the
sub-step, u / omega the body's velocity at the step start): a free robot then ends every control step
exactly on its differential-drive arc.

Motion error: :func:`swarm_envs.sim.motion.motion_error` turns commanded velocities into the ones a platform's wheels deliver
(per-wheel gains, per-step noise, a dead zone; ``docs/design.md#motion-error``). The batched core applies it
before :func:`step_worlds`, so a world steps, and logs for its exact copies, the delivered velocities; a
world stepped directly moves exactly as commanded.

:func:`step_worlds` steps several worlds (e.g. the copies of the batched core) at once: the control
arithmetic runs as one numpy program over all their robots, and each space is written and read with one
``pymunk.batch`` call (no Python loop over bodies), and its contacts are read with one C call per sub-step
(no Python work per contact). The sub-steps themselves (chipmunk's calls) run in compiled code without the
GIL (:mod:`swarm_envs.sim.substep_kernel`), so the spaces step on threads, in contiguous shares of the
worlds that each thread takes as it frees up, with the same result bit for bit; :meth:`World.step` is the
same function for one world.
"""

from __future__ import annotations

import threading
import warnings
from collections.abc import Sequence

import numpy as np
import pymunk
import pymunk.batch
from scipy.spatial import cKDTree

from swarm_envs._compile._worker import run_chunks
from swarm_envs.sim.arena import (
    Arena,
    as_real_array,
    check_obstacles,
    distance_to_segments,
)
from swarm_envs.sim.control import (
    MAX_SUBSTEPS,
    default_substeps,
    motor_limits,
    push_force,
)
from swarm_envs.sim.geometry import wrap_angle
from swarm_envs.sim.motion import wheel_limited
from swarm_envs.sim.platforms import Platform
from swarm_envs.sim.substep_kernel import CHIPMUNK, address, contact_rows, motor_forces, substep_spaces

__all__ = ["World", "step_worlds", "physics_threads", "N_BUMP_SECTORS"]

#: bytes of commands a world keeps per episode for exact copies (16 per robot and step; 64 MB = 400,000
#: steps of 10 robots); a longer episode's copy falls back to pymunk's copy of the space
COPY_LOG_BYTES = 64 << 20
N_BUMP_SECTORS = 8  # bump sensor: one flag per 45-degree sector of the body (sector 0 centred ahead)
_ROBOT, _WALL = 1, 2
#: fraction of a diameter robots overlap (or enter a wall) at most at the default sub-steps and densities
MAX_OVERLAP = 0.02
#: fraction of a diameter two robots of a placement (``reset(options=...)``) may overlap: a deeper overlap
#: (centres closer than one radius) is a mistake, such as two robots on one spot. The physics itself
#: stays far below it: <= 2 % at the default sub-steps and densities (``benchmarks/physics_substeps.py``,
#: ``benchmarks/contacts_hostile.py``), 2-3 % in a full-speed crush of 1,500 robots covering 60 % of the
#: arena, 6-18 % in such a crush of 400 robots at the fewest sub-steps (the Droplet's 3 the deepest)
PLACEMENT_OVERLAP = 0.5
#: fraction of a diameter a robot of a placement may reach past a wall (its centre stays half a radius inside)
PLACEMENT_WALL_DEPTH = 0.25
#: pymunk solver iterations per sub-step (contacts)
SOLVER_ITERATIONS = 10
#: worlds per physics thread at least (:func:`physics_threads`): fewer do not repay a thread hand-off
THREADED_MIN_WORLDS = 8
#: shares of the worlds per physics thread (:func:`step_worlds`): a thread that finishes its share takes the
#: next one, so the threads stay busy when one of them shares its core with the worker thread
SHARES_PER_THREAD = 4
#: fraction of an overlap left after one second of contact correction: 30 % of it is removed every 1/60 s
#: (pymunk's default removes 10 %), which keeps chains of robots pushed together within :data:`MAX_OVERLAP`
COLLISION_BIAS = (1.0 - 0.3) ** 60
# pymunk.batch fields: every body's (x, y, angle, vx, vy, omega) read in one call per space; before each
# sub-step the (vx, vy, omega) read and the motors' (fx, fy, torque) written in one call each; a space's
# bodies come in insertion order (the robots, then the walls' static body)
_READ = pymunk.batch.BodyFields.POSITION | pymunk.batch.BodyFields.ANGLE | pymunk.batch.BodyFields.VELOCITY | pymunk.batch.BodyFields.ANGULAR_VELOCITY
_MOTION = pymunk.batch.BodyFields.VELOCITY | pymunk.batch.BodyFields.ANGULAR_VELOCITY
_WRITE = pymunk.batch.BodyFields.FORCE | pymunk.batch.BodyFields.TORQUE
# contacts: per cached arbiter, the two bodies' ids and its contact count (ints) and normal (floats)
_CONTACT_FIELDS = (
    pymunk.batch.ArbiterFields.BODY_A_ID
    | pymunk.batch.ArbiterFields.BODY_B_ID
    | pymunk.batch.ArbiterFields.CONTACT_COUNT
    | pymunk.batch.ArbiterFields.NORMAL
)
try:  # chipmunk's step and pymunk.batch's C iterators, called directly (pymunk's wrappers add bookkeeping)
    from pymunk._chipmunk_cffi import ffi as _ffi
    from pymunk._chipmunk_cffi import lib as _chipmunk

    _READ_ARBITER = _ffi.addressof(_chipmunk, "pmSpaceArbiterIteratorFuncBatched")
    _GET_BODY = _ffi.addressof(_chipmunk, "pmSpaceBodyGetIteratorFuncBatched")
    _SET_BODY = _ffi.addressof(_chipmunk, "pmSpaceBodySetIteratorFuncBatched")
except (ImportError, AttributeError):  # pragma: no cover - another pymunk layout: the public API is used
    _ffi = _chipmunk = _READ_ARBITER = _GET_BODY = _SET_BODY = None


class World:
    """The physical swarm: ``n`` robots of one platform in one arena, stepped by pymunk.

    State arrays (world frame, SI): ``positions (n, 2)``, ``headings (n,)``, ``velocities (n, 2)``,
    ``angular_velocities (n,)``, and ``bumps (n, N_BUMP_SECTORS)`` for the last control step.
    """

    def __init__(self, platform: Platform, n_robots: int, arena: Arena, substeps: int | None = None, obstacles: np.ndarray | None = None) -> None:
        substeps = default_substeps(platform) if substeps is None else substeps
        if not 1 <= substeps <= MAX_SUBSTEPS:
            raise ValueError(f"physics substeps must be in [1, {MAX_SUBSTEPS}], got {substeps}")
        self.platform = platform
        self.n = int(n_robots)
        self.arena = arena
        #: static obstacle segments (S, 2, 2) m inside the arena, walls like the arena's own
        self.obstacles = np.zeros((0, 2, 2)) if obstacles is None else check_obstacles(obstacles, arena)
        self.substeps = int(substeps)
        self._build_space()
        self.positions = np.zeros((self.n, 2))
        self.headings = np.zeros(self.n)
        self.velocities = np.zeros((self.n, 2))
        self.angular_velocities = np.zeros(self.n)
        self.bumps = np.zeros((self.n, N_BUMP_SECTORS), dtype=bool)
        self._body_motion = np.zeros((self.n, 3))  # pymunk body (vx, vy, omega) after the last step
        self._episode_start: tuple[np.ndarray, np.ndarray] | None = None  # set by place()
        self._commands: list[tuple[np.ndarray, np.ndarray, float]] | None = []
        self._command_bytes = 0

    def _build_space(self, positions: np.ndarray | None = None, headings: np.ndarray | None = None) -> None:
        """A new pymunk space with the walls and every robot at rest at ``positions`` (n, 2) m with
        ``headings`` (n,) rad (default: apart on a row, as pymunk's bounding-box tree needs; robots stacked on
        one spot make every insertion and removal cost O(n)): no contact, arbiter or solver cache from an
        earlier episode survives (a reused world behaves like a fresh one)."""
        platform, arena = self.platform, self.arena
        if positions is None:
            positions = np.stack([3.0 * platform.radius * np.arange(self.n), np.zeros(self.n)], axis=1)
            headings = np.zeros(self.n)
        self.space = pymunk.Space()
        self.space.gravity = (0.0, 0.0)
        self.space.collision_slop = 1e-4  # m: allowed interpenetration before the solver pushes apart
        self.space.iterations = SOLVER_ITERATIONS
        self.space.collision_bias = COLLISION_BIAS
        self.bodies: list[pymunk.Body] = []
        moment = pymunk.moment_for_circle(platform.mass, 0.0, platform.radius)
        for p, h in zip(positions.tolist(), headings.tolist()):
            body = pymunk.Body(platform.mass, moment)
            body.position, body.angle = p, h
            shape = pymunk.Circle(body, platform.radius)
            shape.friction = 0.0
            shape.elasticity = 0.0
            shape.collision_type = _ROBOT
            self.space.add(body, shape)
            self.bodies.append(body)
        for a, b in np.concatenate([arena.wall_segments(), self.obstacles]):
            wall = pymunk.Segment(self.space.static_body, tuple(a), tuple(b), 0.0)
            wall.friction = 0.0
            wall.elasticity = 0.0
            wall.collision_type = _WALL
            self.space.add(wall)
        self._make_buffers()

    def _make_buffers(self) -> None:
        """The pymunk.batch buffers over the space's bodies (C memory: rebuilt, never copied)."""
        # contacts of the sub-steps of a control step, appended by _substeps (see there)
        self._robot_ids = np.array([body.id for body in self.bodies], dtype=np.uintp)
        self._contacts = pymunk.batch.Buffer()
        # the motors' force bounds of the first and of the later sub-steps and their torque bound (_run_substeps)
        force, torque = motor_limits(self.platform, self.substeps)
        self._motor_forces = (force, push_force(self.platform, self.substeps), torque)
        self._inertia = (self.platform.mass, pymunk.moment_for_circle(self.platform.mass, 0.0, self.platform.radius))
        self._control = np.zeros((self.n, 3))  # the control velocities of the current step (step_worlds)
        # batch buffers: the step's read of every body, and the motors' read and write before each sub-step
        ids = pymunk.batch.Buffer()
        pymunk.batch.get_space_bodies(self.space, pymunk.batch.BodyFields.BODY_ID, ids)
        order = [body.id for body in self.bodies] + [self.space.static_body.id]
        if np.frombuffer(ids.int_buf(), dtype=np.uintp).tolist() != order:  # pragma: no cover - pymunk changed
            raise RuntimeError("pymunk.batch does not list the bodies in insertion order")
        self._read_buffer = pymunk.batch.Buffer()
        self._motion_buffer = pymunk.batch.Buffer()  # bodies' (vx, vy, omega) rows (C memory, grown once here)
        pymunk.batch.get_space_bodies(self.space, _MOTION, self._motion_buffer)
        self._write_values = np.zeros(len(order) * 3)  # motors' (fx, fy, torque) rows; the static body's stay 0
        self._write_buffer = pymunk.batch.Buffer()
        self._write_buffer.set_float_buf(self._write_values)
        # the same C iterators as pymunk.batch's get/set_space_bodies and get_space_arbiters, each with one
        # pmBatchedData made here instead of one per call (None: another pymunk layout, public API used)
        self._batched = None
        if _ffi is not None:
            self._batched = tuple(
                _batched_data(buffer, fields)
                for buffer, fields in ((self._write_buffer, _WRITE), (self._read_buffer, _READ), (self._contacts, _CONTACT_FIELDS), (self._motion_buffer, _MOTION))
            )
        self._read_ptr = None  # the read buffer's C array when _read_rows was made
        # the addresses substep_spaces needs: the space, the contacts' pmBatchedData, the motors' read and
        # write (each a pmBatchedData and its pmFloatArray), the step's read of the bodies (the same), and the
        # contacts' pmIntArray and pmFloatArray
        self._native = None
        if CHIPMUNK is not None and self._batched is not None:
            self._native = (
                address(self.space._space),
                address(self._batched[2]),
                (
                    address(self._batched[3]),
                    address(self._motion_buffer._float_arr),
                    address(self._batched[0]),
                    address(self._write_buffer._float_arr),
                ),
                (address(self._batched[1]), address(self._read_buffer._float_arr)),
                (address(self._contacts._int_arr), address(self._contacts._float_arr)),
            )

    # -- copies (copy.deepcopy, pickle) ----------------------------------------------------------------
    # pymunk can pickle a space, but a restored space does not step on bit for bit: chipmunk's contact
    # impulses and its collision index are not part of pymunk's state. A copy therefore rebuilds the space
    # and replays the episode's physics from its placement with the logged commands (physics only: the
    # sensing and task state are copied as they are), which is exact because the physics is deterministic.
    _NOT_COPIED = ("space", "bodies", "_robot_ids", "_contacts", "_read_buffer", "_write_values", "_motion_buffer",
                   "_write_buffer", "_batched", "_read_ptr", "_read_rows", "_motor_forces", "_inertia", "_control", "_native")

    def __getstate__(self) -> dict:
        state = {k: v for k, v in self.__dict__.items() if k not in self._NOT_COPIED}
        if self._commands is None:  # the log outgrew its bound: pymunk's own copy of the space (not exact)
            warnings.warn(
                f"copying a world whose episode log exceeded {COPY_LOG_BYTES >> 20} MB: the copy's physics is "
                "pymunk's copy of the space and may drift from the original by rounding",
                RuntimeWarning,
                stacklevel=2,
            )
            state["_space_copy"] = (self.space, self.bodies)
        return state

    def __setstate__(self, state: dict) -> None:
        space_copy = state.pop("_space_copy", None)
        self.__dict__.update(state)
        if space_copy is not None:
            self.space, self.bodies = space_copy
            self._make_buffers()
            return
        self._build_space()
        if self._episode_start is None:
            return
        final = {k: getattr(self, k) for k in ("positions", "headings", "velocities", "angular_velocities", "bumps", "_body_motion")}
        commands, n_bytes = self._commands, self._command_bytes
        self.place(*self._episode_start)
        for linear, angular, dt in commands:
            step_worlds([self], linear, angular, dt)
        if not (np.array_equal(self.positions, final["positions"]) and np.array_equal(self._body_motion, final["_body_motion"])):
            raise RuntimeError("replaying the episode's physics did not reproduce the copied world")  # pragma: no cover
        self._commands, self._command_bytes = commands, n_bytes
        for key, value in final.items():
            setattr(self, key, value)

    # -- state -----------------------------------------------------------------------------------
    def check_placement(self, positions: np.ndarray, headings: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """``positions`` (n, 2) m and ``headings`` (n,) rad as float arrays; raises ``ValueError`` when they
        have the wrong shape, are not finite, reach past the walls by more than :data:`PLACEMENT_WALL_DEPTH`
        or overlap each other by more than :data:`PLACEMENT_OVERLAP` of a diameter (far more than the physics
        produces, so any state the world reached is accepted). Changes nothing."""
        positions = as_real_array(positions, "positions")
        headings = as_real_array(headings, "headings")
        if positions.shape != (self.n, 2) or headings.shape != (self.n,):
            raise ValueError(
                f"positions must have shape ({self.n}, 2) and headings ({self.n},); "
                f"got {positions.shape} and {headings.shape}"
            )
        if not (np.all(np.isfinite(positions)) and np.all(np.isfinite(headings))):
            raise ValueError("positions and headings must be finite")
        d = self.platform.diameter
        outside = np.flatnonzero(self.arena.wall_depth(positions, self.platform.radius) > PLACEMENT_WALL_DEPTH * d)
        if len(outside):
            raise ValueError(
                f"robots {outside[:10].tolist()} are outside the {self.arena.shape} arena of size {self.arena.size} m "
                f"(robot radius {self.platform.radius} m; a robot may reach at most {PLACEMENT_WALL_DEPTH:.0%} of its diameter past a wall)"
            )
        overlap = cKDTree(positions).query_pairs((1.0 - PLACEMENT_OVERLAP) * d, output_type="ndarray")
        if len(overlap):
            raise ValueError(
                f"robots overlap: pairs {overlap[:5].tolist()} overlap by more than {PLACEMENT_OVERLAP:.0%} of a "
                f"diameter ({d} m; their centres are closer than {(1.0 - PLACEMENT_OVERLAP) * d:.4g} m)"
            )
        # as the arena walls: a robot pressed against a wall may reach into it as deep as the physics lets it
        on_obstacle = np.flatnonzero(distance_to_segments(positions, self.obstacles) < self.platform.radius - PLACEMENT_WALL_DEPTH * d)
        if len(on_obstacle):
            raise ValueError(f"robots {on_obstacle[:5].tolist()} reach more than {PLACEMENT_WALL_DEPTH:.0%} of their diameter into an obstacle wall")
        return positions, headings

    def place(self, positions: np.ndarray, headings: np.ndarray) -> None:
        """Put robots exactly at ``positions`` (n, 2) m with ``headings`` (n,) rad, at rest, in a new
        physics space (nothing of the previous episode survives). Raises like :meth:`check_placement`."""
        positions, headings = self.check_placement(positions, headings)
        self.space = None  # the previous episode's space is freed before the new one is built
        self._build_space(positions, headings)
        self.positions = positions.copy()
        self.headings = wrap_angle(headings)
        self.velocities = np.zeros((self.n, 2))
        self.angular_velocities = np.zeros(self.n)
        self.bumps = np.zeros((self.n, N_BUMP_SECTORS), dtype=bool)
        self._body_motion = np.zeros((self.n, 3))
        # the episode so far, for exact copies (see __getstate__): the placement and every step's commands
        self._episode_start = (positions.copy(), headings.copy())
        self._commands: list[tuple[np.ndarray, np.ndarray, float]] | None = []
        self._command_bytes = 0

    def _record(self, linear: np.ndarray, angular: np.ndarray, dt: float) -> None:
        """Append one step's commands (m/s, rad/s, s) to the episode's log, while it stays under
        :data:`COPY_LOG_BYTES`; past that the log is dropped and copies are no longer exact."""
        if self._commands is None:
            return
        self._command_bytes += linear.nbytes + angular.nbytes
        if self._command_bytes > COPY_LOG_BYTES:
            self._commands = None
            return
        self._commands.append((linear.copy(), angular.copy(), dt))

    def _apply_motors(self, h: float, force: float) -> None:
        """Set every robot's motor force and torque for the next sub-step of ``h`` s (:func:`motor_forces`
        towards its control velocity, the force bounded to ``force`` N): the bodies' velocities read and the
        forces written with one C call each (the public pymunk.batch API with another pymunk layout)."""
        mass, moment = self._inertia
        torque = self._motor_forces[2]
        if self._batched is None:
            self._motion_buffer.clear()
            pymunk.batch.get_space_bodies(self.space, _MOTION, self._motion_buffer)
            motion = np.frombuffer(self._motion_buffer.float_buf(), dtype=np.float64)
            motor_forces(self._control, motion, self._write_values, mass, moment, h, force, torque)
            pymunk.batch.set_space_bodies(self.space, _WRITE, self._write_buffer)
            return
        read, write, handle = self._batched[3], self._batched[0], self.space._space
        read.floatArray.num = 0  # as Buffer.clear
        _chipmunk.cpSpaceEachBody(handle, _GET_BODY, read)
        motion = np.frombuffer(self._motion_buffer.float_buf(), dtype=np.float64)
        motor_forces(self._control, motion, self._write_values, mass, moment, h, force, torque)
        write.floatArray.num = 0  # as pymunk.batch.set_space_bodies: the setter pops values from the start
        _chipmunk.cpSpaceEachBody(handle, _SET_BODY, write)
        write.floatArray.num = len(self._write_values)

    def _run_substeps(self, h: float, reader: object | None) -> None:
        """The sub-steps of ``h`` seconds, each after :meth:`_apply_motors`: the first with the motors' full
        force, which makes the commanded velocity change, the others with :func:`push_force`, which bounds
        how hard a robot pushes (module docstring). A free robot moves the same under both bounds."""
        full, push, _ = self._motor_forces
        for k in range(self.substeps):
            self._apply_motors(h, full if k == 0 else push)
            _substeps(self.space, h, 1, self._contacts, reader)

    def _write_control(self, control: np.ndarray) -> None:
        """Empty the contacts and keep the control (vx, vy, omega) rows ``control`` (n, 3) for the motors."""
        self._contacts.clear()
        self._control[:] = control

    def _read_motion(self) -> np.ndarray:
        """Every robot body's (x, y, angle, vx, vy, omega) (n, 6) with one C call (the known pymunk layout; a
        view of the read buffer, valid until the next step)."""
        read = self._batched[1]
        read.floatArray.num = 0  # as Buffer.clear
        _chipmunk.cpSpaceEachBody(self.space._space, _GET_BODY, read)
        if read.floatArray.arr != self._read_ptr:  # the first read, or the C array moved: a new view
            self._read_ptr = read.floatArray.arr
            self._read_rows = np.frombuffer(self._read_buffer.float_buf(), dtype=np.float64)[: 6 * self.n].reshape(self.n, 6)
        return self._read_rows

    def _advance(self, control: np.ndarray, h: float) -> np.ndarray:
        """Keep the control (vx, vy, omega) rows ``control`` (n, 3), run the sub-steps of ``h``
        seconds from Python, and return every robot body's (x, y, angle, vx, vy, omega) (n, 6) from pymunk
        (a view of the read buffer, valid until the next step)."""
        if self._batched is None:  # another pymunk layout: the public API
            self._write_control(control)
            self._run_substeps(h, None)
            self._read_buffer.clear()
            pymunk.batch.get_space_bodies(self.space, _READ, self._read_buffer)
            return np.frombuffer(self._read_buffer.float_buf(), dtype=np.float64)[: 6 * self.n].reshape(self.n, 6)
        self._write_control(control)
        self._run_substeps(h, self._batched[2])
        return self._read_motion()

    # -- dynamics --------------------------------------------------------------------------------
    def wheel_limited(self, linear: np.ndarray, angular: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Clip commanded (v m/s, w rad/s) so neither wheel exceeds the platform's max speed."""
        return wheel_limited(self.platform, linear, angular)

    def step(self, linear: np.ndarray, angular: np.ndarray, dt: float) -> None:
        """Advance ``dt`` seconds with commanded linear (m/s) and angular (rad/s) velocities (n,)."""
        step_worlds([self], linear, angular, dt)


def physics_threads(n_worlds: int) -> int:
    """Threads :func:`step_worlds` steps ``n_worlds`` spaces on: numba's thread count (the process's thread
    setting, ``NUMBA_NUM_THREADS``), at most one per :data:`THREADED_MIN_WORLDS` worlds, and 1 off the main
    Python thread (envs stepped from other threads stay on their thread)."""
    if n_worlds < 2 * THREADED_MIN_WORLDS or threading.current_thread() is not threading.main_thread():
        return 1
    import numba

    return max(1, min(int(numba.get_num_threads()), n_worlds // THREADED_MIN_WORLDS))


def step_worlds(worlds: Sequence[World], linear: np.ndarray, angular: np.ndarray, dt: float, threads: int | None = None) -> None:
    """Advance every world of ``worlds`` (one platform and sub-step count) by ``dt`` seconds.

    ``linear`` (m/s) and ``angular`` (rad/s) are the commanded velocities of all their robots, world after
    world (sum of ``n``,). The control arithmetic is one numpy program over all robots (element-wise, so
    each world's numbers are those it would get alone); each space then takes one ``pymunk.batch`` write,
    its sub-steps, and one read. Updates each world's state arrays and bump flags.

    The spaces are stepped on ``threads`` threads (default :func:`physics_threads`) in contiguous shares of
    the worlds (up to :data:`SHARES_PER_THREAD` per thread, each thread taking the next share when it
    finishes one), their sub-steps by :func:`swarm_envs.sim.substep_kernel.substep_spaces` (compiled, without
    the GIL; a space is touched by one thread only): the result is the same bit for bit for any thread count.
    """
    if not worlds:
        return
    first = worlds[0]
    platform, substeps = first.platform, first.substeps
    if any(w.platform is not platform or w.substeps != substeps for w in worlds):
        raise ValueError("step_worlds needs worlds of one platform and one sub-step count")
    linear, angular = np.asarray(linear, float).reshape(-1), np.asarray(angular, float).reshape(-1)
    sizes = [w.n for w in worlds]
    bounds = np.concatenate([[0], np.cumsum(sizes)])
    spans = list(zip(bounds[:-1].tolist(), bounds[1:].tolist()))  # each world's rows (Python ints: cheaper slicing)
    for w, (a, b) in zip(worlds, spans):
        w._record(linear[a:b], angular[a:b], dt)
    linear, angular = first.wheel_limited(linear, angular)
    if linear.shape[0] != bounds[-1]:
        raise ValueError(f"expected {bounds[-1]} commands (the worlds' robots), got {linear.shape[0]}")
    single = len(worlds) == 1
    headings = first.headings if single else np.concatenate([w.headings for w in worlds])
    before_pos = first.positions if single else np.concatenate([w.positions for w in worlds])
    h = dt / substeps
    # chord of the differential-drive arc over the control step (module docstring)
    half = 0.5 * angular * dt
    chord = linear * dt * np.sinc(half / np.pi)
    mid = headings + half
    if substeps > 1:
        body = first._body_motion if single else np.concatenate([w._body_motion for w in worlds])
        control = np.stack(
            [
                (chord * np.cos(mid) - h * body[:, 0]) / (dt - h),
                (chord * np.sin(mid) - h * body[:, 1]) / (dt - h),
                (angular * dt - h * body[:, 2]) / (dt - h),
            ],
            axis=1,
        )
    else:  # one sub-step: the motors act only from the next step on
        control = np.stack([chord * np.cos(mid) / dt, chord * np.sin(mid) / dt, angular], axis=1)
    read = np.empty((bounds[-1], 6))

    chunks = physics_threads(len(worlds)) if threads is None else max(1, min(int(threads), len(worlds)))
    # the sub-steps compiled, without the GIL (substep_kernel), for every world that allows it (not the first
    # step of a space, whose new bodies pymunk's Space.step checks first); the Python calls for the others
    batch = _native_batch(worlds)
    if batch is None:
        ready, rest = [], list(range(len(worlds)))
    else:
        native = [_plain_space(w.space) for w in worlds]
        ready = [i for i, ok in enumerate(native) if ok]
        rest = [i for i, ok in enumerate(native) if not ok]
    if ready:
        _substep_native(worlds, batch, ready, bounds, control, read, h, substeps, chunks)

    def advance(k: int) -> None:  # the k-th contiguous share of the other worlds
        for i in rest[len(rest) * k // chunks : len(rest) * (k + 1) // chunks]:
            read[bounds[i] : bounds[i + 1]] = worlds[i]._advance(control[bounds[i] : bounds[i + 1]], h)

    if rest:
        run_chunks(advance, min(chunks, len(rest)))
    positions = read[:, 0:2].copy()
    new_headings = wrap_angle(read[:, 2])
    # velocity = motion actually achieved over the control step (pushes and walls included)
    velocities = (positions - before_pos) / dt
    angular_velocities = wrap_angle(new_headings - headings) / dt
    bumps = _bump_flags(worlds, bounds, new_headings, batch)
    motion = read[:, 3:6].copy()
    for w, (a, b) in zip(worlds, spans):
        w.positions, w.headings = positions[a:b], new_headings[a:b]
        w.velocities, w.angular_velocities = velocities[a:b], angular_velocities[a:b]
        w.bumps, w._body_motion = bumps[a:b], motion[a:b]


class _NativeBatch:
    """What :func:`substep_spaces` and :func:`contact_rows` read of a list of worlds (the ``_native`` addresses
    of :meth:`World._make_buffers` as arrays, the motors' bounds) and the worlds' robot body ids sorted with
    their rows: built once for a list of worlds and kept while every world keeps its space."""

    def __init__(self, worlds: Sequence[World], natives: list[tuple]) -> None:
        self.natives = natives  # held, so that no other tuple can take their ids (the cache key)
        self.spaces = np.array([nat[0] for nat in natives], dtype=np.uintp)
        self.readers = np.array([nat[1] for nat in natives], dtype=np.uintp)
        self.motors = np.array([nat[2] for nat in natives], dtype=np.uintp).reshape(-1, 4)
        self.reads = np.array([nat[3] for nat in natives], dtype=np.uintp).reshape(-1, 2)
        self.contacts = np.array([nat[4] for nat in natives], dtype=np.uintp).reshape(-1, 2)
        self.first_force = np.array([w._motor_forces[0] for w in worlds], dtype=float)
        self.push = np.array([w._motor_forces[1] for w in worlds], dtype=float)
        self.torque = np.array([w._motor_forces[2] for w in worlds], dtype=float)
        self.inertia = worlds[0]._inertia
        ids = np.concatenate([w._robot_ids for w in worlds])  # body ids are unique among live bodies
        order = np.argsort(ids)
        self.sorted_ids, self.id_rows = ids[order], order  # robot rows of the worlds, world after world


_NATIVE_BATCHES: dict[tuple[int, ...], _NativeBatch] = {}
_NATIVE_BATCHES_KEPT = 8
_NATIVE_BATCHES_LOCK = threading.Lock()  # envs may step on several threads


def _native_batch(worlds: Sequence[World]) -> _NativeBatch | None:
    """The :class:`_NativeBatch` of ``worlds`` (cached by the identity of their ``_native`` tuples, which a
    world replaces with each new space), or None when a world has no native addresses (another pymunk
    layout, or pymunk.batch's internals unavailable)."""
    natives = [w._native if w._batched is not None else None for w in worlds]
    if any(nat is None for nat in natives):
        return None
    key = tuple(map(id, natives))
    with _NATIVE_BATCHES_LOCK:
        batch = _NATIVE_BATCHES.get(key)
        if batch is None:
            if len(_NATIVE_BATCHES) >= _NATIVE_BATCHES_KEPT:  # the oldest goes
                _NATIVE_BATCHES.pop(next(iter(_NATIVE_BATCHES)))
            batch = _NATIVE_BATCHES[key] = _NativeBatch(worlds, natives)
    return batch


def _substep_native(worlds: Sequence[World], batch: _NativeBatch, ready: list[int], bounds: np.ndarray, control: np.ndarray, read: np.ndarray,
                    h: float, substeps: int, threads: int) -> None:
    """:func:`step_worlds`'s contacts emptied, sub-steps and read of the worlds ``ready`` of ``worlds`` (each
    with a space :func:`_plain_space` allows; ``batch`` their :class:`_NativeBatch`; world ``i``'s robots are
    rows ``bounds[i]:bounds[i + 1]`` of ``control`` and ``read``), by
    :func:`swarm_envs.sim.substep_kernel.substep_spaces` (no GIL), contiguous shares of the worlds on
    ``threads`` threads (up to :data:`SHARES_PER_THREAD` shares per thread, taken as threads free up)."""
    idx = np.asarray(ready, dtype=np.int64)
    every = idx.shape[0] == len(worlds)
    pick = (lambda a: a) if every else (lambda a: a[idx])
    spaces, readers, motors, reads, contacts = (pick(a) for a in (batch.spaces, batch.readers, batch.motors, batch.reads, batch.contacts))
    first_force, push, torque = pick(batch.first_force), pick(batch.push), pick(batch.torque)
    row_bounds = np.stack([bounds[:-1], bounds[1:]], axis=1).astype(np.int64)[idx]
    mass, moment = batch.inertia
    control = np.ascontiguousarray(control)
    n = idx.shape[0]
    threads = max(1, min(threads, n))
    shares = threads if threads == 1 else max(threads, min(n // THREADED_MIN_WORLDS, threads * SHARES_PER_THREAD))

    def share(k: int) -> None:
        substep_spaces(*CHIPMUNK, spaces, readers, motors, reads, contacts, row_bounds, control, read, first_force, push, torque, mass, moment, h,
                       substeps, n * k // shares, n * (k + 1) // shares)

    stepping = worlds if every else [worlds[i] for i in ready]
    for w in stepping:  # as Space.step: no pymunk call may change a space while it steps
        w.space._locked = True
    try:
        run_chunks(share, shares, threads)
    finally:
        for w in stepping:
            w.space._locked = False


def _batched_data(buffer: pymunk.batch.Buffer, fields: pymunk.batch.BodyFields | pymunk.batch.ArbiterFields) -> object:
    """A cffi ``pmBatchedData`` over ``buffer``'s arrays for ``fields``, as pymunk.batch makes per call."""
    data = _ffi.new("pmBatchedData *")
    data.fields = fields.value
    data.floatArray = buffer._float_arr
    data.intArray = buffer._int_arr
    return data


def _plain_space(space: pymunk.Space) -> bool:
    """Whether ``space`` has none of the bookkeeping ``Space.step`` wraps around ``cpSpaceStep`` (bodies
    added or removed from callbacks, post-step callbacks, the threaded solver), so chipmunk's step can be
    called directly; False with another pymunk layout."""
    try:
        return not (space._bodies_to_check or space._add_later or space._remove_later or space._post_step_callbacks or space.threaded)
    except AttributeError:  # pragma: no cover - pymunk internals changed
        return False


def _substeps(space: pymunk.Space, h: float, count: int, contacts: pymunk.batch.Buffer, reader: object | None) -> None:
    """``count`` pymunk steps of ``h`` seconds; after each, the contacts the step processed are appended to
    ``contacts``: per arbiter the ints (body a id, body b id, contact count) and the floats (normal x, y).

    Contacts: chipmunk keeps every arbiter touched in the last ``space.collision_persistence`` steps in the
    space's cached-arbiter set (``cpSpaceArbiterSetFilter``); one touched in the step just taken has its
    contacts and normal of this step, while an older one is marked cached, for which ``cpArbiterGetCount``
    returns 0. Reading the set after every step and keeping the rows with a contact count > 0 (done by
    :func:`_bump_flags`) therefore gives exactly the arbiters the step's solver processed, the ones its
    post-solve collision callbacks would report, with the same normals, and never an earlier step's
    (whatever the persistence and sub-step count). One C call per step, no Python work per contact.

    ``Space.step`` wraps chipmunk's ``cpSpaceStep`` in bookkeeping for bodies added or removed from
    callbacks and for post-step callbacks, none of which this module uses; when that bookkeeping is empty
    the space is locked once (as ``Space.step`` does) and ``cpSpaceStep`` and the arbiter iteration (with
    ``reader``, a ``pmBatchedData`` over ``contacts``) are called directly. Otherwise (or with another
    pymunk layout) ``Space.step`` and ``pymunk.batch.get_space_arbiters`` are used: the same chipmunk calls.
    """
    if reader is None or not _plain_space(space):
        for _ in range(count):
            space.step(h)
            pymunk.batch.get_space_arbiters(space, _CONTACT_FIELDS, contacts)
        return
    handle = space._space
    step, each_arbiter = _chipmunk.cpSpaceStep, _chipmunk.cpSpaceEachCachedArbiter
    space._locked = True
    try:
        for _ in range(count):
            step(handle, h)
            each_arbiter(handle, _READ_ARBITER, reader)
    finally:
        space._locked = False


def _bump_flags(worlds: Sequence[World], bounds: np.ndarray, headings: np.ndarray, batch: _NativeBatch | None = None) -> np.ndarray:
    """(sum n, N_BUMP_SECTORS) contact flags of the last control step from the worlds' contacts.

    Each contact of a sub-step (an arbiter with a contact count > 0, see :func:`_substeps`) flags, for
    each of its two bodies that is a robot, the sector of the contact normal seen from that robot (the
    normal points from body a to body b) relative to the robot's heading at the end of the step.
    ``batch``: the worlds' :class:`_NativeBatch`, whose addresses read every world's contacts in one call
    (:func:`contact_rows`); None: each world's buffers are read from Python.
    """
    bumps = np.zeros((bounds[-1], N_BUMP_SECTORS), dtype=bool)
    if batch is not None:
        arbiters, normals = contact_rows(batch.contacts)
        if arbiters.shape[0] == 0:
            return bumps
        return _flag_sectors(bumps, arbiters.view(np.uintp), normals, batch.sorted_ids, batch.id_rows, headings)
    ints, floats, ids, starts, sizes = [], [], [], [], []
    for w, a in zip(worlds, bounds[:-1]):
        if w._contacts._int_arr.num:  # the world had contacts
            ints.append(w._contacts.int_buf())
            floats.append(w._contacts.float_buf())
            ids.append(w._robot_ids)
            starts.append(a)
            sizes.append(w.n)
    if not ints:
        return bumps
    arbiters = np.frombuffer(b"".join(ints), dtype=np.uintp).reshape(-1, 3)
    normals = np.frombuffer(b"".join(floats), dtype=np.float64).reshape(-1, 2)
    # body ids (unique among live bodies) -> robot rows
    ids, sizes = np.concatenate(ids), np.array(sizes)
    rows = np.arange(len(ids)) + np.repeat(np.array(starts) - (np.cumsum(sizes) - sizes), sizes)
    order = np.argsort(ids)
    return _flag_sectors(bumps, arbiters, normals, ids[order], rows[order], headings)


def _flag_sectors(bumps: np.ndarray, arbiters: np.ndarray, normals: np.ndarray, ids: np.ndarray, rows: np.ndarray, headings: np.ndarray) -> np.ndarray:
    """:func:`_bump_flags` of the arbiters (A, 3) (body a id, body b id, contact count) with their normals
    (A, 2), set in ``bumps`` (returned): ``ids`` robot body ids sorted, ``rows`` their rows of ``bumps``."""
    touching = arbiters[:, 2] > 0
    arbiters, normals = arbiters[touching], normals[touching]
    # the walls' static body is no robot
    bodies = arbiters[:, :2].ravel()  # a, b, a, b, ...: body a sees the normal, body b its opposite
    pos = np.minimum(np.searchsorted(ids, bodies), len(ids) - 1)
    robot = ids[pos] == bodies
    idx = rows[pos[robot]]
    normal = (normals[:, None, :] * np.array([[1.0], [-1.0]])).reshape(-1, 2)[robot]
    world_angle = np.arctan2(normal[:, 1], normal[:, 0])
    body_angle = wrap_angle(world_angle - headings[idx])
    sector = np.floor((body_angle + np.pi / N_BUMP_SECTORS) / (2 * np.pi / N_BUMP_SECTORS)).astype(int)
    bumps[idx, sector % N_BUMP_SECTORS] = True
    return bumps
