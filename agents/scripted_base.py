"""What the scripted controllers share: :class:`ScriptedPolicy` (per-robot state over a batch, the turn-to-a-bearing
step, odometry of the own rotation), circular means of bearings, the bump direction and the decoded ids of
observation rows."""

from __future__ import annotations
import numpy as np
from swarm_envs.agents.base import Policy
from swarm_envs.adapters.env import DT
from swarm_envs.sim.geometry import wrap_angle
from swarm_envs.sensing.observation import ObservationLayout
from swarm_envs.sim.platforms import Platform
from swarm_envs.sim.world import N_BUMP_SECTORS

__all__ = ["circular_mean", "wrap_below_pi", "bump_direction", "ScriptedPolicy", "decoded_ids", "require_ids"]


_SECTOR_ANGLES = np.arange(N_BUMP_SECTORS) * (2 * np.pi / N_BUMP_SECTORS)  # sector i centred at 45 i deg (body frame)


def circular_mean(cos: np.ndarray, sin: np.ndarray, valid: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Angle (rad) of the mean of the valid unit vectors per row ``(N, K) -> (N,)``, and a has-any mask.

    Rows with no valid entry (or a zero resultant) get angle 0 and ``False``.
    """
    w = valid.astype(np.float64)
    c, s = (cos * w).sum(axis=1), (sin * w).sum(axis=1)
    has = (w.sum(axis=1) > 0) & (np.hypot(c, s) > 1e-9)
    return np.where(has, np.arctan2(s, c), 0.0), has


def wrap_below_pi(angle: np.ndarray) -> np.ndarray:
    """Angles (rad) wrapped to [-pi, pi), the mirror of :func:`swarm_envs.sim.geometry.wrap_angle`'s (-pi, pi],
    bit for bit ``mod(angle + pi, 2 pi) - pi``: the baselines turn clockwise (by -pi) away from a bump dead
    ahead and read a bearing of exactly pi as -pi, as their recorded results do."""
    return -wrap_angle(-np.asarray(angle, dtype=float)) + 0.0  # + 0.0: a zero comes out as +0.0


def bump_direction(proprio: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Body-frame direction (rad) of the bumped sectors per robot, and whether any sector is bumped."""
    bumps = proprio[:, :N_BUMP_SECTORS] > 0.5
    return circular_mean(np.cos(_SECTOR_ANGLES)[None], np.sin(_SECTOR_ANGLES)[None], bumps)


class ScriptedPolicy(Policy):
    """Shared machinery: a bump escape manoeuvre and a random-walk fallback, both with per-row state."""

    def __init__(
        self,
        platform: Platform,
        layout: ObservationLayout,
        rng: np.random.Generator | None = None,
        t_m: float = 2.0,
    ) -> None:
        super().__init__(platform, layout, rng)
        self.t_m = float(t_m)
        self.reset(0)

    def reset(self, n: int, rng: np.random.Generator | None = None) -> None:
        super().reset(n, rng)
        self._escape = np.zeros(n)  # remaining in-place turn (rad, signed) of a bump escape
        self._rw_turn = np.zeros(n)  # random walk: remaining rotation (rad, signed)
        self._rw_steps = np.zeros(n, dtype=np.int64)  # random walk: remaining forward steps
        self._rw_speed = np.zeros(n)  # random walk: forward speed fraction
        self._turned = None  # own rotation per step, newest first (_rotation_since)

    def _ensure(self, n: int) -> None:
        if n != self.n:
            self.reset(n)

    def _rotation_since(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        """(N, 65) own rotation (rad) over the last 0 .. 64 steps, from the last actions in ``proprio``
        (odometry; call once per step). ``_current_bearings`` turns stale readings back by it."""
        n = len(obs["proprio"])
        if getattr(self, "_turned", None) is None or self._turned.shape[0] != n:
            self._turned = np.zeros((n, 64))
        self._turned = np.roll(self._turned, 1, axis=1)
        self._turned[:, 0] = obs["proprio"][:, N_BUMP_SECTORS + 1] * self.platform.max_angular_speed * DT
        return np.concatenate([np.zeros((n, 1)), np.cumsum(self._turned, axis=1)], axis=1)

    def _current_bearings(self, rb: np.ndarray, since: np.ndarray) -> np.ndarray:
        """(N, K) bearings (rad) of the ``range_bearing`` rows, each turned back by the robot's own rotation
        since it was measured (its ``age``): an r-one reading refreshes only when a frame of that
        neighbour is decoded, and a stale body-frame bearing is off by however much the robot turned."""
        age = np.clip(np.rint(rb[..., 6]).astype(np.int64), 0, since.shape[1] - 1)
        return wrap_below_pi(np.arctan2(rb[..., 3], rb[..., 2]) - np.take_along_axis(since, age, axis=1))

    # -- [T20] Alg. 1 --------------------------------------------------------------------------------
    def _random_walk(self, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """One step of the random walk for the selected rows (bool mask); returns (linear, angular)."""
        n = self.n
        lin, ang = np.zeros(n), np.zeros(n)
        if not rows.any():
            return lin, ang
        step_turn = self.platform.max_angular_speed * DT  # rad per step at full angular speed
        # start a new cycle where both phases are over: theta in (-pi, pi], v in [-vmax, vmax]
        new = rows & (np.abs(self._rw_turn) < 1e-9) & (self._rw_steps <= 0)
        k = int(new.sum())
        if k:
            self._rw_turn[new] = -self.rng.uniform(-np.pi, np.pi, k)  # -U[-pi, pi) = U(-pi, pi]
            self._rw_speed[new] = self.rng.uniform(-1.0, 1.0, k)
            self._rw_steps[new] = int(round(self.t_m / DT))
        turning = rows & (np.abs(self._rw_turn) >= 1e-9)
        delta = np.clip(self._rw_turn, -step_turn, step_turn)
        ang[turning] = delta[turning] / step_turn
        self._rw_turn[turning] -= delta[turning]
        moving = rows & ~turning & (self._rw_steps > 0)
        lin[moving] = self._rw_speed[moving]
        self._rw_steps[moving] -= 1
        return lin, ang

    # -- [L] Algs. 5-7, "if CheckBumpObstacle(u): PoseSet(tv = 0, heading = theta_u + pi)" ----------------------
    def _bump_escape(self, proprio: np.ndarray, turn_away: bool = True) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Start/continue the escape turn; returns (escaping mask, linear, angular).

        A new bump on the front half (outside an escape) starts an in-place turn that puts the bump direction
        behind the robot (for a frontal bump this is exactly ``theta_u + pi``); the robot does not drive while
        escaping. Contacts on the rear half are ignored (turning around would face the obstacle).
        """
        n = self.n
        step_turn = self.platform.max_angular_speed * DT
        direction, bumped = bump_direction(proprio)
        if turn_away:
            # only contacts on the front half stop the robot (a push from behind does not block it)
            start = bumped & (np.cos(direction) > 0) & (np.abs(self._escape) < 1e-9)
            # turn so that the bump direction ends up at pi (behind): rotate by direction - pi (wrapped)
            self._escape[start] = wrap_below_pi(direction[start] - np.pi)
        escaping = np.abs(self._escape) >= 1e-9
        delta = np.clip(self._escape, -step_turn, step_turn)
        ang = np.where(escaping, delta / step_turn, 0.0)
        self._escape[escaping] -= delta[escaping]
        return escaping, np.zeros(n), ang


def decoded_ids(id_rows: np.ndarray, n_world: int) -> np.ndarray:
    """Integer ids (N, R) of id-part rows (N, R, 4) (``range_bearing_ids``, ``message_ids``, ...), -1 where a
    row has none; ``n_world`` robots per env copy (``ObservationLayout.n_world``)."""
    return np.where(id_rows[..., 0] > 0.5, np.rint(id_rows[..., 1] * max(n_world - 1, 1)).astype(np.int64), -1)


def require_ids(obs: dict[str, np.ndarray], name: str) -> None:
    if "own_id" not in obs:
        raise ValueError(f"{name} reads decoded ids: make the env with observe_ids=True")
