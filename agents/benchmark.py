"""Scripted baselines vs random on the swarm tasks, with bootstrap 95 % confidence intervals.

    python -m swarm_envs.agents.benchmark [--task aggregation|flocking|centroid_seeking ...] [--episodes N]
                               [--sensing full|ideal] [--max-cycles T] [--n-robots N] [--json]

``--task`` is repeatable or a comma list (default: every task). For each task the task's scripted controller (:data:`agents.scripted.TASK_SCRIPTED`), the [T20] Alg. 1
random walk and uniform random actions run on the same seeds ``0 .. N-1``; on flocking also the sorted
following controller ([L] Alg. 6, with 4 message bits for the ids). Prints one table per task:
``mean [95 % bootstrap percentile interval]`` per metric (see :mod:`swarm_envs.agents.evaluation` for the reductions) and the wall time.
Cost: ~5 ms per env step with ``sensing="full"`` (10 robots), so ``--episodes 20 --max-cycles 300`` takes
~4.5 min on 2 cores and the defaults (30 episodes x 500 steps) ~15 min; ``--sensing ideal`` is ~8x faster.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from typing import Any

import numpy as np

from swarm_envs.agents.evaluation import PRIMARY_METRIC, TASK_METRICS, evaluate, markdown_table, random_factory, summarise
from swarm_envs.agents.scripted import TASK_SCRIPTED, make_scripted

__all__ = ["run_benchmark", "main"]


def run_benchmark(
    episodes: int, sensing: str, max_cycles: int | None, n_robots: int | None, tasks: list[str] | None = None
) -> dict[str, Any]:
    """``{task: {"rows": summary rows, "seconds": {policy: s}, "env": kwargs}}`` for ``tasks`` (default: all)."""
    out: dict[str, Any] = {}
    seeds = list(range(episodes))
    for task in tasks or list(TASK_SCRIPTED):
        scripted = TASK_SCRIPTED[task]
        kwargs: dict[str, Any] = {"sensing": sensing}
        if max_cycles is not None:
            kwargs["max_cycles"] = max_cycles
        if n_robots is not None:
            kwargs["n_robots"] = n_robots
        candidates: dict[str, tuple[dict, Any]] = {
            scripted: (kwargs, lambda env, name=scripted: make_scripted(name, env)),
            "random_walk": (kwargs, lambda env: make_scripted("random_walk", env)),
            "random": (kwargs, random_factory),
        }
        if task == "flocking":
            candidates["sorted_following"] = ({**kwargs, "message_bits": 4}, lambda env: make_scripted("sorted_following", env))
        results, seconds = {}, {}
        for name, (kw, factory) in candidates.items():
            t0 = time.perf_counter()
            results[name] = evaluate(task, kw, factory, seeds, progress=True, desc=f"{task}/{name}")
            seconds[name] = time.perf_counter() - t0
        out[task] = {"rows": summarise(results), "seconds": seconds, "env": kwargs,
                     "per_seed": {p: {m: v.tolist() for m, v in r.items()} for p, r in results.items()}}
    return out


def _json_safe(obj: Any) -> Any:
    """Plain JSON: NaN (no interval with one seed) -> null, numpy scalars -> float."""
    if isinstance(obj, dict):
        return {k: _json_safe(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_json_safe(v) for v in obj]
    if isinstance(obj, (float, np.floating)):
        return None if not np.isfinite(obj) else float(obj)
    return obj


def parse_tasks(values: list[str]) -> list[str]:
    """Task names from repeated and/or comma-separated ``--task`` values (order kept, duplicates dropped)."""
    names = [t.strip() for v in values for t in v.split(",") if t.strip()]
    unknown = [t for t in names if t not in TASK_SCRIPTED]
    if unknown:
        raise ValueError(f"unknown task(s) {unknown}; available: {list(TASK_SCRIPTED)}")
    return list(dict.fromkeys(names))


def main(argv: list[str] | None = None) -> int:
    """Command line of ``python -m swarm_envs.agents.benchmark``; returns the exit code."""
    parser = argparse.ArgumentParser(description="Scripted swarm baselines vs random, with bootstrap 95% CIs")
    parser.add_argument("--task", action="append", default=[], metavar="TASK",
                        help=f"task to run, repeatable or a comma list; one of {', '.join(TASK_SCRIPTED)} (default: all)")
    parser.add_argument("--episodes", type=int, default=30, help="seeds per policy and task (default 30)")
    parser.add_argument("--sensing", choices=("full", "ideal"), default="full")
    parser.add_argument("--max-cycles", type=int, default=None, help="episode length (default: the env's 500)")
    parser.add_argument("--n-robots", type=int, default=None, help="agents per env (default: the task's)")
    parser.add_argument("--json", action="store_true", help="print the results as JSON")
    args = parser.parse_args(argv)
    if args.episodes < 1:
        parser.error("--episodes must be >= 1 (>= 2 for a confidence interval)")
    if args.max_cycles is not None and args.max_cycles < 1:
        parser.error("--max-cycles must be >= 1")
    try:
        tasks = parse_tasks(args.task)
    except ValueError as err:
        parser.error(str(err))
    results = run_benchmark(args.episodes, args.sensing, args.max_cycles, args.n_robots, tasks=tasks or None)
    if args.json:
        print(json.dumps(_json_safe(results)))
        return 0
    for task, res in results.items():
        primary, sign = PRIMARY_METRIC[task]
        print(f"\n## {task}  (env {res['env']}; headline `{primary}`, {'higher' if sign > 0 else 'lower'} is better; "
              f"reductions {TASK_METRICS[task]})\n")
        print(markdown_table(res["rows"], n_seeds=args.episodes), end="")
        print("wall time: " + ", ".join(f"{p} {s:.1f} s" for p, s in res["seconds"].items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
