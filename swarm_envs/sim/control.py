"""The control step and what happens in it: :data:`DT` (s), how many physics sub-steps it takes (a robot
closes at most a set fraction of a diameter per sub-step) and the force and torque the motors may use
(N, N m)."""

from __future__ import annotations

import math

import pymunk
import pymunk.batch

from swarm_envs.sim.platforms import Platform

__all__ = ["DT", "DEFAULT_CLOSING", "MIN_DEFAULT_SUBSTEPS", "MAX_CLOSING", "MAX_SUBSTEPS", "MOTOR_MARGIN", "closing_per_substep", "default_substeps", "min_substeps", "motor_limits", "push_force"]

#: s, one control step of the envs = the Droplet R&B update rate [F14 Sec. V]; the physics defaults are sized for it
DT = 0.1

#: fraction of a diameter two robots driving head-on at full speed close per sub-step at the default count
DEFAULT_CLOSING = 0.0175

#: the fewest sub-steps a platform gets by default
MIN_DEFAULT_SUBSTEPS = 8

#: fraction of a diameter two robots may close per sub-step at most (any ``physics_substeps``): with more,
#: crushes of hundreds of robots overlap by half a diameter (:data:`swarm_envs.sim.world.PLACEMENT_OVERLAP`)
MAX_CLOSING = 0.05

#: sub-steps per control step at most (the ``physics_substeps`` setting's bound: cost grows linearly)
MAX_SUBSTEPS = 1000

#: motor force over the largest velocity change of one sub-step (:func:`motor_limits`)
MOTOR_MARGIN = 1.25


def closing_per_substep(platform: Platform, substeps: int) -> float:
    """Distance (m) two robots driving head-on at full speed close within one sub-step of the control step."""
    return 2.0 * platform.max_speed * DT / substeps


def default_substeps(platform: Platform) -> int:
    """The platform's default sub-steps per control step: the fewest (at least :data:`MIN_DEFAULT_SUBSTEPS`)
    at which two robots close at most :data:`DEFAULT_CLOSING` of a diameter per sub-step."""
    need = 2.0 * platform.max_speed * DT / (DEFAULT_CLOSING * platform.diameter)
    return max(MIN_DEFAULT_SUBSTEPS, math.ceil(need - 1e-9))


def min_substeps(platform: Platform) -> int:
    """The fewest sub-steps per control step the platform may use: two robots close at most
    :data:`MAX_CLOSING` of a diameter per sub-step, and at least 3 (the motors then keep every robot on its
    exact arc, :func:`motor_limits`)."""
    need = 2.0 * platform.max_speed * DT / (MAX_CLOSING * platform.diameter)
    return max(3, math.ceil(need - 1e-9))


def motor_limits(platform: Platform, substeps: int) -> tuple[float, float]:
    """The motors' largest force (N) and torque (N m) in the first sub-step of a control step, where the
    commanded velocity change is made (:func:`push_force` bounds the force after it): :data:`MOTOR_MARGIN`
    times the largest velocity change the control velocities of :mod:`swarm_envs.sim.world`'s docstring ask
    for within one sub-step, linear and angular.

    A control velocity is ``c = (D - h u) / (dt - h)`` with ``|D| <= v dt`` and ``u`` the previous one, so
    ``|c| <= v dt / (dt - 2 h)`` however the commands alternate, and a change ``c - u`` is at most twice
    that (3 or more sub-steps; with 2 the bound grows without limit, with 1 the motors act a step late)."""
    h = DT / substeps
    reach = 2.0 * DT / (DT - 2 * h) if substeps >= 3 else 2.0 * substeps
    moment = pymunk.moment_for_circle(platform.mass, 0.0, platform.radius)
    force = MOTOR_MARGIN * platform.mass * reach * platform.max_speed / h
    torque = MOTOR_MARGIN * moment * reach * platform.max_angular_speed / h
    return force, torque


def push_force(platform: Platform, substeps: int) -> float:
    """The motors' largest force (N) after the first sub-step of a control step (module docstring): the
    force of :func:`motor_limits` spread over the control step instead of one sub-step, ``force / substeps``,
    i.e. the same largest velocity change made within one control step. A free robot needs no force then;
    this bounds how hard a robot pushes against robots and walls."""
    force, _ = motor_limits(platform, substeps)
    return force / substeps
