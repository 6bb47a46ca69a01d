"""How much memory copies of a task need, and how much the machine has: the checks that keep
``make_vec``, the TorchRL env and training from asking for more copies than fit."""

from __future__ import annotations

import os

import numpy as np

from swarm_envs.sim.world import COPY_LOG_BYTES
from swarm_envs.tasks.settings import SettingsError
from swarm_envs.tasks.task import Task

__all__ = ["MAX_COPIES", "MAX_TOTAL_ROBOTS", "copy_memory", "available_memory", "check_memory"]

#: copies of one batched core at most, and robots over all its copies at most (memory grows with both)
MAX_COPIES = 100_000
MAX_TOTAL_ROBOTS = 200_000

# Memory of one env copy (bytes), measured as the growth of the process's resident memory (VmRSS, peak
# VmHWM) of make_vec(B) over its build, reset and steps (e-puck, full sensing; docs/settings.md#make_vec):
#: per copy (its physics space, random generators and sensing state): 320-330 KB with one robot
COPY_BYTES = 320_000
#: per robot of a copy, at the peak of a step (34-57 KB measured from 10 to 5,000 robots per copy)
ROBOT_BYTES = 60_000
#: per wall segment of a copy's physics space (a circle arena's 64 add ~87 KB)
WALL_BYTES = 1_500
#: per control step of an episode, besides 16 bytes per robot: a world's command log for exact copies
#: (swarm_envs.sim.world.COPY_LOG_BYTES; 0.4-0.6 KB per step measured)
LOG_STEP_BYTES = 500


def copy_memory(task: Task) -> int:
    """Estimated peak memory (bytes) of one copy of ``task`` (a task built for one copy) over an episode of
    ``max_cycles`` steps: :data:`COPY_BYTES`, :data:`ROBOT_BYTES` per robot, :data:`WALL_BYTES` per wall
    segment, the task's own arrays and the world's command log (16 bytes per robot + :data:`LOG_STEP_BYTES`
    per step, until the log reaches ``COPY_LOG_BYTES``)."""
    n = task.n_world
    segments = len(task.arena.wall_segments()) + len(task.obstacle_segments)
    own = sum(value.nbytes for value in vars(task).values() if isinstance(value, np.ndarray))
    steps = min(task.max_cycles, COPY_LOG_BYTES // (16 * n) + 1)
    return COPY_BYTES + ROBOT_BYTES * n + WALL_BYTES * segments + own + steps * (16 * n + LOG_STEP_BYTES)


def _read_number(path: str) -> int | None:
    try:
        with open(path, encoding="ascii") as f:
            return int(f.read().split()[0])
    except (OSError, ValueError, IndexError):
        return None


def available_memory() -> int | None:
    """Memory (bytes) this process can still take: ``MemAvailable`` of ``/proc/meminfo`` (else the free
    physical pages, ``os.sysconf``), or less when the process's memory cgroup allows less; None if unknown."""
    available = None
    try:
        with open("/proc/meminfo", encoding="ascii") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    available = int(line.split()[1]) * 1024  # kB
                    break
    except (OSError, ValueError, IndexError):
        pass
    if available is None:
        try:
            available = os.sysconf("SC_AVPHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
        except (AttributeError, ValueError, OSError):
            return None
    for limit_path, usage_path in (
        ("/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory.current"),  # cgroup v2 ("max": no limit)
        ("/sys/fs/cgroup/memory/memory.limit_in_bytes", "/sys/fs/cgroup/memory/memory.usage_in_bytes"),  # v1
    ):
        limit, usage = _read_number(limit_path), _read_number(usage_path)
        if limit is not None and usage is not None and limit < 1 << 60:
            available = min(available, max(limit - usage, 0))
    return available


def check_memory(task: Task, num_envs: int) -> None:
    """:class:`SettingsError` naming ``num_envs`` when ``num_envs`` copies of ``task`` (built for one copy)
    would need more memory (:func:`copy_memory`) than is available (:func:`available_memory`)."""
    available = available_memory()
    per_copy = copy_memory(task)
    if available is None or num_envs * per_copy <= available:
        return
    raise SettingsError(
        "num_envs",
        f"num_envs={num_envs} copies of {task.n_world} robot(s) would need ~{num_envs * per_copy / 2**30:.2f} GiB of memory "
        f"(~{per_copy / 1e3:,.0f} KB per copy over an episode of {task.max_cycles:,} steps), but the machine has "
        f"{available / 2**30:.2f} GiB available; use at most {available // per_copy:,} copies, fewer robots or a shorter max_cycles",
    )
