"""The process's one worker thread, for work that runs alongside the main thread's step.

A large single scene (one env copy of hundreds of robots, numba on more than one thread) has stages that
do not depend on each other: range & bearing and SwarmCom read the same IR links; the task's rewards
read only the ground truth. :class:`swarm_envs.sensing.full.FullSensing` runs range & bearing here while
the channel is simulated on the calling thread, and :class:`swarm_envs.core.BatchCore` the rewards while
the sensing runs. Work submitted here draws from its own random streams and touches state nothing else
touches in the meantime, and the compiled kernels release the GIL (``nogil``), so results are the same
bit for bit either way. One thread, in submission order.
"""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

__all__ = ["worker"]

_WORKER: ThreadPoolExecutor | None = None


def worker() -> ThreadPoolExecutor:
    """The worker thread (created on first use)."""
    global _WORKER
    if _WORKER is None:
        _WORKER = ThreadPoolExecutor(max_workers=1, thread_name_prefix="swarm_envs-worker")
    return _WORKER
