"""The benchmark table: every task's config trained with several training seeds per RL variant, the scripted
baseline and random actions on the same evaluation seeds, and the cost of faithful sensing.

    python -m swarm_envs.agents.suite [--suite configs/suite/benchmark.yaml] [--output DIR] [--tasks a,b] [--seeds 0,1,2]
                                      [--variants mlp,odometry] [--jobs 2] [--set key=value ...] [--no-sensing-cost]
                                      [--report-only]

A suite file (``configs/suite/benchmark.yaml``) names, per task, a training config and the RL variants to train on
it (each a set of ``--set`` overrides of ``train.py``, e.g. ``agent.odometry: true``), the training seeds, and
the variant whose sensing cost is measured. For every (task, variant, training seed) the suite runs
``train.py`` into ``DIR/<task>/<variant>/seed<S>`` (the policy evaluated on the config's evaluation seeds);
the scripted baseline and random actions are evaluated once per task on the same seeds
(``DIR/<task>/baselines``). For the sensing cost the ``sensing_cost`` variant is also trained with
``env.sensing=ideal`` (``DIR/<task>/<variant>@ideal/seed<S>``) and that model evaluated with full sensing
(``.../eval-full``). A run whose ``results.csv`` exists is kept, so an interrupted suite resumes where it
stopped; ``--tasks``, ``--seeds`` and ``--variants`` run a subset.

Outputs in ``DIR``: ``results.md`` and ``results.csv`` (per task and policy: headline mean over training
seeds with a 95 % t-interval over the training seeds' means, each of which is a mean over the evaluation
seeds; the baselines with a bootstrap interval over evaluation seeds), ``sensing_cost.md``,
``curves_<task>.png`` (mean episode return against robot-steps, mean and min-max band over training seeds)
and ``timing.json`` (wall time per task).
"""

from __future__ import annotations

import argparse
import concurrent.futures
import csv
import json
import math
import os
import subprocess
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from swarm_envs.agents.evaluation import confidence_interval, t_interval

__all__ = ["load_suite", "plan", "execute", "report", "main"]

#: how the suite runs train.py (a subprocess per run)
TRAIN = [sys.executable, "-m", "swarm_envs.agents.train"]


def load_suite(path: str | Path) -> dict[str, Any]:
    """The suite file, checked: ``tasks`` maps each task to ``config``, ``variants`` ({name: overrides}) and
    optionally ``sensing_cost`` (a variant name); ``seeds`` is a list of training seeds."""
    with open(path) as fh:
        suite = yaml.safe_load(fh)
    if not isinstance(suite, dict) or not isinstance(suite.get("tasks"), dict) or not suite["tasks"]:
        raise ValueError(f"suite file '{path}' needs a 'tasks' mapping")
    seeds = suite.setdefault("seeds", [0, 1, 2])
    if not isinstance(seeds, list) or not seeds or not all(isinstance(s, int) and s >= 0 for s in seeds):
        raise ValueError(f"suite file '{path}': 'seeds' must be a list of training seeds (integers >= 0), got {seeds!r}")
    base = Path(path).resolve().parent  # config paths are relative to the suite file
    for task, entry in suite["tasks"].items():
        if not isinstance(entry, dict) or "config" not in entry or not isinstance(entry.get("variants"), dict) or not entry["variants"]:
            raise ValueError(f"suite file '{path}': task {task!r} needs 'config' and a 'variants' mapping")
        config = Path(entry["config"])
        entry["config"] = str(config if config.is_absolute() else base / config)
        for name, sets in entry["variants"].items():
            if not isinstance(sets, dict) or "@" in name or "/" in name:
                raise ValueError(f"suite file '{path}': variant {task}.{name} must be a mapping of overrides (no '@' or '/' in its name)")
        cost = entry.get("sensing_cost")
        if cost is not None and cost not in entry["variants"]:
            raise ValueError(f"suite file '{path}': {task}.sensing_cost names no variant of {task} ({cost!r})")
    return suite


def _sets(overrides: dict[str, Any]) -> list[str]:
    out = []
    for key, value in overrides.items():
        out += ["--set", f"{key}={json.dumps(value) if not isinstance(value, str) else value}"]
    return out


def plan(suite: dict[str, Any], out: Path, tasks: list[str] | None = None, seeds: list[int] | None = None,
         variants: list[str] | None = None, extra: list[str] | None = None, sensing_cost: bool = True) -> list[dict[str, Any]]:
    """The runs of the suite (``train.py`` command lines), in order; each ``{"dir", "argv", "after"}`` (a run
    with ``after`` evaluates the model another run trains); ``sensing_cost=False`` leaves out the sensing-cost
    runs."""
    runs = []
    for task, entry in suite["tasks"].items():
        if tasks and task not in tasks:
            continue
        task_dir = out / task
        common = ["--config", entry["config"], *(extra or [])]
        runs.append({"dir": task_dir / "baselines", "argv": [*common, "--baselines-only"]})
        for name, overrides in entry["variants"].items():
            if variants and name not in variants:
                continue
            for seed in seeds or suite["seeds"]:
                base = [*common, *_sets(overrides), "--set", f"seed={seed}", "--set", "eval.baselines=false"]
                runs.append({"dir": task_dir / name / f"seed{seed}", "argv": base})
                if sensing_cost and entry.get("sensing_cost") == name:
                    ideal = task_dir / f"{name}@ideal" / f"seed{seed}"
                    runs.append({"dir": ideal, "argv": [*base, "--set", "env.sensing=ideal"]})
                    runs.append({"dir": ideal / "eval-full", "after": ideal,
                                 "argv": [*common, *_sets(overrides), "--set", f"seed={seed}", "--set", "eval.baselines=false",
                                          "--set", "env.sensing=full", "--eval-only", str(ideal / "model.zip")]})
    return runs


def job_environment(jobs: int) -> dict[str, str]:
    """The environment of each ``train.py`` run when ``jobs`` run at once: the cores are shared out, so each
    run gets ``cores // jobs`` numba threads (at least 1) unless ``NUMBA_NUM_THREADS`` is set already.
    Results do not depend on the thread count; oversubscribed cores only slow every run down."""
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    env.setdefault("NUMBA_NUM_THREADS", str(max(1, (os.cpu_count() or 1) // max(1, jobs))))
    return env


def _run(run: dict[str, Any], log: Path, env: dict[str, str]) -> tuple[str, int, float]:
    """Run one ``train.py`` command into its directory (its output appended to ``log``)."""
    argv = [*TRAIN, *run["argv"], "--output", str(run["dir"]), "--set", "train.progress_bar=false"]
    t0 = time.perf_counter()
    with open(log, "a") as fh:
        fh.write(f"\n$ {' '.join(argv)}\n")
        fh.flush()
        code = subprocess.call(argv, stdout=fh, stderr=subprocess.STDOUT, env=env)
    return str(run["dir"]), code, time.perf_counter() - t0


def execute(runs: list[dict[str, Any]], out: Path, jobs: int = 1) -> list[tuple[str, int, float]]:
    """Run every run whose ``results.csv`` is missing, ``jobs`` at a time, in plan order; a run that
    evaluates another run's model starts once that run has finished. Returns (directory, exit code,
    seconds) of the runs started."""
    out.mkdir(parents=True, exist_ok=True)
    log = out / "suite.log"
    todo = [r for r in runs if not (Path(r["dir"]) / "results.csv").is_file()]
    pending = {str(r["dir"]) for r in todo}
    done: list[tuple[str, int, float]] = []
    env = job_environment(jobs)
    with concurrent.futures.ThreadPoolExecutor(max_workers=max(1, jobs)) as pool:
        running: dict[concurrent.futures.Future, dict[str, Any]] = {}
        while todo or running:
            ready = [r for r in todo if str(r.get("after")) not in pending]
            for run in ready[: max(1, jobs) - len(running)]:
                todo.remove(run)
                running[pool.submit(_run, run, log, env)] = run
            if not running:  # what is left waits for runs that were not planned (or failed): run it anyway
                running[pool.submit(_run, todo[0], log, env)] = todo.pop(0)
            finished, _ = concurrent.futures.wait(running, return_when=concurrent.futures.FIRST_COMPLETED)
            for future in finished:
                run = running.pop(future)
                pending.discard(str(run["dir"]))
                result = future.result()
                status = "ok" if result[1] == 0 else f"FAILED (exit {result[1]}, see {log})"
                print(f"{result[0]}: {status} in {result[2]:.0f} s", flush=True)
                done.append(result)
    return done


# -- report -----------------------------------------------------------------------------------------------
def _per_seed(path: Path) -> dict[str, dict[str, list[float]]]:
    return json.loads((path / "per_seed.json").read_text()) if (path / "per_seed.json").is_file() else {}


def _fmt(mean: float, lo: float, hi: float, n: int) -> str:
    if not math.isfinite(mean):
        return "n/a"
    text = f"{mean:.3g}"
    if math.isfinite(lo) and math.isfinite(hi):
        text += f" [{lo:.3g}, {hi:.3g}]"
    return text + f" (n={n})"


def _rl_cell(dirs: list[Path], metric: str) -> tuple[float, float, float, int, list[float]]:
    """Headline over training seeds: each seed's mean over its evaluation seeds, then a t-interval."""
    means = []
    for d in dirs:
        values = _per_seed(d).get("ppo", {}).get(metric)
        if values:
            means.append(float(np.nanmean(values)))
    mean, lo, hi = t_interval(means)
    return mean, lo, hi, len(means), means


def _seed_dirs(variant: Path) -> list[Path]:
    """The finished runs (``seed<S>`` with ``per_seed.json``) of one variant's directory."""
    return sorted(p for p in variant.glob("seed*") if (p / "per_seed.json").is_file())


def _curve(run: Path) -> tuple[np.ndarray, np.ndarray] | None:
    """(robot-steps, mean episode return) of one run's ``progress.csv`` (PPO counts decisions: times the
    run's ``agent.action_repeat``)."""
    path = run / "progress.csv"
    if not path.is_file():
        return None
    repeat = int(((yaml.safe_load((run / "config.yaml").read_text()) or {}).get("agent") or {}).get("action_repeat", 1))
    with open(path, newline="") as fh:
        rows = [r for r in csv.DictReader(fh) if r.get("rollout/ep_rew_mean") not in (None, "")]
    if not rows:
        return None
    steps = np.array([float(r["time/total_timesteps"]) for r in rows]) * repeat
    return steps, np.array([float(r["rollout/ep_rew_mean"]) for r in rows])


def report(suite: dict[str, Any], out: Path, tasks: list[str] | None = None) -> str:
    """Write ``results.md``, ``results.csv``, ``sensing_cost.md`` and ``curves_<task>.png`` from the runs
    on disk; returns the Markdown of the results table."""
    from swarm_envs.agents.tasks import headline

    lines = ["| task | headline metric | policy | mean [95 % interval] (n) | eval seeds |", "|---|---|---|---|---|"]
    cost_lines = ["| task | variant | trained ideal, evaluated ideal | trained ideal, evaluated full | trained full, evaluated full |",
                  "|---|---|---|---|---|"]
    csv_rows: list[dict[str, Any]] = []
    for task, entry in suite["tasks"].items():
        if tasks and task not in tasks:
            continue
        best = headline(task)
        if best is None:
            continue
        metric, sign = best
        task_dir = out / task
        base = _per_seed(task_dir / "baselines")
        n_eval = len(base.get("seeds", []))
        curves: dict[str, list[tuple[np.ndarray, np.ndarray]]] = {}
        for name in entry["variants"]:
            dirs = _seed_dirs(task_dir / name)
            mean, lo, hi, n, means = _rl_cell(dirs, metric)
            if n:
                n_eval = n_eval or len(_per_seed(dirs[0]).get("seeds", []))
                lines.append(f"| {task} | {metric} ({'higher' if sign > 0 else 'lower'} is better) | RL: {name} | {_fmt(mean, lo, hi, n)} training seeds | {n_eval} |")
                csv_rows.append({"task": task, "metric": metric, "policy": f"rl:{name}", "mean": mean, "ci_low": lo, "ci_high": hi,
                                 "n": n, "interval": "t over training seeds", "per_training_seed": ";".join(f"{m:.6g}" for m in means)})
            curves[name] = [c for c in map(_curve, dirs) if c is not None]
        for policy in ("scripted", "random"):
            values = base.get(policy, {}).get(metric)
            if values:
                mean, lo, hi = confidence_interval(values)
                lines.append(f"| {task} | {metric} | {policy} | {_fmt(mean, lo, hi, len(values))} evaluation seeds | {len(values)} |")
                csv_rows.append({"task": task, "metric": metric, "policy": policy, "mean": mean, "ci_low": lo, "ci_high": hi,
                                 "n": len(values), "interval": "bootstrap over evaluation seeds", "per_training_seed": ""})
        cost = entry.get("sensing_cost")
        if cost:
            ideal_dirs = _seed_dirs(task_dir / f"{cost}@ideal")
            full_eval = [d / "eval-full" for d in ideal_dirs if (d / "eval-full" / "per_seed.json").is_file()]
            full_dirs = _seed_dirs(task_dir / cost)
            cells = []
            for dirs in (ideal_dirs, full_eval, full_dirs):
                mean, lo, hi, n, _ = _rl_cell(dirs, metric)
                cells.append(_fmt(mean, lo, hi, n) if n else "not run")
            cost_lines.append(f"| {task} ({metric}{'' if sign > 0 else ', lower is better'}) | {cost} | " + " | ".join(cells) + " |")
        _plot_curves(curves, out / f"curves_{task}.png", f"{task}: mean episode return per robot (mean, min-max over training seeds)")
    note = ("\n\nRL rows: mean over training seeds of each seed's mean over the evaluation seeds, with a 95 % Student-t "
            "interval over the training seeds (n = training seeds). Baselines: bootstrap 95 % interval over the "
            "evaluation seeds. Every policy of a task is evaluated on the same evaluation seeds.\n")
    table = "\n".join(lines) + note
    (out / "results.md").write_text(table)
    with open(out / "results.csv", "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=["task", "metric", "policy", "mean", "ci_low", "ci_high", "n", "interval", "per_training_seed"])
        writer.writeheader()
        writer.writerows(csv_rows)
    (out / "sensing_cost.md").write_text("\n".join(cost_lines) + "\n\nCells: headline mean [95 % t-interval over training seeds] (n = training seeds).\n")
    return table


def _plot_curves(curves: dict[str, list[tuple[np.ndarray, np.ndarray]]], path: Path, title: str) -> None:
    curves = {k: v for k, v in curves.items() if v}
    if not curves:
        return
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(5.5, 3.4))
    for name, runs in curves.items():
        end = min(r[0][-1] for r in runs)
        grid = np.linspace(max(r[0][0] for r in runs), end, 60)
        ys = np.array([np.interp(grid, s, y) for s, y in runs])
        line = ax.plot(grid, ys.mean(axis=0), label=f"{name} ({len(runs)} seeds)", lw=1.2)[0]
        ax.fill_between(grid, ys.min(axis=0), ys.max(axis=0), color=line.get_color(), alpha=0.2, lw=0)
    ax.set_xlabel("robot-steps")
    ax.set_ylabel("mean episode return")
    ax.set_title(title, fontsize=8)
    ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def _names(text: str | None) -> list[str] | None:
    return [t for t in text.split(",") if t] if text else None


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--suite", default="configs/suite/benchmark.yaml", help="suite file (default: configs/suite/benchmark.yaml)")
    parser.add_argument("--output", default="runs/suite", help="output directory (runs are kept: a rerun resumes)")
    parser.add_argument("--tasks", default=None, help="comma list of tasks of the suite file (default: all)")
    parser.add_argument("--seeds", default=None, help="comma list of training seeds (default: the suite file's)")
    parser.add_argument("--variants", default=None, help="comma list of variant names (default: all)")
    parser.add_argument("--jobs", type=int, default=max(1, (os.cpu_count() or 1)), help="train.py runs at a time (default: one per core)")
    parser.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                        help="override for every run, e.g. train.total_timesteps=20000 (repeatable)")
    parser.add_argument("--no-sensing-cost", action="store_true", help="leave out the sensing-cost runs (trained with ideal sensing)")
    parser.add_argument("--report-only", action="store_true", help="only rebuild the tables and curves from the runs on disk")
    args = parser.parse_args(argv)
    try:
        suite = load_suite(args.suite)
        seeds = [int(s) for s in _names(args.seeds)] if args.seeds else None
    except (OSError, ValueError, yaml.YAMLError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    tasks, variants = _names(args.tasks), _names(args.variants)
    unknown = sorted(set(tasks or []) - set(suite["tasks"]))
    if unknown:
        print(f"error: unknown task(s) {unknown}; the suite has {sorted(suite['tasks'])}", file=sys.stderr)
        return 2
    out = Path(args.output)
    extra = [x for kv in args.overrides for x in ("--set", kv)]
    failed = 0
    if not args.report_only:
        t0 = time.perf_counter()
        started = execute(plan(suite, out, tasks, seeds, variants, extra, sensing_cost=not args.no_sensing_cost), out, args.jobs)
        failed = sum(code != 0 for _, code, _ in started)
        timing_path = out / "timing.json"
        timing = json.loads(timing_path.read_text()) if timing_path.is_file() else {}
        for task in suite["tasks"]:
            spent = sum(s for d, _, s in started if Path(d).is_relative_to(out / task))
            if spent:
                timing[task] = round(timing.get(task, 0.0) + spent, 1)
        timing["jobs"] = args.jobs
        timing_path.write_text(json.dumps(timing, indent=1))
        print(f"ran {len(started)} runs in {time.perf_counter() - t0:.0f} s ({failed} failed)")
    print(report(suite, out, tasks))
    print(f"wrote {out / 'results.md'}, {out / 'results.csv'}, {out / 'sensing_cost.md'}, {out}/curves_<task>.png")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
