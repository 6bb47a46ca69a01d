"""The environment pages' numbers: each task's showcase scene (the GIF's) over several seeds, shown policy against random.

    python benchmarks/showcase_seeds.py [--seeds 8] [--json PATH]

``swarm-demo --all`` draws one episode per task (seed 0, or the preset's seed) with the settings of
:data:`swarm_envs.demo.SHOWCASE` and prints its headline metric beside the random policy's on the same seed.
This script runs the same scenes without drawing, on seeds ``0 .. N-1``, with the shown policy, the task's
scripted baseline (when the showcase shows another controller) and the random policy, and prints every
metric (reduced as the evaluation reduces it): the mean over the seeds and, in brackets, the showcase
seed's own value. docs/environments/<task>.md quote them (``--json`` writes them, the file
``benchmarks/results/showcase_seeds.json`` that tests/integration/test_showcase_quotes.py compares the pages with).
"""

from __future__ import annotations

import argparse
import json
import os
import time
from pathlib import Path
from typing import Any

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from swarm_envs.agents.evaluation import make_env, run_episode  # noqa: E402
from swarm_envs.demo import _headline, demo_tasks, make_policy, showcase_settings  # noqa: E402


def measure(task: str, seeds: int) -> dict[str, Any]:
    """One task's reduced metrics per seed for the shown policy, the task's scripted baseline (when the
    showcase shows another controller) and the random policy, with their means over the seeds."""
    env_kwargs, shown, showcase_seed = showcase_settings(task)
    policies: dict[str, Any] = {}
    headline = None
    for kind in dict.fromkeys((shown, "scripted", "random")):
        runs = []
        for seed in range(seeds):
            env = make_env(task, **env_kwargs)
            try:
                policy = make_policy(kind, env)
                runs.append({k: float(v) for k, v in run_episode(env, policy, seed, task).items()})
            finally:
                env.close()
        headline = headline or _headline(task, runs[0])[0]
        label = kind if kind != "scripted" or shown == "scripted" else f"scripted ({getattr(policy, 'name', 'baseline')})"
        policies[label] = {
            "mean": {k: float(np.mean([run[k] for run in runs])) for k in runs[0]},
            "showcase_seed": runs[showcase_seed] if showcase_seed < seeds else None,
            "per_seed": runs,
        }
    return {"settings": env_kwargs, "shown_policy": shown, "headline": headline, "showcase_seed": showcase_seed, "policies": policies}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=8, help="seeds 0 .. N-1 (default 8)")
    parser.add_argument("--json", type=Path, default=None, help="also write the numbers to this file")
    args = parser.parse_args(argv)
    if args.seeds < 1:
        parser.error(f"--seeds must be >= 1, got {args.seeds}")
    start = time.perf_counter()
    out: dict[str, Any] = {"seeds": args.seeds, "tasks": {}}
    for task in demo_tasks():
        result = measure(task, args.seeds)
        out["tasks"][task] = result
        print(f"{task} (seeds 0-{args.seeds - 1}; the showcase seed {result['showcase_seed']} in brackets)", flush=True)
        for kind, p in result["policies"].items():
            seed_values = p["showcase_seed"] or {}
            cells = ", ".join(f"{k} {v:.3f}" + (f" [{seed_values[k]:.3f}]" if k in seed_values else "") for k, v in p["mean"].items())
            print(f"  {kind}: {cells}", flush=True)
    out["seconds"] = time.perf_counter() - start
    if args.json is not None:
        args.json.write_text(json.dumps(out, indent=1) + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
