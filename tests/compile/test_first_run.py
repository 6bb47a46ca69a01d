"""The first run on a cold numba cache (swarm_envs._compile._first_run, swarm_envs._compile._numba, swarm_envs._compile._sort): the
"compiling" line on an empty cache and none on a warm one, the background compile process filling the
cache with the same results, one set of compiler flags for every kernel, no per-constant
specialisations, a cache entry of another signature rejected, and numba's argsort written out."""

from __future__ import annotations

import importlib
import os
import pkgutil
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import numba
import numpy as np
import pytest

import swarm_envs
from swarm_envs._compile import _first_run, _kernel_manifest
from swarm_envs._compile._numba import njit
from swarm_envs._compile._sort import argsort_quick

ROOT = Path(__file__).resolve().parents[2]
NOTICE = "swarm_envs: compiling the numba kernels for the first run"

# a short episode of the README's scenario; prints a checksum of what it observed
SCRIPT = textwrap.dedent(
    """
    import sys
    import numpy as np
    from numba.core import event
    compiled = []
    class Count(event.Listener):
        def on_start(self, ev):
            if ev.data["dispatcher"].py_func.__module__.startswith("swarm_envs."):
                compiled.append(ev.data["dispatcher"].py_func.__qualname__)
        def on_end(self, ev):
            pass
    event.register("numba:compile", Count())
    import swarm_envs
    env = swarm_envs.make("swarm_envs/Aggregation-v0", n_robots=10, platform="epuck")
    obs, _ = env.reset(seed=3)
    total = sum(float(np.sum(v)) for o in obs.values() for v in o.values())
    for i, agent in enumerate(env.possible_agents):
        env.action_space(agent).seed(i)
    for _ in range(STEPS):
        obs, *_ = env.step({a: env.action_space(a).sample() for a in env.agents})
        total += sum(float(np.sum(v)) for o in obs.values() for v in o.values())
    print(repr(total))
    print("compiled", len(compiled), file=sys.stderr)
    """
)


def _run(cache: Path, steps: int, background: bool = True) -> subprocess.CompletedProcess:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache), "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))}
    env["SWARM_ENVS_BACKGROUND_COMPILE"] = "1" if background else "0"  # 1: whatever the machine's load
    proc = subprocess.run([sys.executable, "-c", SCRIPT.replace("STEPS", str(steps))], cwd=ROOT, env=env, capture_output=True, text=True, timeout=900)
    assert proc.returncode == 0, proc.stderr
    return proc


def _checksum_here(steps: int) -> float:
    env = swarm_envs.make("swarm_envs/Aggregation-v0", n_robots=10, platform="epuck")
    obs, _ = env.reset(seed=3)
    total = sum(float(np.sum(v)) for o in obs.values() for v in o.values())
    for i, agent in enumerate(env.possible_agents):
        env.action_space(agent).seed(i)
    for _ in range(steps):
        obs, *_ = env.step({a: env.action_space(a).sample() for a in env.agents})
        total += sum(float(np.sum(v)) for o in obs.values() for v in o.values())
    return total


@pytest.mark.slow  # compiles every kernel of a scenario from an empty cache, in two processes (~25 s idle)
def test_compiling_line_on_an_empty_cache_only_and_background_compile_fills_it(tmp_path):
    """An empty cache: one "compiling" line, and the background process compiles the rest of the
    scenario's kernels; once it is done, a second run prints nothing and compiles nothing; both runs
    observe exactly what this process (its own compiled kernels) observes."""
    cache = tmp_path / "cache"
    first = _run(cache, steps=20)
    assert first.stderr.count(NOTICE) == 1, first.stderr
    assert "cached afterwards" in first.stderr and "on two cores" in first.stderr
    deadline = time.time() + 600
    time.sleep(1.0)
    while any(cache.rglob(_first_run.LOCK_NAME)) and time.time() < deadline:  # the background process is still compiling
        time.sleep(1.0)
    assert not any(cache.rglob(_first_run.LOCK_NAME)), "the background compile process did not finish"
    second = _run(cache, steps=20)
    assert NOTICE not in second.stderr, second.stderr
    assert "compiled 0" in second.stderr, second.stderr  # every kernel came from the cache
    assert float(first.stdout) == float(second.stdout) == _checksum_here(20)


def test_compiling_line_without_the_background_process(monkeypatch, capsys):
    """``SWARM_ENVS_BACKGROUND_COMPILE=0``: the line still says what happens, without "two cores", once,
    and no background process starts."""
    monkeypatch.setattr(_first_run, "_prepared", set())
    monkeypatch.setattr(_first_run, "_noticed", False)
    monkeypatch.setenv("SWARM_ENVS_BACKGROUND_COMPILE", "0")
    started = []
    monkeypatch.setattr(_first_run.subprocess, "Popen", lambda *a, **k: started.append(a))
    monkeypatch.setattr(_first_run, "cold_kernels", lambda task, platform: [(None, (), 20.0)])
    _first_run.prepare("AggregationTask", "epuck", "full")
    _first_run.prepare("FlockingTask", "epuck", "full")  # once per process
    _first_run.prepare("FlockingTask", "droplet", "ideal")
    assert not started
    err = capsys.readouterr().err
    assert err.count(NOTICE) == 1 and "about 20 s;" in err and "two cores" not in err


def test_notice_once_and_only_above_a_few_seconds(monkeypatch, capsys):
    monkeypatch.setattr(_first_run, "_prepared", set())
    monkeypatch.setattr(_first_run, "_noticed", False)
    monkeypatch.setattr(_first_run, "_start_helper", lambda *a: False)
    monkeypatch.setattr(_first_run, "cold_kernels", lambda task, platform: [(None, (), 0.5)] * 4)  # 2 s: no line
    _first_run.prepare("AggregationTask", "epuck", "full")
    assert capsys.readouterr().err == ""
    monkeypatch.setattr(_first_run, "cold_kernels", lambda task, platform: [(None, (), 6.0)] * 4)
    _first_run.prepare("FlockingTask", "epuck", "full")
    _first_run.prepare("FlockingTask", "rone", "full")
    err = capsys.readouterr().err
    assert err.count(NOTICE) == 1 and "about 25 s;" in err and "two cores" not in err


def test_manifest_names_existing_kernels_and_scenarios():
    """Every recorded kernel resolves to a cached dispatcher of the package and its argument types decode
    (a renamed kernel or a changed type module fails here: re-record with ``python -m
    swarm_envs._compile._kernel_record``); every scenario is a registered task on a known platform."""
    assert _kernel_manifest.KERNELS and _kernel_manifest.SCENARIOS
    for module, name, types in _kernel_manifest.KERNELS:
        dispatcher = _first_run._dispatcher(module, name)
        assert getattr(dispatcher._cache, "_swarm_guarded", False), (module, name)
        decoded = tuple(_first_run.decode_type(s) for s in types)
        assert tuple(_first_run.encode_type(t) for t in decoded) == tuple(types)
    from swarm_envs.registry import task_class

    tasks = {task_class(env_id).__name__ for env_id in swarm_envs.list_envs()}
    for (task, platform), rows in _kernel_manifest.SCENARIOS.items():
        assert task in tasks and platform in ("droplet", "epuck", "rone")
        assert rows and all(0 <= i < len(_kernel_manifest.KERNELS) and s >= 0 for i, s in rows)
    assert ("AggregationTask", "epuck") in _kernel_manifest.SCENARIOS  # the README's scenario


def _package_dispatchers():
    from numba.core.registry import CPUDispatcher

    found = {}
    for info in pkgutil.walk_packages(swarm_envs.__path__, "swarm_envs."):
        if info.name.endswith("__main__"):
            continue
        try:
            module = importlib.import_module(info.name)
        except ImportError:  # an optional dependency (benchmarl, ...) is not installed
            continue
        for value in vars(module).values():
            if isinstance(value, CPUDispatcher) and value.py_func.__module__.startswith("swarm_envs."):
                found[(value.py_func.__module__, value.py_func.__qualname__)] = value
    return found


def test_every_kernel_has_the_shared_flags_and_a_guarded_cache():
    """One set of compiler flags for all kernels (numba compiles the library functions a kernel calls once
    per set), calls between kernels without per-constant specialisations, caches that recover."""
    dispatchers = _package_dispatchers()
    assert len(dispatchers) > 60
    for key, d in dispatchers.items():
        assert d.targetoptions.get("nogil") is True and d.targetoptions.get("error_model") == "numpy", key
        assert getattr(d._cache, "_swarm_guarded", False), key
        assert getattr(d, "_swarm_unliteral", False), key


def test_kernels_allocate_with_np_empty_and_a_positional_dtype():
    """Kernels allocate only with ``np.empty(shape, dtype)`` (swarm_envs._compile._numba docstring): every
    ``np.zeros``/``np.ones``/``np.full`` or dtype left to its default or given by keyword is one more library
    function numba compiles on the first run."""
    import ast
    import inspect

    allowed = {"np.float64", "np.float32", "np.int64", "np.int8", "np.uint8", "np.uint32", "np.bool_"}
    bad = []
    for key, d in _package_dispatchers().items():
        tree = ast.parse(textwrap.dedent(inspect.getsource(d.py_func)))
        for node in ast.walk(tree):
            if not (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)):
                continue
            if getattr(node.func.value, "id", "") != "np" or node.func.attr not in ("empty", "zeros", "ones", "full"):
                continue
            form_ok = node.func.attr == "empty" and len(node.args) == 2 and not node.keywords
            dtype = ast.unparse(node.args[1]) if len(node.args) == 2 else ""
            if not form_ok or (dtype not in allowed and not dtype.endswith(".dtype")):
                bad.append(f"{key[0]}.{key[1]}: {ast.unparse(node)}")
    assert not bad, "\n".join(bad)


def test_constant_arguments_compile_one_specialisation():
    @njit
    def add(x, k):
        return x + k

    @njit
    def caller(x):
        return add(x, 0) + add(x, 1) + add(x, 7)

    assert caller(1.0) == 11.0
    assert len(add.signatures) == 1 and "Literal" not in str(add.signatures[0])


def test_a_cache_entry_of_another_signature_is_recompiled(tmp_path):
    """Two processes saving two signatures of one function at once can give both the same data file; the
    guard then sees code of the other signature, warns and recompiles instead of running it."""
    (tmp_path / "kern.py").write_text(
        textwrap.dedent(
            """
            from swarm_envs._compile._numba import njit

            @njit(cache=True)
            def half(x):
                return x / 2
            """
        )
    )
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "cache"), "PYTHONPATH": f"{tmp_path}{os.pathsep}{ROOT}"}
    code = "import warnings, numpy as np; warnings.simplefilter('always'); import kern; print(kern.half(np.int64(3)), kern.half(3.0))"
    run = lambda: subprocess.run([sys.executable, "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True, timeout=600)  # noqa: E731
    first = run()
    assert first.returncode == 0 and first.stdout.split() == ["1.5", "1.5"], first.stderr
    data = sorted((tmp_path / "cache").rglob("*.nbc"))
    assert len(data) == 2
    a, b = (f.read_bytes() for f in data)
    data[0].write_bytes(b)  # both index entries now name code compiled for one signature
    data[1].write_bytes(a)
    second = run()
    assert second.returncode == 0 and second.stdout.split() == ["1.5", "1.5"], second.stderr
    assert "NumbaCacheWarning" in second.stderr and "another signature" in second.stderr


def _kernel_in(tmp_path: Path, monkeypatch, name: str):
    """A fresh cached kernel ``double(float64)`` in module ``name`` under ``tmp_path`` (its own disk cache)."""
    (tmp_path / f"{name}.py").write_text("from swarm_envs._compile._numba import njit\n\n@njit(cache=True)\ndef double(x):\n    return 2 * x\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path / "cache"), raising=False)
    module = importlib.import_module(name)
    return module.double, (numba.core.types.float64,)


def _holder(seconds: float) -> subprocess.Popen:
    """A process that lives ``seconds``, reaped when it exits (as prepare() reaps the background process:
    an unreaped child would still answer os.kill(pid, 0))."""
    proc = subprocess.Popen([sys.executable, "-c", f"import time; time.sleep({seconds})"])
    threading.Thread(target=proc.wait, daemon=True).start()
    return proc


def test_a_kernel_claimed_by_another_process_is_not_compiled_twice(tmp_path, monkeypatch):
    """While another live process holds a kernel's claim, this one neither compiles it nor claims it; once
    the claim is free it compiles it, saves it and removes its own claim."""
    double, argtypes = _kernel_in(tmp_path, monkeypatch, "kern_claimed")
    claim = _first_run._claim_path(double, 0)
    holder = _holder(60)
    try:
        claim.write_text(str(holder.pid))
        assert not _first_run._compile_claimed(double, argtypes, 0)
        assert not _first_run._cached(double, argtypes) and claim.read_text() == str(holder.pid)
    finally:
        holder.kill()
        holder.wait()
    assert _first_run._compile_claimed(double, argtypes, 0)  # the holder is gone: its claim is stale
    assert _first_run._cached(double, argtypes) and not claim.exists()
    assert not _first_run._compile_claimed(double, argtypes, 0)  # cached now: nothing to do


def test_compile_share_waits_only_while_someone_compiles(tmp_path, monkeypatch):
    """The main process waits for a kernel the background process has claimed, and stops waiting as soon
    as nobody holds the claim (then the env compiles the kernel where it calls it)."""
    double, argtypes = _kernel_in(tmp_path, monkeypatch, "kern_waited")
    monkeypatch.setattr(_first_run, "cold_kernels", lambda task, platform: [(double, argtypes, 100.0, 0)])
    claim = _first_run._claim_path(double, 0)
    holder = _holder(1.5)
    try:
        claim.write_text(str(holder.pid))
        t0 = time.monotonic()
        assert _first_run.compile_share("AggregationTask", "epuck") == 0
        waited = time.monotonic() - t0
    finally:
        holder.kill()
        holder.wait()
    assert 1.0 < waited < 30.0, waited  # the holder's life, not the 210 s deadline
    assert not _first_run._cached(double, argtypes)
    claim.unlink()
    assert _first_run.compile_share("AggregationTask", "epuck") == 1  # unclaimed: compiled here
    assert _first_run._cached(double, argtypes)


def test_both_processes_compile_the_longest_kernels_first(monkeypatch):
    """The main and the background process take the scenario's cold kernels longest first (ties in order
    of first use), so the two finish within about one short kernel of each other; the README scenario's
    generator list kernel is in the manifest (its argument, a Generator, is recorded)."""
    rows = [("a", (), 0.3, 0), ("b", (), 2.0, 1), ("c", (), 0.3, 2), ("d", (), 1.1, 3)]
    assert [r[0] for r in _first_run.longest_first(rows)] == ["b", "d", "a", "c"]
    order = []
    monkeypatch.setattr(_first_run, "cold_kernels", lambda task, platform: rows)
    monkeypatch.setattr(_first_run, "_compile_claimed", lambda d, argtypes, index: order.append(d) or True)
    monkeypatch.setattr(_first_run, "_cached", lambda d, argtypes: True)
    assert _first_run.compile_share("AggregationTask", "epuck") == 4
    assert order == ["b", "d", "a", "c"]
    names = {_kernel_manifest.KERNELS[i][1] for i, _ in _kernel_manifest.SCENARIOS[("AggregationTask", "epuck")]}
    assert "_generator_list" in names


def test_argsort_quick_is_numbas_argsort():
    """The same permutation as ``np.argsort`` compiled by numba, ties, NaN and signed zeros included."""

    @numba.njit
    def reference(a):
        return np.argsort(a)

    rng = np.random.default_rng(7)
    for trial in range(600):
        n = int(rng.integers(0, 300 if trial % 10 else 3000))
        kind = trial % 5
        if kind == 0:
            a = rng.random(n)
        elif kind == 1:
            a = rng.integers(0, 4, n).astype(float)  # many ties
        elif kind == 2:
            a = np.sort(rng.random(n))
        elif kind == 3:
            a = np.sort(rng.random(n))[::-1].copy()
        else:
            a = rng.normal(size=n)
            a[rng.random(n) < 0.2] = np.nan
            a[rng.random(n) < 0.1] = -0.0
            a[rng.random(n) < 0.1] = 0.0
        np.testing.assert_array_equal(argsort_quick(a), reference(a))


def test_first_run_benchmark_reads_the_readme_snippet():
    import importlib.util

    spec = importlib.util.spec_from_file_location("bench_first_run", ROOT / "benchmarks" / "bench_first_run.py")
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    snippet = bench.readme_snippet()
    assert 'pettingzoo.make("parallel", "swarm_envs/Aggregation-v0"' in snippet and "env.reset(seed=0)" in snippet
    assert bench.LOCK_NAME == _first_run.LOCK_NAME and bench.NOTICE in NOTICE


def test_background_process_only_with_an_idle_core(monkeypatch):
    """Unset, the background process starts only when the load average leaves a core idle (on a busy
    machine a second compiling process competes with the env's); 0 and 1 decide regardless."""
    monkeypatch.setattr(_first_run, "_cores", lambda: 2)
    monkeypatch.delenv("SWARM_ENVS_BACKGROUND_COMPILE", raising=False)
    monkeypatch.setattr(_first_run.os, "getloadavg", lambda: (0.4, 0.3, 0.2))
    assert _first_run._background_wanted()
    monkeypatch.setattr(_first_run.os, "getloadavg", lambda: (3.9, 4.1, 4.0))
    assert not _first_run._background_wanted()
    monkeypatch.setenv("SWARM_ENVS_BACKGROUND_COMPILE", "1")
    assert _first_run._background_wanted()
    monkeypatch.setenv("SWARM_ENVS_BACKGROUND_COMPILE", "0")
    monkeypatch.setattr(_first_run.os, "getloadavg", lambda: (0.0, 0.0, 0.0))
    assert not _first_run._background_wanted()
    monkeypatch.setattr(_first_run, "_cores", lambda: 1)
    monkeypatch.setenv("SWARM_ENVS_BACKGROUND_COMPILE", "1")
    assert not _first_run._background_wanted()
