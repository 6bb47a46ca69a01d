"""The sub-steps of many pymunk spaces in one compiled loop: chipmunk's C functions called from numba.

:func:`swarm_envs.sim.world.step_worlds` writes each space's control bodies, runs its sub-steps and reads
its bodies back. The sub-steps are the costly part (chipmunk's solver) and consist of short C calls:
per sub-step ``cpSpaceStep`` (a few microseconds for ten robots) and ``cpSpaceEachCachedArbiter`` with
pymunk.batch's arbiter reader, and before the first and the second sub-step one
``cpConstraintSetMaxForce`` per motor joint (:meth:`swarm_envs.sim.world.World._run_substeps`).
Called from Python, each call takes and releases the GIL, so threads stepping different spaces wait on
each other between calls. :func:`substep_spaces` makes exactly the same C calls, in the same order, for a
range of spaces from compiled code that holds no GIL, so the spaces step in parallel on threads and the
result is the same bit for bit.

The C functions come from pymunk's own compiled module (``pymunk._chipmunk_cffi``) as ctypes function
pointers, passed to the kernel as arguments (their addresses are read at run time, so the kernel's
on-disk cache holds none). Pointers travel as unsigned integers (``size_t``, the width of a pointer).
:data:`CHIPMUNK` is None when pymunk's layout differs; the world then uses pymunk's Python wrappers.
"""

from __future__ import annotations

import ctypes
from typing import Any, NamedTuple

import numpy as np

from swarm_envs._compile._numba import njit

__all__ = ["ChipmunkCalls", "CHIPMUNK", "address", "substep_spaces"]


class ChipmunkCalls(NamedTuple):
    """chipmunk's functions used by the sub-steps, as ctypes function pointers taking pointers as
    ``size_t``, and the address of pymunk.batch's arbiter iterator (the callback of ``each_arbiter``)."""

    step: Any  #: cpSpaceStep(space, dt)
    each_arbiter: Any  #: cpSpaceEachCachedArbiter(space, callback, data)
    set_max_force: Any  #: cpConstraintSetMaxForce(constraint, force)
    read_arbiter: int  #: pmSpaceArbiterIteratorFuncBatched


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
        function("cpConstraintSetMaxForce", size_t, ctypes.c_double),
        address(_ffi.addressof(_lib, "pmSpaceArbiterIteratorFuncBatched")),
    )


try:
    from pymunk._chipmunk_cffi import ffi as _ffi
    from pymunk._chipmunk_cffi import lib as _lib

    #: chipmunk's functions for :func:`substep_spaces` (None: another pymunk layout)
    CHIPMUNK: ChipmunkCalls | None = _chipmunk_calls()
except (ImportError, AttributeError):  # pragma: no cover - another pymunk layout
    CHIPMUNK = None


@njit(cache=True)
def substep_spaces(
    step: Any,
    each_arbiter: Any,
    set_max_force: Any,
    read_arbiter: int,
    spaces: np.ndarray,
    readers: np.ndarray,
    joint_start: np.ndarray,
    joints: np.ndarray,
    first_force: np.ndarray,
    push_force: np.ndarray,
    h: float,
    substeps: int,
    lo: int,
    hi: int,
) -> None:
    """The sub-steps of spaces ``lo..hi-1``: space ``i`` (address ``spaces[i]``) gets its motor joints
    ``joints[joint_start[i]:joint_start[i + 1]]`` bounded to ``first_force[i]`` (N), one step of ``h`` s
    followed by a read of its cached arbiters into ``readers[i]`` (a ``pmBatchedData *``), then the joints
    bounded to ``push_force[i]`` and ``substeps - 1`` more such steps: the calls of
    :meth:`swarm_envs.sim.world.World._run_substeps`."""
    for i in range(lo, hi):
        space = spaces[i]
        for j in range(joint_start[i], joint_start[i + 1]):
            set_max_force(joints[j], first_force[i])
        step(space, h)
        each_arbiter(space, read_arbiter, readers[i])
        if substeps > 1:
            for j in range(joint_start[i], joint_start[i + 1]):
                set_max_force(joints[j], push_force[i])
            for _ in range(substeps - 1):
                step(space, h)
                each_arbiter(space, read_arbiter, readers[i])
