"""The sub-steps of many pymunk spaces in one compiled loop: chipmunk's C functions called from numba.

:func:`swarm_envs.sim.world.step_worlds` gives each space its control velocities, runs its sub-steps and reads
its bodies back. The sub-steps are the costly part (chipmunk's solver) and consist of short C calls:
per sub-step two ``cpSpaceEachBody`` with pymunk.batch's body getter and setter (the bodies' velocities
read, the motors' forces written, :func:`motor_forces`), ``cpSpaceStep`` and ``cpSpaceEachCachedArbiter``
with pymunk.batch's arbiter reader (:meth:`swarm_envs.sim.world.World._run_substeps`).
Called from Python, each call takes and releases the GIL, so threads stepping different spaces wait on
each other between calls. :func:`substep_spaces` makes exactly the same C calls, in the same order, for a
range of spaces from compiled code that holds no GIL, so the spaces step in parallel on threads and the
result is the same bit for bit.

pymunk.batch's float arrays are read and written in place through their addresses (:data:`FLOAT_ARRAY_DATA`).
The C functions come from pymunk's own compiled module (``pymunk._chipmunk_cffi``) as ctypes function
pointers, passed to the kernel as arguments (their addresses are read at run time, so the kernel's
on-disk cache holds none). Pointers travel as unsigned integers (``size_t``, the width of a pointer).
:data:`CHIPMUNK` is None when pymunk's layout differs; the world then uses pymunk's Python wrappers.
"""

from __future__ import annotations

import ctypes
from typing import Any, NamedTuple

import numpy as np

from llvmlite import ir
from numba import carray, types
from numba.core.extending import intrinsic

from swarm_envs._compile._numba import njit

__all__ = ["ChipmunkCalls", "CHIPMUNK", "FLOAT_ARRAY_DATA", "address", "contact_rows", "motor_forces", "substep_spaces"]


class ChipmunkCalls(NamedTuple):
    """chipmunk's functions used by the sub-steps, as ctypes function pointers taking pointers as
    ``size_t``, and the address of pymunk.batch's arbiter iterator (the callback of ``each_arbiter``)."""

    step: Any  #: cpSpaceStep(space, dt)
    each_arbiter: Any  #: cpSpaceEachCachedArbiter(space, callback, data)
    each_body: Any  #: cpSpaceEachBody(space, callback, data)
    read_arbiter: int  #: pmSpaceArbiterIteratorFuncBatched
    get_body: int  #: pmSpaceBodyGetIteratorFuncBatched
    set_body: int  #: pmSpaceBodySetIteratorFuncBatched


def address(pointer: Any) -> int:
    """The address of a cffi pointer (a ``cpSpace *``, ``cpConstraint *``, ``pmBatchedData *``, ...)."""
    return int(_ffi.cast("uintptr_t", pointer))


def _chipmunk_calls() -> ChipmunkCalls | None:
    size_t = ctypes.c_size_t

    def function(name: str, *arguments: Any) -> Any:
        return ctypes.CFUNCTYPE(None, *arguments)(address(_ffi.addressof(_lib, name)))

    return ChipmunkCalls(
        function("cpSpaceStep", size_t, ctypes.c_double),
        function("cpSpaceEachCachedArbiter", size_t, size_t, size_t),
        function("cpSpaceEachBody", size_t, size_t, size_t),
        address(_ffi.addressof(_lib, "pmSpaceArbiterIteratorFuncBatched")),
        address(_ffi.addressof(_lib, "pmSpaceBodyGetIteratorFuncBatched")),
        address(_ffi.addressof(_lib, "pmSpaceBodySetIteratorFuncBatched")),
    )


try:
    from pymunk._chipmunk_cffi import ffi as _ffi
    from pymunk._chipmunk_cffi import lib as _lib

    #: chipmunk's functions for :func:`substep_spaces` (None: another pymunk layout)
    CHIPMUNK: ChipmunkCalls | None = _chipmunk_calls()
    #: byte offset of the data pointer in pymunk.batch's ``pmFloatArray {int num, max; cpFloat *arr;}`` (and
    #: ``pmIntArray``, the same with ``uintptr_t *arr``)
    FLOAT_ARRAY_DATA = int(_ffi.offsetof("pmFloatArray", "arr"))
    _same_layout = _ffi.offsetof("pmIntArray", "num") == 0 and _ffi.offsetof("pmIntArray", "arr") == FLOAT_ARRAY_DATA
    if _ffi.offsetof("pmFloatArray", "num") != 0 or _ffi.sizeof("int") != 4 or not _same_layout:  # pragma: no cover
        CHIPMUNK = None
except (ImportError, AttributeError):  # pragma: no cover - another pymunk layout
    CHIPMUNK = None
    FLOAT_ARRAY_DATA = 8


@intrinsic
def _pointer(typingctx, address):  # an address (a 64-bit integer) as a void pointer
    if not isinstance(address, types.Integer) or address.bitwidth != 64:
        return None

    def codegen(context, builder, signature, args):
        return builder.inttoptr(args[0], ir.IntType(8).as_pointer())

    return types.voidptr(address), codegen


@njit(cache=True)
def _clear(address: int) -> None:
    """Set the count of the pmFloatArray at ``address`` to 0 (as ``pymunk.batch.Buffer.clear``: a getter
    then appends from the start of its C array, a setter pops from there)."""
    carray(_pointer(address), 1, np.int32)[0] = 0


@njit(cache=True)
def _floats(address: int, size: int) -> np.ndarray:
    """The first ``size`` floats of the pmFloatArray at ``address`` (a view of its C array)."""
    data = carray(_pointer(address + FLOAT_ARRAY_DATA), 1, np.uintp)[0]
    return carray(_pointer(data), size, np.float64)


@njit(cache=True)
def _count(address: int) -> int:
    """The count of the pmFloatArray or pmIntArray at ``address`` (its first field, an int)."""
    return carray(_pointer(address), 1, np.int32)[0]


@njit(cache=True)
def _words(address: int, size: int) -> np.ndarray:
    """The first ``size`` values of the pmIntArray at ``address`` (``uintptr_t``; a view of its C array)."""
    data = carray(_pointer(address + FLOAT_ARRAY_DATA), 1, np.uintp)[0]
    return carray(_pointer(data), size, np.uintp)


@njit(cache=True)
def contact_rows(contacts: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The contacts the sub-steps of several spaces appended (:func:`swarm_envs.sim.world._substeps`), read from
    each space's contacts arrays (``contacts[i]``: the ``pmIntArray *`` and ``pmFloatArray *``), space after
    space: per cached arbiter its ints (body a id, body b id, contact count) (A, 3) and its normal (A, 2),
    the rows ``np.frombuffer`` of each buffer's ``int_buf()`` and ``float_buf()`` gives, concatenated. The
    ints are the ``uintptr_t`` words' bits in an int64 array (``.view(np.uintp)`` reads them as they are)."""
    total = 0
    for i in range(contacts.shape[0]):
        total += _count(contacts[i, 0]) // 3
    ints = np.empty((total, 3), np.int64)
    normals = np.empty((total, 2), np.float64)
    row = 0
    for i in range(contacts.shape[0]):
        m = _count(contacts[i, 0]) // 3
        words, floats = _words(contacts[i, 0], 3 * m), _floats(contacts[i, 1], 2 * m)
        for k in range(m):
            for c in range(3):
                ints[row + k, c] = words[3 * k + c]
            normals[row + k, 0] = floats[2 * k]
            normals[row + k, 1] = floats[2 * k + 1]
        row += m
    return ints, normals


@njit(cache=True)
def motor_forces(control: np.ndarray, motion: np.ndarray, out: np.ndarray, mass: float, moment: float, h: float, force: float, torque: float) -> None:
    """The motors' force and torque on each robot for the next sub-step of ``h`` s: the velocity change a
    motor bounded to ``force`` (N) and ``torque`` (N m) makes alone within one sub-step towards the robot's
    control velocity, as a force chipmunk applies in its velocity integration (after moving the bodies,
    before solving contacts). ``control`` (n, 3) the control (vx, vy, omega) m/s, rad/s; ``motion`` the
    bodies' (vx, vy, omega) rows, flat (robots first); ``out`` gets the (fx, fy, torque) rows, flat."""
    cap = force * h / mass
    cap_w = torque * h / moment
    for j in range(control.shape[0]):
        dvx = control[j, 0] - motion[3 * j]
        dvy = control[j, 1] - motion[3 * j + 1]
        dw = control[j, 2] - motion[3 * j + 2]
        norm2 = dvx * dvx + dvy * dvy
        if norm2 > cap * cap:
            scale = cap / np.sqrt(norm2)
            dvx *= scale
            dvy *= scale
        dw = min(max(dw, -cap_w), cap_w)
        out[3 * j] = dvx * mass / h
        out[3 * j + 1] = dvy * mass / h
        out[3 * j + 2] = dw * moment / h


@njit(cache=True)
def substep_spaces(
    step: Any,
    each_arbiter: Any,
    each_body: Any,
    read_arbiter: int,
    get_body: int,
    set_body: int,
    spaces: np.ndarray,
    readers: np.ndarray,
    motors: np.ndarray,
    reads: np.ndarray,
    contacts: np.ndarray,
    rows: np.ndarray,
    control: np.ndarray,
    read: np.ndarray,
    first_force: np.ndarray,
    push_force: np.ndarray,
    torque: np.ndarray,
    mass: float,
    moment: float,
    h: float,
    substeps: int,
    lo: int,
    hi: int,
) -> None:
    """The sub-steps of spaces ``lo..hi-1``, each of ``h`` s: before each, space ``i`` (address
    ``spaces[i]``) reads its bodies' velocities with pymunk.batch's getter (``motors[i, 0]`` its
    ``pmBatchedData *``, ``motors[i, 1]`` that one's ``pmFloatArray *``), gets the :func:`motor_forces`
    towards ``control[rows[i, 0]:rows[i, 1]]`` (bounded to ``first_force[i]`` N in the first sub-step,
    ``push_force[i]`` after, ``torque[i]`` N m) written with the setter (``motors[i, 2:4]``); then one
    ``cpSpaceStep`` and a read of its cached arbiters into ``readers[i]`` (a ``pmBatchedData *``): the calls
    of :meth:`swarm_envs.sim.world.World._run_substeps`. Before the sub-steps the contacts' arrays (the
    ``pmIntArray *`` and ``pmFloatArray *`` ``contacts[i]``) are emptied, as ``Buffer.clear``; after them every
    body's (x, y, angle, vx, vy, omega) is read with the getter (``reads[i, 0]`` the ``pmBatchedData *``,
    ``reads[i, 1]`` its ``pmFloatArray *``) and its robots' rows copied into ``read[rows[i, 0]:rows[i, 1]]``
    (n, 6): the calls of :meth:`swarm_envs.sim.world.World._advance`."""
    for i in range(lo, hi):
        space = spaces[i]
        n = rows[i, 1] - rows[i, 0]
        target = control[rows[i, 0] : rows[i, 1]]
        _clear(contacts[i, 0])
        _clear(contacts[i, 1])
        for k in range(substeps):
            _clear(motors[i, 1])
            each_body(space, get_body, motors[i, 0])
            forces = _floats(motors[i, 3], 3 * n)
            motor_forces(target, _floats(motors[i, 1], 3 * n), forces, mass, moment, h, first_force[i] if k == 0 else push_force[i], torque[i])
            _clear(motors[i, 3])
            each_body(space, set_body, motors[i, 2])
            step(space, h)
            each_arbiter(space, read_arbiter, readers[i])
        _clear(reads[i, 1])
        each_body(space, get_body, reads[i, 0])
        bodies = _floats(reads[i, 1], 6 * n)
        for j in range(n):
            for c in range(6):
                read[rows[i, 0] + j, c] = bodies[6 * j + c]
