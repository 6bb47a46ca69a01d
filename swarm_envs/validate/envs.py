"""Validation scenes run in the environment itself: one batched core copy per scene.

The experiments that measure a figure "through the env's stack" (physics, IR layer, SwarmCom, message-borne
bearings, the bearing exchange, scale-free coordinates) place their robots exactly as
``env.reset(seed=s, options={"positions": ..., "headings": ...})`` would, one copy of the batched core
(:class:`swarm_envs.core.SwarmCore`) per scene, and step all copies as one array program. Copy b seeded with
s equals a single env reset with that seed and those options, bit for bit, given the same actions.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from swarm_envs.core import SwarmCore
from swarm_envs.adapters.views import check_reset_options, make_layout, resolve_config
from swarm_envs.sim.platforms import get_platform
from swarm_envs.registry import task_class
from swarm_envs.sensing.exchange import NeighbourKnowledge

__all__ = ["scene_core", "copy_knowledge"]


def scene_core(
    task: Any,
    positions: list[np.ndarray],
    headings: list[np.ndarray],
    seeds: list[int],
    **settings: Any,
) -> SwarmCore:
    """A core of ``len(positions)`` copies of ``task`` (a registered id or task class) with ``settings``,
    copy b started at ``positions[b]`` (n_world, 2) m and ``headings[b]`` (n_world,) rad with seed
    ``seeds[b]`` (as a single env's reset with those options), and its first (reset) step taken.

    Raises the env's own errors for bad settings or placements (overlap, outside the arena)."""
    if not (len(positions) == len(headings) == len(seeds) > 0):
        raise ValueError(f"positions, headings and seeds need one entry per scene, got {len(positions)}, {len(headings)}, {len(seeds)}")
    task_cls = task_class(task)
    cfg = resolve_config(task_cls, settings)
    platform = get_platform(cfg["platform"])
    core = SwarmCore(task_cls(cfg, platform, n_copies=len(positions)), make_layout(cfg, platform))
    poses = []
    for b, (p, h, s) in enumerate(zip(positions, headings, seeds)):
        poses.append(check_reset_options({"positions": p, "headings": h}, core.worlds[b]))
        core.seed(b, int(s))
    core.start(np.arange(len(positions)), poses)
    core.step(None)
    return core


def copy_knowledge(core: SwarmCore, copy: int) -> NeighbourKnowledge:
    """What the robots of env copy ``copy`` know now from the bearing exchange (read only): their own
    bearings and the neighbour lists they received, with the copy's own robot ids 0..n_world-1."""
    kn = core.sensing.exchange.knowledge(copy=True)
    n = core.n_world
    rows = slice(copy * n, (copy + 1) * n)
    base = copy * n

    def local(ids: np.ndarray) -> np.ndarray:
        return np.where(ids >= 0, ids - base, -1)

    return NeighbourKnowledge(
        ids=local(kn.ids[rows]),
        bearings=kn.bearings[rows],
        row_ids=local(kn.row_ids[rows]),
        row_bearings=kn.row_bearings[rows],
        row_age=None if kn.row_age is None else kn.row_age[rows],
    )
