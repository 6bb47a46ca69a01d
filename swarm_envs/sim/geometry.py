"""Small planar geometry helpers shared by the physics, the IR layer and the sensing stacks."""

from __future__ import annotations

import numpy as np

__all__ = ["wrap_angle"]


def wrap_angle(a: np.ndarray | float) -> np.ndarray:
    """Wrap angles (rad) to (-pi, pi]."""
    return np.pi - np.mod(np.pi - np.asarray(a, dtype=float), 2.0 * np.pi)
