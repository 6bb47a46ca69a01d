"""The first run: the README's first Python snippet in a fresh process on an empty numba cache.

    python benchmarks/bench_first_run.py [--runs 3] [--background | --no-background] [--root CHECKOUT] [--json]

Each run starts ``python`` on the snippet (``README.md``, the first ```` ```python ```` block under "Using
the environments": make, reset, one episode of random actions) with ``NUMBA_CACHE_DIR`` a new empty
directory, so every kernel it calls compiles, and times it from start to exit (wall clock, as a user
waits for it). Then the same snippet runs again on the now filled cache (the warm time). Before the
next run the benchmark waits for the background compile process the first run may have started
(:mod:`swarm_envs._compile._first_run`) to finish, so runs do not overlap. Prints the median of the runs, each
run, whether the "compiling" line was printed, and the load averages; ``--json`` prints one JSON object.
The background process starts only when a core is idle (as for a user); ``--background`` starts it
whatever the load (``SWARM_ENVS_BACKGROUND_COMPILE=1``), ``--no-background`` never (``=0``, compiling
in the snippet's process only); ``--root`` runs the
snippet of another checkout with its own ``swarm_envs`` (to compare two versions on one machine).
"""

from __future__ import annotations

import argparse
import json
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
NOTICE = "swarm_envs: compiling the numba kernels"
LOCK_NAME = "swarm_envs_first_run.lock"  # swarm_envs._compile._first_run.LOCK_NAME


def readme_snippet(readme: Path = ROOT / "README.md") -> str:
    """The first ```python block after the "Using the environments" heading of the README."""
    text = readme.read_text(encoding="utf-8")
    start = text.index("## Using the environments")
    match = re.search(r"```python\n(.*?)```", text[start:], re.S)
    if match is None:
        raise ValueError("README.md has no ```python block under 'Using the environments'")
    return match.group(1)


def _run(script: Path, cache: Path, background: bool | None, root: Path = ROOT) -> tuple[float, str]:
    env = {**os.environ, "NUMBA_CACHE_DIR": str(cache),
           "PYTHONPATH": os.pathsep.join(filter(None, [str(root), os.environ.get("PYTHONPATH")]))}
    env.pop("SWARM_ENVS_BACKGROUND_COMPILE", None)
    if background is not None:
        env["SWARM_ENVS_BACKGROUND_COMPILE"] = "1" if background else "0"
    t0 = time.perf_counter()
    proc = subprocess.run([sys.executable, str(script)], cwd=root, env=env, capture_output=True, text=True)
    wall = time.perf_counter() - t0
    if proc.returncode != 0:
        raise RuntimeError(f"the README snippet failed:\n{proc.stderr}")
    return wall, proc.stderr


def _wait_for_background(cache: Path, timeout: float = 300.0) -> float:
    """Wait until no background compile process holds a lock in ``cache``; seconds waited."""
    t0 = time.perf_counter()
    time.sleep(0.5)  # the process creates its lock shortly after it starts
    while any(cache.rglob(LOCK_NAME)) and time.perf_counter() - t0 < timeout:
        time.sleep(0.5)
    return time.perf_counter() - t0


def measure(runs: int = 3, background: bool | None = None, root: Path = ROOT) -> dict:
    """``runs`` cold runs of the README snippet of ``root``, each followed by a warm run on its cache
    (``background``: None as for a user, True/False forces the background compile process on/off)."""
    load_before = os.getloadavg()
    cold, warm, notices, two = [], [], [], []
    with tempfile.TemporaryDirectory() as tmp:
        script = Path(tmp) / "readme_snippet.py"
        script.write_text(readme_snippet(root / "README.md"), encoding="utf-8")
        for i in range(runs):
            cache = Path(tmp) / f"cache{i}"
            cache.mkdir()
            seconds, stderr = _run(script, cache, background, root)
            cold.append(seconds)
            notices.append(NOTICE in stderr)
            two.append("on two cores" in stderr)
            _wait_for_background(cache)
            warm.append(_run(script, cache, background, root)[0])
            print(f"run {i + 1}: first run {cold[-1]:.1f} s, warm {warm[-1]:.1f} s", file=sys.stderr, flush=True)
    return {
        "runs": runs, "background": background, "cold_s": cold, "warm_s": warm,
        "cold_median_s": statistics.median(cold), "warm_median_s": statistics.median(warm),
        "notice_printed": notices, "background_started": two, "cores": os.cpu_count(),
        "load_before": list(load_before), "load_after": list(os.getloadavg()),
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--runs", type=int, default=3, help="cold runs (each with its own empty cache; default 3)")
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument("--background", action="store_true", help="start the background compile process whatever the load (=1)")
    mode.add_argument("--no-background", action="store_true", help="compile in the snippet's process only (=0)")
    parser.add_argument("--root", type=Path, default=ROOT, help="checkout whose README snippet and swarm_envs run (default: this one)")
    parser.add_argument("--json", action="store_true", help="print one JSON object")
    args = parser.parse_args(argv)
    background = True if args.background else False if args.no_background else None
    res = measure(max(1, args.runs), background=background, root=args.root.resolve())
    if args.json:
        print(json.dumps(res))
        return 0
    load = lambda v: " / ".join(f"{x:.2f}" for x in v)  # noqa: E731
    print(f"README snippet on an empty numba cache ({res['cores']} cores; background compile process in "
          f"{sum(res['background_started'])}/{res['runs']} runs): median {res['cold_median_s']:.1f} s of {res['runs']} runs "
          f"({', '.join(f'{s:.1f}' for s in res['cold_s'])} s); warm {res['warm_median_s']:.1f} s; "
          f"'compiling' line printed: {sum(res['notice_printed'])}/{res['runs']}; "
          f"load {load(res['load_before'])} before, {load(res['load_after'])} after")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
