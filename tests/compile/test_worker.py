"""swarm_envs._compile._worker: the worker thread and the helper threads of run_chunks."""

import threading
import time

import pytest

from swarm_envs._compile._worker import run_chunks, worker


def test_run_chunks_returns_results_in_chunk_order_with_chunk_zero_here():
    names = {}

    def chunk(k):
        names[k] = threading.current_thread().name
        time.sleep(0.01 * (3 - k))  # later chunks finish first
        return k * k

    assert run_chunks(chunk, 3) == [0, 1, 4]
    assert names[0] == threading.current_thread().name
    assert all(names[k].startswith("swarm_envs-helper") for k in (1, 2))
    assert run_chunks(chunk, 1) == [0] and run_chunks(chunk, 0) == []


def test_run_chunks_waits_for_every_chunk_before_raising():
    finished = []

    def chunk(k):
        if k == 0:
            raise RuntimeError("chunk 0 failed")
        time.sleep(0.05)
        finished.append(k)
        return k

    with pytest.raises(RuntimeError, match="chunk 0 failed"):
        run_chunks(chunk, 2)
    assert finished == [1]  # the helper was done before the error reached the caller

    def late(k):
        if k == 1:
            raise ValueError("chunk 1 failed")
        return k

    with pytest.raises(ValueError, match="chunk 1 failed"):
        run_chunks(late, 2)


def test_helpers_are_not_the_worker():
    """The worker may be busy (rewards, range & bearing) while a kernel's chunks run: they never queue behind it."""
    gate = threading.Event()
    busy = worker().submit(gate.wait, 5.0)
    try:
        assert run_chunks(lambda k: k + 1, 2) == [1, 2]
    finally:
        gate.set()
        busy.result()


def test_run_chunks_on_fewer_threads_runs_every_chunk_once_in_chunk_order():
    """With fewer threads than chunks the threads take chunks as they free up: every chunk runs once, on at
    most ``threads`` threads (the calling one among them), and the results come in chunk order."""
    runs, names = [], set()

    def chunk(k):
        runs.append(k)
        names.add(threading.current_thread().name)
        time.sleep(0.002 * (k % 3))
        return 10 * k

    assert run_chunks(chunk, 9, threads=2) == [10 * k for k in range(9)]
    assert sorted(runs) == list(range(9))
    assert len(names) <= 2 and threading.current_thread().name in names
    runs.clear()
    assert run_chunks(chunk, 4, threads=1) == [0, 10, 20, 30] and runs == [0, 1, 2, 3]  # in order, here
    assert run_chunks(chunk, 0, threads=2) == []


def test_run_chunks_on_fewer_threads_raises_the_first_failed_chunk_after_all_ran():
    runs = []

    def chunk(k):
        runs.append(k)
        if k in (2, 5):
            raise ValueError(f"chunk {k} failed")
        return k

    with pytest.raises(ValueError, match="chunk 2 failed"):
        run_chunks(chunk, 7, threads=2)
    assert sorted(runs) == list(range(7))
