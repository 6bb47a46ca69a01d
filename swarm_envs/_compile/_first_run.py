"""The first run on a cold numba cache: say that the kernels compile, and compile them on two cores.

With ``cache=True`` numba compiles a kernel the first time it is called and keeps the machine code on
disk; a fresh install (or a new numba version, or an edited kernel module) starts from an empty cache,
and the first ``env.reset()`` with the modelled sensing compiles the few dozen kernels of its stack,
about twenty seconds on one core. :func:`prepare`, called when an env's sensing is built, looks up the
kernels its scenario (task class and platform) calls, recorded in :mod:`swarm_envs._compile._kernel_manifest`
with their compile times. When those not on disk yet would take more than :data:`NOTICE_SECONDS` to
compile, it prints one line to stderr, once per process, and, when a core is idle, starts one background
process (``python -m swarm_envs._compile._first_run TASK PLATFORM``, at low priority) that compiles them into the
same cache while this process compiles them too (:func:`compile_share`) before the env is built. Both
processes take the kernels longest first (by recorded compile time); each claims a kernel (a claim file
beside its cache) before compiling it and skips the kernels the other has claimed, so no kernel is
compiled twice, and the two finish within about one short kernel of each other; this process then waits
for the kernels the other is still compiling and loads them from the disk cache. The machine code is the
same whichever process compiles a kernel (same source, flags and CPU): results do not change. Only one
background process runs per cache directory (a lock file), and none on one core.

``SWARM_ENVS_BACKGROUND_COMPILE``: ``0`` never starts the background process (the notice stays), ``1``
starts it even when no core looks idle; unset, it starts when the 1-minute load average is below the
number of cores minus a half.

``python -m swarm_envs._compile._kernel_record`` re-records the manifest (:mod:`swarm_envs._compile._kernel_record`). A
manifest that no longer matches a kernel costs only time: a signature that does not compile is skipped,
a kernel it misses is compiled where it is first called.
"""

from __future__ import annotations

import importlib
import os
import re
import subprocess
import sys
import threading
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

__all__ = ["prepare", "compile_share", "longest_first", "NOTICE_SECONDS", "encode_type", "decode_type", "scenario_kernels", "cold_kernels"]

#: expected compile time (s of one core) above which :func:`prepare` prints the notice
NOTICE_SECONDS = 5.0
#: environment variable: ``0`` no background compile process, ``1`` one whatever the load, unset one when a core is idle
BACKGROUND_VARIABLE = "SWARM_ENVS_BACKGROUND_COMPILE"
#: the lock file of the background process, in the numba cache directory of the kernels
LOCK_NAME = "swarm_envs_first_run.lock"
#: the claim file of one kernel, beside its cache files: the process compiling it (``.format(function, manifest index)``)
CLAIM_NAME = "swarm_envs_first_run.{}.{}.claim"
#: a lock older than this (s) is stale (its process died without removing it)
LOCK_STALE_S = 600.0
#: niceness of the background process (POSIX): it uses idle cores, and yields to the env and other work
NICE = 10

_noticed = False
_prepared: set[tuple[str, str]] = set()
_helpers: list[subprocess.Popen] = []


# ----------------------------------------------------------------------------------------- argument types
_ARRAY = re.compile(r"^(\w+)\[(\d+)([CFA])(,ro)?\]$")


def encode_type(t: Any) -> str | None:
    """A numba argument type as a short string (``float64[2C]``, ``int64``, ``generator``, ``list[generator]``), or None
    for a type the manifest does not record."""
    from numba.core import types

    if isinstance(t, types.Array) and isinstance(t.dtype, (types.Number, types.Boolean)) and t.aligned:
        return f"{t.dtype}[{t.ndim}{t.layout}{'' if t.mutable else ',ro'}]"
    if isinstance(t, (types.Integer, types.Float, types.Boolean)) and not isinstance(t, types.Literal):
        return str(t)
    if type(t).__name__ == "NumPyRandomGeneratorType":
        return "generator"
    if isinstance(t, types.ListType) and type(t.item_type).__name__ == "NumPyRandomGeneratorType":
        return "list[generator]"
    return None


def decode_type(s: str) -> Any:
    """The numba type of an :func:`encode_type` string."""
    import numpy as np
    from numba import typeof
    from numba.core import types

    if s == "generator":
        return typeof(np.random.default_rng(0))
    if s == "list[generator]":
        return types.ListType(typeof(np.random.default_rng(0)))
    m = _ARRAY.match(s)
    if m:
        return types.Array(_scalar(m.group(1)), int(m.group(2)), m.group(3), readonly=bool(m.group(4)))
    return _scalar(s)


def _scalar(name: str) -> Any:
    from numba.core import types

    t = types.boolean if name == "bool" else getattr(types, name, None)
    if not isinstance(t, (types.Integer, types.Float, types.Boolean)):
        raise ValueError(f"not a recorded numba type: {name!r}")
    return t


# ----------------------------------------------------------------------------------------- the manifest
def scenario_kernels(task: str, platform: str) -> list[tuple[str, str, tuple[str, ...], float]]:
    """The recorded kernels of a scenario in order of first use: (module, function, argument types,
    compile seconds). ``task`` is the task class name; a pairing not recorded takes the first recording on
    its platform (the platform decides most of the sensing stack), else the task's on another platform (a
    custom platform). Empty when unknown."""
    import swarm_envs._compile._kernel_manifest as manifest

    return [(*manifest.KERNELS[i], seconds) for i, seconds in _scenario_rows(task, platform)]


def _scenario_rows(task: str, platform: str) -> tuple[tuple[int, float], ...]:
    """(index into the manifest's KERNELS, compile seconds) of the scenario (see :func:`scenario_kernels`)."""
    import swarm_envs._compile._kernel_manifest as manifest

    rows = manifest.SCENARIOS.get((task, platform))
    if rows is None:
        rows = next((v for (_, p), v in manifest.SCENARIOS.items() if p == platform), None)
    if rows is None:
        rows = next((v for (t, _), v in manifest.SCENARIOS.items() if t == task), ())
    return rows


def _dispatcher(module: str, name: str) -> Any:
    obj: Any = importlib.import_module(module)
    for part in name.split("."):
        obj = getattr(obj, part)
    return obj


def _cached(dispatcher: Any, argtypes: tuple) -> bool:
    """Whether the disk cache holds ``dispatcher`` compiled for ``argtypes`` (reads the cache index only)."""
    if tuple(argtypes) in dispatcher.overloads:
        return True
    cache = dispatcher._cache
    key = cache._index_key(tuple(argtypes), dispatcher.targetctx.codegen())
    return key in cache._cache_file._load_index()


def cold_kernels(task: str, platform: str) -> list[tuple[Any, tuple, float, int]]:
    """(dispatcher, argument types, compile seconds, manifest index) of the scenario's kernels that are
    neither loaded nor in the disk cache, in order of first use. Entries that no longer resolve are left out."""
    import swarm_envs._compile._kernel_manifest as manifest

    out = []
    for index, seconds in _scenario_rows(task, platform):
        try:
            module, name, encoded = manifest.KERNELS[index]
            dispatcher = _dispatcher(module, name)
            argtypes = tuple(decode_type(s) for s in encoded)
            if not _cached(dispatcher, argtypes):
                out.append((dispatcher, argtypes, seconds, index))
        except Exception:  # a renamed kernel, a changed type, a cache it cannot read: not this module's business
            continue
    return out


def _claim_path(dispatcher: Any, index: int) -> Path:
    """The claim file of manifest kernel ``index`` (``dispatcher``), in the directory of its cache files."""
    return Path(dispatcher._cache.cache_path) / CLAIM_NAME.format(dispatcher.py_func.__name__, index)


def _compile_claimed(dispatcher: Any, argtypes: tuple, index: int) -> bool:
    """Compile one kernel unless it is cached or another process has claimed it; whether this process compiled it."""
    if _cached(dispatcher, argtypes):
        return False
    claim = _claim_path(dispatcher, index)
    if not _acquire(claim):
        return False
    try:
        if _cached(dispatcher, argtypes):  # finished by the other process between the two checks
            return False
        dispatcher.compile(argtypes)  # saves it to the disk cache
        return True
    except Exception:  # a stale manifest entry: compiled where it is really called
        return False
    finally:
        _release(claim)


# ----------------------------------------------------------------------------------------- the main process
def prepare(task: str, platform: str, sensing: str) -> None:
    """Before an env's first step (see the module docstring): when the kernels of scenario (``task`` class
    name, ``platform`` name) still to compile take more than :data:`NOTICE_SECONDS`, print the notice
    (once per process) and start the background compile process. Does nothing for ``sensing="ideal"``
    (a few seconds of compiling), with numba's JIT disabled, or for a scenario already prepared in this
    process."""
    global _noticed
    if sensing != "full" or (task, platform) in _prepared:
        return
    _prepared.add((task, platform))
    import numba

    if numba.config.DISABLE_JIT:
        return
    try:
        cold = cold_kernels(task, platform)
    except Exception:  # no manifest entry, an unreadable manifest: compile as usual, without notice
        return
    seconds = sum(row[2] for row in cold)
    if seconds < NOTICE_SECONDS:
        return
    helper = _start_helper(task, platform, cold)
    # the two processes share the work; the background one starts ~1 s later and both compile the library
    # functions their kernels call
    expected = seconds / 2.0 + 2.0 if helper else seconds
    if not _noticed:
        _noticed = True
        how = " on two cores" if helper else ""
        print(
            f"swarm_envs: compiling the numba kernels for the first run (about {max(5, 5 * int(expected / 5 + 0.5))} s{how};"
            " cached afterwards)",
            file=sys.stderr,
            flush=True,
        )
    if helper:
        compile_share(task, platform)


def longest_first(cold: Sequence[tuple[Any, tuple, float, int]]) -> list[tuple[Any, tuple, float, int]]:
    """:func:`cold_kernels` rows in the order both processes compile them: longest recorded compile time
    first (ties in order of first use). Two processes taking the next unclaimed kernel from this list finish
    within about the last kernel's time of each other (longest-processing-time-first scheduling)."""
    return sorted(cold, key=lambda row: -row[2])


def compile_share(task: str, platform: str) -> int:
    """This process's share of a first run with the background process: the scenario's cold kernels longest
    first (:func:`longest_first`), each compiled unless the background process has claimed it; then wait
    until the kernels it is compiling are in the disk cache, so that none is compiled twice.
    The wait ends early when nobody holds the claim of a missing kernel (it is then compiled where it is
    called), and after twice the recorded compile time of the missing kernels plus 10 s (a background
    process starved on a busy machine). Any failure here (a cache it cannot read) leaves the kernels to
    be compiled where they are called. Returns the number of kernels compiled here."""
    done = 0
    try:
        cold = longest_first(cold_kernels(task, platform))
        for dispatcher, argtypes, _, index in cold:
            done += _compile_claimed(dispatcher, argtypes, index)
        missing = [row for row in cold if not _cached(row[0], row[1])]
        deadline = time.monotonic() + 10.0 + 2.0 * sum(row[2] for row in missing)
        while missing and time.monotonic() < deadline:
            if not any(_lock_holder(_claim_path(d, i)) is not None for d, _, _, i in missing):
                break  # nobody is compiling them (yet): the env compiles what it calls
            time.sleep(0.02)
            missing = [row for row in missing if not _cached(row[0], row[1])]
    except Exception:
        pass
    return done


def _cores() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):  # not Linux
        return os.cpu_count() or 1


def _background_wanted() -> bool:
    """Whether to compile in a background process: ``SWARM_ENVS_BACKGROUND_COMPILE`` ``0`` never, ``1``
    always (with two cores or more), unset when a core is idle: the 1-minute load average is below the
    cores minus a half (on a busy machine a second compiling process only competes with this one)."""
    value = os.environ.get(BACKGROUND_VARIABLE, "").strip().lower()
    cores = _cores()
    if value in ("0", "false", "no", "off") or cores < 2:
        return False
    if value in ("1", "true", "yes", "on"):
        return True
    try:
        return os.getloadavg()[0] < cores - 0.5
    except (AttributeError, OSError):  # no load average (Windows)
        return True


def _start_helper(task: str, platform: str, cold: Sequence[tuple[Any, tuple, float]]) -> bool:
    """Start the background compile process for the scenario; whether it was started."""
    if not _background_wanted():
        return False
    if not sys.executable or not cold:
        return False
    try:
        lock = _lock_path(task, platform)
    except Exception:  # no cache path (numba without a disk cache here): compile in this process only
        return False
    if not _acquire(lock):  # taken here, before the process starts: workers starting together start one
        return _lock_holder(lock) is not None  # one is compiling for this cache already
    import numba

    env = dict(os.environ)
    env[BACKGROUND_VARIABLE] = "0"
    if numba.config.CACHE_DIR:
        env["NUMBA_CACHE_DIR"] = str(numba.config.CACHE_DIR)
    package_root = str(Path(__file__).resolve().parent.parent)  # this copy of swarm_envs, not another one
    env["PYTHONPATH"] = os.pathsep.join(filter(None, [package_root, env.get("PYTHONPATH")]))
    try:
        proc = subprocess.Popen(
            [sys.executable, "-m", "swarm_envs._compile._first_run", task, platform],
            env=env, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
        )
    except OSError:
        _release(lock)
        return False
    try:
        lock.write_text(str(proc.pid))  # the lock is the background process's now
    except OSError:
        pass
    _helpers.append(proc)
    threading.Thread(target=proc.wait, daemon=True, name="swarm_envs-compile-wait").start()
    return True


# ----------------------------------------------------------------------------------------- the helper process
def _lock_path(task: str, platform: str) -> Path:
    """The scenario's lock file: in the cache directory of its first recorded kernel (the same path for
    the main and the background process, whatever has been compiled meanwhile)."""
    module, name, _, _ = scenario_kernels(task, platform)[0]
    return Path(_dispatcher(module, name)._cache.cache_path) / LOCK_NAME


def _lock_holder(path: Path) -> int | None:
    """The process id holding the lock at ``path``, or None when free or stale."""
    try:
        pid = int(path.read_text().strip() or 0)
        age = time.time() - path.stat().st_mtime
    except (OSError, ValueError):
        return None
    if age > LOCK_STALE_S:
        return None
    if os.name == "nt":  # os.kill would terminate the process there: trust the age
        return pid
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return None
    except (PermissionError, OSError):
        pass  # exists (another user's), or cannot tell: treat as held
    return pid


def _release(path: Path) -> None:
    try:
        path.unlink()
    except OSError:
        pass


def _acquire(path: Path) -> bool:
    for _ in range(2):
        try:
            fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY)
        except FileExistsError:
            if _lock_holder(path) is not None:
                return False
            try:
                path.unlink()  # stale
            except OSError:
                return False
            continue
        except OSError:
            return False
        with os.fdopen(fd, "w") as f:
            f.write(str(os.getpid()))
        return True
    return False


def compile_in_background(task: str, platform: str) -> int:
    """The background process: compile the scenario's cold kernels longest first (:func:`longest_first`),
    each unless the disk cache has it by then or the main process has claimed it (:func:`compile_share`). A
    function recorded with more than one signature is left to the main process (two processes saving
    different signatures of one function at once could both name their data file alike). Runs at low
    priority (nice 10): it takes a core that is idle, not one the env or other work needs. Returns the
    number compiled."""
    if hasattr(os, "nice"):
        try:
            os.nice(NICE)
        except OSError:
            pass
    lock = _lock_path(task, platform)
    try:
        owner = int(lock.read_text().strip() or 0)
    except (OSError, ValueError):
        owner = 0
    # started by prepare(): the lock names this process (or, for an instant, the one that started it)
    if owner not in (os.getpid(), os.getppid()) and not _acquire(lock):
        return 0
    try:
        cold = cold_kernels(task, platform)
        signatures: dict[int, int] = {}
        for dispatcher, _, _, _ in cold:
            signatures[id(dispatcher)] = signatures.get(id(dispatcher), 0) + 1
        return sum(
            _compile_claimed(dispatcher, argtypes, index)
            for dispatcher, argtypes, _, index in longest_first(cold)
            if signatures[id(dispatcher)] == 1
        )
    finally:
        _release(lock)


def main(argv: Sequence[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    if len(args) != 2:
        print("usage: python -m swarm_envs._compile._first_run TASK PLATFORM", file=sys.stderr)
        return 2
    try:
        compile_in_background(*args)
    except Exception:  # an unknown scenario, no disk cache: nothing to do in the background
        return 1
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
