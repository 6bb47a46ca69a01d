"""The motion model: the velocities a platform's wheels deliver for commanded ones (per-wheel gains drawn per
robot, per-step noise, a dead zone, wheel speed limits; docs/design.md#motion-error), in m/s and rad/s, and its
random side for the copies of the batched core (:class:`MotionError`: each copy's own stream of draws and its
robots' wheel gains). The core applies the error before :func:`swarm_envs.sim.world.step_worlds`, so a world
steps, and logs for its exact copies, the delivered velocities; a world stepped directly moves as commanded."""

from __future__ import annotations

import numpy as np

from swarm_envs.sim.copies import CopyStream
from swarm_envs.sim.platforms import Platform

__all__ = ["wheel_gains", "motion_error", "wheel_limited", "MotionError"]


def wheel_gains(platform: Platform, draws: np.ndarray) -> np.ndarray:
    """(..., 2) per-wheel speed gains (left, right) of robots for an episode, ``max(1 + wheel_gain_std z, 0)``
    from standard normal ``draws`` z (..., 2): the calibration error of the motion-error model
    (:func:`motion_error`)."""
    return np.maximum(1.0 + platform.wheel_gain_std * np.asarray(draws, dtype=float), 0.0)


def motion_error(platform: Platform, linear: np.ndarray, angular: np.ndarray, gains: np.ndarray, draws: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The linear (m/s) and angular (rad/s) velocities (n,) the wheels deliver for the commanded ``linear``
    and ``angular`` (n,) under the platform's motion error (``docs/design.md#motion-error``).

    Each wheel's commanded speed u (``v -+ w b / 2``, limited to ``max_speed``) does not turn the wheel
    below ``min_wheel_speed`` (gear-train friction, a dead zone [L Sec. 3.1]); otherwise the wheel turns at
    ``u g max(1 + wheel_noise_std z, 0)``, limited to ``max_speed``, with ``gains`` g (n, 2) the robot's
    per-wheel gains of the episode (:func:`wheel_gains`) and ``draws`` z (n, 2) standard normal draws of this
    control step (left, right). Unequal gains make a robot told to drive straight drive an arc (heading
    drift); the noise is slip and speed jitter. A wheel commanded to stand still stands still."""
    half = 0.5 * platform.wheel_base
    vmax = platform.max_speed
    wheels = np.stack([linear - angular * half, linear + angular * half], axis=-1)
    np.clip(wheels, -vmax, vmax, out=wheels)
    if platform.min_wheel_speed > 0:
        wheels[np.abs(wheels) < platform.min_wheel_speed] = 0.0
    wheels *= gains * np.maximum(1.0 + platform.wheel_noise_std * draws, 0.0)
    np.clip(wheels, -vmax, vmax, out=wheels)
    left, right = wheels[:, 0], wheels[:, 1]
    return 0.5 * (left + right), (right - left) / (2 * half)


def wheel_limited(platform: Platform, linear: np.ndarray, angular: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Commanded (v m/s, w rad/s) clipped so neither wheel of ``platform`` exceeds its max speed."""
    half_base = 0.5 * platform.wheel_base
    vmax = platform.max_speed
    left = np.clip(linear - angular * half_base, -vmax, vmax)
    right = np.clip(linear + angular * half_base, -vmax, vmax)
    return 0.5 * (left + right), (right - left) / (2 * half_base)


class MotionError:
    """The motion error of ``n_copies`` copies of ``n_world`` robots of ``platform`` (copy ``b``'s robots are
    rows ``b * n_world`` to ``(b + 1) * n_world - 1``).

    Each copy draws from its own stream of standard normal numbers (:class:`swarm_envs.sim.copies.CopyStream`):
    its robots' wheel gains at the episode start (:meth:`start`), then two draws per robot every step the
    copy moves (:meth:`apply`), whatever the commands, so a copy's draws never depend on another copy's.
    """

    def __init__(self, platform: Platform, n_copies: int, n_world: int) -> None:
        self.platform = platform
        self.n_world = int(n_world)
        self.stream = CopyStream([np.random.default_rng() for _ in range(n_copies)], "normal", chunk=max(2048, 64 * self.n_world))
        #: (n_copies * n_world, 2) every robot's per-wheel gains (left, right) of its episode
        self.gains = np.ones((n_copies * self.n_world, 2))

    def start(self, copy: int, generator: np.random.Generator) -> None:
        """Begin copy ``copy``'s episode: its stream draws from ``generator`` from now on, and its robots'
        wheel gains are drawn from it."""
        self.stream.set_generator(int(copy), generator)
        own = slice(int(copy) * self.n_world, (int(copy) + 1) * self.n_world)
        self.gains[own] = wheel_gains(self.platform, self.stream.draw(np.full(self.n_world, copy), (2,)))

    def apply(self, rows: np.ndarray, row_copy: np.ndarray, linear: np.ndarray, angular: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The velocities (m/s, rad/s) the wheels deliver for the commanded ``linear`` and ``angular`` (k,) of
        the robots ``rows`` (indices or a boolean mask over all copies' robots; their copies ``row_copy`` (k,),
        ascending), with two draws per robot from its copy's stream (:func:`motion_error`)."""
        draws = self.stream.draw(row_copy, (2,))
        return motion_error(self.platform, linear, angular, self.gains[rows], draws)
