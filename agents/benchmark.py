"""Scripted baselines vs random on the swarm tasks, with bootstrap 95 % confidence intervals.

    python -m swarm_envs.agents.benchmark [--task TASK ...] [--import MODULE ...] [--episodes N]
                               [--sensing full|ideal] [--max-cycles T] [--n-robots N] [--json]

``--task`` (an env id or a short name such as ``flocking``) is repeatable or a comma list (default: every
registered task with a scripted baseline); ``--import`` imports the modules (or ``.py`` files) that
register tasks of your own first. For each task the task's scripted controller (``Task.SCRIPTED_POLICY``), the [T20] Alg. 1
random walk and uniform random actions run on the same seeds ``0 .. N-1``. Prints one table per task:
``mean [95 % bootstrap percentile interval]`` per metric (see :mod:`swarm_envs.agents.evaluation` for the reductions) and the wall time.
Cost: ~5 ms per env step with ``sensing="full"`` (10 robots), so ``--episodes 20 --max-cycles 300`` takes
~4.5 min on 2 cores and the defaults (30 episodes x 500 steps) ~15 min; ``--sensing ideal`` is ~8x faster.
"""

from __future__ import annotations

import json
import sys
import time
from typing import Any

import numpy as np

from swarm_envs.agents.config import progress_bar_on
from swarm_envs.agents.evaluation import evaluate, markdown_table, random_factory, summarise
from swarm_envs.agents.scripted import make_scripted, scripted_class
from swarm_envs.agents.tasks import SHORT_NAMES, env_id, headline, import_modules, metric_reductions, scripted_policy
from swarm_envs._text import shown
from swarm_envs.registry import list_envs
from swarm_envs.tasks.settings import COMMON_SETTINGS, Int
from swarm_envs.tasks.settings_cli import OneLineArgumentParser, cli_type

__all__ = ["run_benchmark", "main"]


def default_tasks() -> list[str]:
    """The suite's short names, then every other registered id whose task has a scripted baseline."""
    ids = set(SHORT_NAMES.values())
    return list(SHORT_NAMES) + [i for i in list_envs() if i not in ids and scripted_policy(i) is not None]


def run_benchmark(
    episodes: int, sensing: str, max_cycles: int | None, n_robots: int | None, tasks: list[str] | None = None
) -> dict[str, Any]:
    """``{task: {"rows": summary rows, "seconds": {policy: s}, "env": kwargs}}`` for ``tasks`` (default:
    :func:`default_tasks`)."""
    out: dict[str, Any] = {}
    seeds = list(range(episodes))
    for task in tasks or default_tasks():
        scripted = scripted_policy(task)
        kwargs: dict[str, Any] = {"sensing": sensing}
        if max_cycles is not None:
            kwargs["max_cycles"] = max_cycles
        if n_robots is not None:
            kwargs["n_robots"] = n_robots
        candidates: dict[str, tuple[dict, Any]] = {}
        if scripted is not None:
            candidates[scripted_class(scripted).name] = (kwargs, lambda env, name=scripted: make_scripted(name, env))
        candidates["random_walk"] = (kwargs, lambda env: make_scripted("random_walk", env))
        candidates["random"] = (kwargs, random_factory)
        results, seconds = {}, {}
        for name, (kw, factory) in candidates.items():
            t0 = time.perf_counter()
            results[name] = evaluate(task, kw, factory, seeds, progress=progress_bar_on("auto"), desc=f"{task}/{name}")
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
    """Task names from repeated and/or comma-separated ``--task`` values (order kept, duplicates dropped);
    ``ValueError`` for an unknown one, or a value with an empty name (``--task ''``, ``--task ','``)."""
    for value in values:
        if not all(t.strip() for t in value.split(",")):
            raise ValueError(
                f"--task {shown(value)} has an empty task name; give env ids or short names ({', '.join(SHORT_NAMES)}), "
                "repeated or comma-separated, or leave --task out for every task with a scripted baseline"
            )
    names = [t.strip() for v in values for t in v.split(",")]
    for name in names:
        env_id(name)
    return list(dict.fromkeys(names))


def main(argv: list[str] | None = None) -> int:
    """Command line of ``python -m swarm_envs.agents.benchmark``; returns the exit code."""
    parser = OneLineArgumentParser(prog="swarm-benchmark", description="Scripted swarm baselines vs random, with bootstrap 95% CIs")
    parser.add_argument("--task", action="append", default=[], metavar="TASK",
                        help=f"task to run (env id or one of {', '.join(SHORT_NAMES)}), repeatable or a comma list "
                             "(default: every task with a scripted baseline)")
    parser.add_argument("--import", dest="imports", action="append", default=[], metavar="MODULE",
                        help="module or .py file to import first (one that registers tasks of your own); repeatable")
    episodes = Int(30, "seeds per policy and task", low=1, high=100_000)
    parser.add_argument("--episodes", type=cli_type(episodes, "--episodes"), default=30, help="seeds per policy and task (default 30)")
    parser.add_argument("--sensing", choices=("full", "ideal"), default="full")
    parser.add_argument("--max-cycles", type=cli_type(COMMON_SETTINGS["max_cycles"], "--max-cycles"), default=None,
                        help="episode length (default: the env's 500)")
    parser.add_argument("--n-robots", type=cli_type(COMMON_SETTINGS["n_robots"], "--n-robots"), default=None,
                        help="agents per env (default: the task's)")
    parser.add_argument("--json", action="store_true", help="print the results as JSON")
    args = parser.parse_args(argv)
    try:
        import_modules(args.imports)
        tasks = parse_tasks(args.task)
    except (ImportError, ValueError) as err:
        parser.error(str(err))
    try:
        results = run_benchmark(args.episodes, args.sensing, args.max_cycles, args.n_robots, tasks=tasks or None)
    except (ValueError, TypeError) as err:  # settings the env refuses (e.g. robots that do not fit): one line
        parser.error(str(err))
    if args.json:
        print(json.dumps(_json_safe(results)))
        return 0
    for task, res in results.items():
        best = headline(task)
        about = f"headline `{best[0]}`, {'higher' if best[1] > 0 else 'lower'} is better; " if best else ""
        print(f"\n## {task}  (env {res['env']}; {about}reductions {metric_reductions(task)})\n")
        print(markdown_table(res["rows"], n_seeds=args.episodes), end="")
        print("wall time: " + ", ".join(f"{p} {s:.1f} s" for p, s in res["seconds"].items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
