"""A sensible default for torch's intra-op thread count on small, shared machines.

Torch starts one intra-op thread per core. On a machine with few cores that also steps the simulation,
those threads compete with the env (and with each other) for the cores, and small MLP updates get slower,
not faster. :func:`set_torch_threads` picks 1 thread on machines with at most 2 cores and
``min(4, cores // 2)`` above that, unless a count is given, or the standard ``OMP_NUM_THREADS`` environment
variable is set (then that count is used). The adapters and examples that run torch call it once.
"""

from __future__ import annotations

import os

__all__ = ["default_torch_threads", "set_torch_threads"]


def _available_cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def default_torch_threads(cores: int | None = None) -> int:
    """The thread count :func:`set_torch_threads` uses when none is given: ``OMP_NUM_THREADS`` if set,
    else 1 on at most 2 cores, else ``min(4, cores // 2)`` (``cores``: default, the cores this process may use)."""
    env = os.environ.get("OMP_NUM_THREADS", "").strip()
    if env:
        try:
            value = int(env)
        except ValueError:
            raise ValueError(f"OMP_NUM_THREADS must be a positive integer, got {env!r}") from None
        if value < 1:
            raise ValueError(f"OMP_NUM_THREADS must be a positive integer, got {env!r}")
        return value
    cores = _available_cores() if cores is None else int(cores)
    return 1 if cores <= 2 else min(4, cores // 2)


def set_torch_threads(threads: int | None = None) -> int:
    """Set torch's intra-op thread count (``torch.set_num_threads``) and return it.

    Args:
        threads: the count; None: :func:`default_torch_threads`.
    """
    if threads is None:
        threads = default_torch_threads()
    if isinstance(threads, bool) or not isinstance(threads, int) or threads < 1:
        raise ValueError(f"threads must be a positive integer or None, got {threads!r}")
    import torch

    torch.set_num_threads(threads)
    return threads
