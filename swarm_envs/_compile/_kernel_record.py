"""Recording the kernels each scenario compiles: ``python -m swarm_envs._compile._kernel_record``.

Every scenario of :data:`RECORD_SCENARIOS` runs one episode in a fresh process with an empty numba cache,
and the kernels it compiles from Python, with their argument types (:func:`swarm_envs._compile._first_run.encode_type`)
and the process time each compile took, are written in order of first use to
``swarm_envs/_compile/_kernel_manifest.py``, which :mod:`swarm_envs._compile._first_run` reads. Run it after changing which
kernels the sensing stack calls or their argument types (``tests/compile/test_first_run.py`` checks that every
recorded kernel still exists).
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from swarm_envs._compile._first_run import BACKGROUND_VARIABLE, encode_type

__all__ = ["RECORD_SCENARIOS", "record"]

#: (env id, platform) of each recorded scenario (modelled sensing): aggregation on every platform, each
#: other task on its default platform; another pairing uses the recording of its platform
RECORD_SCENARIOS = (
    ("swarm_envs/Aggregation-v0", "epuck"),
    ("swarm_envs/Aggregation-v0", "droplet"),
    ("swarm_envs/Aggregation-v0", "rone"),
    ("swarm_envs/Flocking-v0", "epuck"),
    ("swarm_envs/CentroidSeeking-v0", "epuck"),
    ("swarm_envs/SortedFollowing-v0", "rone"),
    ("swarm_envs/ParityClustering-v0", "rone"),
    ("swarm_envs/MidAngleNavigation-v0", "rone"),
)


def _record_one(env_id: str, platform: str, steps: int) -> list[tuple[str, str, tuple[str, ...], float]]:
    """Run one episode of ``env_id`` on ``platform`` in this process (its cache must be empty) and return
    the kernels compiled from Python, in order: (module, function, argument types, process seconds)."""
    from numba.core import event

    import swarm_envs

    calls: list[tuple[str, str, tuple[str, ...], float]] = []
    stack: list[tuple[bool, float]] = []

    class Listener(event.Listener):
        def on_start(self, ev: Any) -> None:
            stack.append((ev.data["dispatcher"].py_func.__module__.startswith("swarm_envs."), time.process_time()))

        def on_end(self, ev: Any) -> None:
            ours, t0 = stack.pop()
            if ours and not any(o for o, _ in stack):  # compiled from Python, not as a callee of another kernel
                func = ev.data["dispatcher"].py_func
                encoded = tuple(encode_type(t) for t in ev.data["args"])
                if None not in encoded:
                    calls.append((func.__module__, func.__qualname__, encoded, time.process_time() - t0))

    event.register("numba:compile", Listener())
    env = swarm_envs.make(env_id, platform=platform)
    env.reset(seed=0)
    for i, agent in enumerate(env.possible_agents):
        env.action_space(agent).seed(i)
    for _ in range(steps):
        if not env.agents:
            break
        env.step({a: env.action_space(a).sample() for a in env.agents})
    env.close()
    return calls


def record(path: Path, scenarios: Sequence[tuple[str, str]] = RECORD_SCENARIOS, steps: int = 500) -> None:
    """Record every scenario in a fresh process with an empty cache and write the manifest module at
    ``path`` after each (so an interrupted recording keeps what it has)."""
    from swarm_envs.registry import task_class

    kernels: list[tuple[str, str, tuple[str, ...]]] = []
    table: dict[tuple[str, str], list[tuple[int, float]]] = {}
    for env_id, platform in scenarios:
        with tempfile.TemporaryDirectory() as cache:
            env = {**os.environ, "NUMBA_CACHE_DIR": cache, BACKGROUND_VARIABLE: "0"}
            code = f"import json, swarm_envs._compile._kernel_record as r; print(json.dumps(r._record_one({env_id!r}, {platform!r}, {steps})))"
            out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True).stdout
        calls = json.loads(out.strip().splitlines()[-1])
        task = task_class(env_id).__name__
        rows = []
        for module, name, encoded, seconds in calls:
            entry = (module, name, tuple(encoded))
            if entry not in kernels:
                kernels.append(entry)
            rows.append((kernels.index(entry), round(seconds, 2)))
        table[(task, platform)] = rows
        print(f"{env_id} {platform}: {len(rows)} kernels, {sum(s for _, s in rows):.1f} s", flush=True)
        _write_manifest(path, kernels, table)


def _write_manifest(path: Path, kernels: list, table: dict) -> None:
    import numba

    lines = [
        '"""The numba kernels each scenario compiles, in order of first use (:mod:`swarm_envs._compile._first_run`).',
        "",
        "Written by ``python -m swarm_envs._compile._kernel_record``; do not edit. ``KERNELS``: (module, function,",
        "argument types) of kernels called from Python; ``SCENARIOS``: (task class, platform) -> (index into",
        'KERNELS, process seconds its compile took on the recording machine) in order of first use."""',
        "",
        f"NUMBA_VERSION = {numba.__version__!r}",
        "",
        "KERNELS = [",
        *(f"    {entry!r}," for entry in kernels),
        "]",
        "",
        "SCENARIOS = {",
        *(f"    {key!r}: {tuple(rows)!r}," for key, rows in table.items()),
        "}",
        "",
    ]
    path.write_text("\n".join(lines), encoding="utf-8")


def main(argv: Sequence[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    if args:
        print("usage: python -m swarm_envs._compile._kernel_record   (records every scenario, writes swarm_envs/_compile/_kernel_manifest.py)", file=sys.stderr)
        return 2
    record(Path(__file__).with_name("_kernel_manifest.py"))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
