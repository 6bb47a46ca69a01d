"""What the views of the batched core share: the PettingZoo env (:mod:`swarm_envs.adapters.env`) and the vector env
(:mod:`swarm_envs.adapters.vector`, and through it the TorchRL env) check their settings, seeds, reset options and
actions, build the observation layout and read the infos here, so the views agree and neither imports the
other.
"""

from __future__ import annotations

import numbers
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from swarm_envs.core import SwarmCore
from swarm_envs.sensing.observation import ObservationLayout
from swarm_envs.sim.platforms import Platform
from swarm_envs.sensing.full import reading_max_age
from swarm_envs.tasks.settings import validate_settings
from swarm_envs.sim.world import World
from swarm_envs.sim.arena import as_real_array

__all__ = ["resolve_config", "make_layout", "check_seed", "check_reset_options", "real_actions", "check_finite_actions", "info_arrays"]


def resolve_config(task: Any, kwargs: dict[str, Any]) -> dict[str, Any]:
    """Every setting of ``task`` (a ``Task`` subclass, env class or registered id) filled in and checked
    (:func:`swarm_envs.tasks.settings.validate_settings`): unknown names raise ``TypeError``, bad values
    ``SettingsError`` (a ``ValueError``) naming the key."""
    return validate_settings(task, kwargs)


def make_layout(cfg: dict[str, Any], platform: Platform, n_world: int = 1) -> ObservationLayout:
    """One robot's observation layout for resolved settings ``cfg`` and ``n_world`` robots per copy."""
    return ObservationLayout(
        n_neighbours=cfg["n_neighbours"],
        n_messages=cfg["n_messages"],
        message_bits=cfg["message_bits"],
        max_range=platform.ir_range,
        max_age=reading_max_age(cfg, platform),
        flatten=cfg["flatten"],
        observe_ids=cfg["observe_ids"],
        n_world=n_world,
    )


def check_seed(seed: Any) -> int | None:
    """``seed`` as an int (or None); ``ValueError`` for a negative, ``TypeError`` for a non-integer seed."""
    if seed is None:
        return None
    if isinstance(seed, (bool, np.bool_)) or not isinstance(seed, numbers.Integral):
        raise TypeError(f"seed must be a non-negative integer or None, got {seed!r} ({type(seed).__name__})")
    if seed < 0:
        raise ValueError(f"seed must be a non-negative integer or None, got {seed}")
    return int(seed)


def check_reset_options(options: Any, world: World) -> tuple[np.ndarray | None, np.ndarray | None]:
    """Validated (positions (n, 2) m, headings (n,) rad) from reset ``options`` (None where not given).

    Raises ``TypeError``/``ValueError`` for anything wrong (not a dict, shapes, non-finite values, overlap,
    outside the arena); changes nothing. Unknown keys only warn (PettingZoo's API test passes some).
    """
    if options is None:
        return None, None
    if not isinstance(options, Mapping):
        raise TypeError(
            f"reset options must be a dict (keys 'positions', 'headings') or None, got {type(options).__name__}: {options!r:.80}"
        )
    unknown = sorted((k for k in options if k not in ("positions", "headings")), key=str)
    if unknown:
        import gymnasium

        gymnasium.logger.warn(f"ignoring unknown reset option(s) {unknown}; allowed: ['headings', 'positions']")
    n = world.n
    positions = headings = None
    if "headings" in options:
        headings = as_real_array(options["headings"], "options['headings']")
        if headings.shape != (n,):
            raise ValueError(f"options['headings'] must have shape ({n},) radians, got {headings.shape}")
        if not np.all(np.isfinite(headings)):
            raise ValueError("options['headings'] must be finite")
    if "positions" in options:
        positions = as_real_array(options["positions"], "options['positions']")
        if positions.shape != (n, 2):
            raise ValueError(f"options['positions'] must have shape ({n}, 2) metres, got {positions.shape}")
        positions, _ = world.check_placement(positions, np.zeros(n) if headings is None else headings)
    return positions, headings


def real_actions(actions: Any, shape: tuple[int, ...], what: str, expected: str) -> np.ndarray:
    """``actions`` as a float64 array of ``shape``: ``TypeError`` for anything but an int or float array
    (bool, complex, strings, objects), ``ValueError`` for another shape; ``what`` names the actions and
    ``expected`` describes the shape in the messages."""
    try:
        arr = np.asarray(actions)
    except (TypeError, ValueError):
        arr = np.asarray(None)
    if arr.dtype.kind not in "iuf":
        raise TypeError(f"{what} must be a real-valued numeric array of shape {shape} (int or float dtype), got {actions!r:.80} of dtype {arr.dtype}")
    if arr.shape != shape:
        raise ValueError(f"{what} has shape {arr.shape}; expected {expected}")
    return arr.astype(np.float64)


def check_finite_actions(actions: np.ndarray, name: Callable[[int], str]) -> np.ndarray:
    """``actions`` (n, A) clipped to [-1, 1]; ``ValueError`` naming (``name(row)``) the first row whose
    action holds NaN or inf."""
    finite = np.isfinite(actions).all(axis=1)
    if not finite.all():
        first = int(np.argmin(finite))
        raise ValueError(f"action for {name(first)} contains NaN or inf: {actions[first]}")
    return np.clip(actions, -1.0, 1.0)


def info_arrays(core: SwarmCore, rows: np.ndarray) -> dict[str, dict[str, np.ndarray]]:
    """The infos of the agents at core rows ``rows`` (B, N), as arrays (fresh copies): ``metrics[name]`` (B,),
    ``reward_terms[name]`` (B, N), ``ground_truth`` ``position`` (B, N, 2) m, ``heading`` (B, N) rad,
    ``velocity`` (B, N, 2) m/s, and ``sensing[name]`` (B, N) (empty under ideal sensing)."""
    stats = core.frame.stats if core.frame is not None else {}
    return {
        "metrics": {k: np.asarray(v, dtype=np.float64).copy() for k, v in core.metrics.items()},
        "reward_terms": {k: np.asarray(v, dtype=np.float64).copy() for k, v in core.terms.items()},
        "ground_truth": {
            "position": core.positions[rows].copy(),
            "heading": core.headings[rows].copy(),
            "velocity": core.velocities[rows].copy(),
        },
        "sensing": {k: np.asarray(v)[rows] for k, v in stats.items()},
    }
