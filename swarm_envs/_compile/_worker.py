"""The process's worker thread and helper threads, for work that runs alongside the main thread's step.

A large scene (one env of hundreds of robots, or a batch of copies with as many IR pairs; numba on more
than one thread) has stages that
do not depend on each other: range & bearing and SwarmCom read the same IR links; the task's rewards
read only the ground truth. :class:`swarm_envs.sensing.full.FullSensing` runs range & bearing here while
the channel is simulated on the calling thread, and :class:`swarm_envs.core.SwarmCore` the rewards while
the sensing runs. Work submitted here draws from its own random streams and touches state nothing else
touches in the meantime, and the compiled kernels release the GIL (``nogil``), so results are the same
bit for bit either way. One thread, in submission order; it also draws SwarmCom's random numbers and
queues the step's messages while the physics runs (:meth:`FullSensing.prepare_step`).

The helper threads (:func:`run_chunks`) are a separate pool for pieces of one compiled computation: the
chunks of the IR layer's gain kernel and occluder search, the shares of a batch's physics, SwarmCom's
groups of copies, the scale-free coordinates' ranges of robots. Idle threads of both pools wait on a
lock, so they take no core from the rest.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import TypeVar

__all__ = ["worker", "run_chunks"]

T = TypeVar("T")

_WORKER: ThreadPoolExecutor | None = None
_HELPERS: ThreadPoolExecutor | None = None
_HELPER_COUNT = 0


def worker() -> ThreadPoolExecutor:
    """The worker thread (created on first use)."""
    global _WORKER
    if _WORKER is None:
        _WORKER = ThreadPoolExecutor(max_workers=1, thread_name_prefix="swarm_envs-worker")
    return _WORKER


def _helpers(n: int) -> ThreadPoolExecutor:
    """The helper pool, grown to at least ``n`` threads."""
    global _HELPERS, _HELPER_COUNT
    if _HELPERS is None or _HELPER_COUNT < n:
        old, _HELPERS = _HELPERS, ThreadPoolExecutor(max_workers=n, thread_name_prefix="swarm_envs-helper")
        _HELPER_COUNT = n
        if old is not None:
            old.shutdown(wait=False)
    return _HELPERS


def run_chunks(chunk: Callable[[int], T], n_chunks: int, threads: int | None = None) -> list[T]:
    """``[chunk(0), ..., chunk(n_chunks - 1)]`` on ``threads`` threads (default one per chunk): the calling
    thread and helper threads (a pool of its own, not the worker, grown to ``threads - 1`` threads on
    demand), for compiled kernels that release the GIL and write disjoint parts of shared arrays (the IR
    layer's gain kernel and occluder search, the physics of env copies, SwarmCom's groups of copies).

    With one thread per chunk, chunk 0 runs on the calling thread. With fewer threads than chunks, each
    thread takes the next chunk not yet taken when it finishes one, so a thread that shares its core with
    other work (the worker thread) takes fewer chunks; which thread runs a chunk changes no result.

    The helpers wait on a lock between calls, so an idle helper takes no core from the worker thread or the
    physics. Waits for every chunk; the first chunk's error (in chunk order) is raised."""
    threads = n_chunks if threads is None else max(1, min(int(threads), n_chunks))
    if threads == n_chunks:
        if n_chunks <= 1:
            return [chunk(0)] if n_chunks == 1 else []
        pool = _helpers(n_chunks - 1)
        futures = [pool.submit(chunk, k) for k in range(1, n_chunks)]
        try:
            first = chunk(0)
        finally:  # never return while a helper still writes into the caller's arrays
            for f in futures:
                f.exception()  # waits
        return [first, *(f.result() for f in futures)]
    results: list = [None] * n_chunks
    errors: dict[int, BaseException] = {}
    taken = itertools.count()  # next() of a count is atomic under the GIL: each chunk is taken once

    def take_chunks(_: int) -> None:
        while (k := next(taken)) < n_chunks:
            try:
                results[k] = chunk(k)
            except BaseException as error:  # kept: raised in chunk order once every chunk has run
                errors[k] = error

    run_chunks(take_chunks, threads)
    if errors:
        raise errors[min(errors)]
    return results
