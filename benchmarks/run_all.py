"""Run every benchmark in this folder in turn and print their tables, or write docs/performance.md.

    python benchmarks/run_all.py [--skip NAME ...]          # every bench_*.py, its own table each
    python benchmarks/run_all.py --markdown [PATH]           # measure and write the performance page

Each benchmark is its own script (``bench_*.py``) and can be run alone with its own options.

``--markdown`` (default PATH ``docs/performance.md``) measures the batched core's rollout throughput
(``bench_vec.py --json``, one fresh process per swarm size, so a large scene is not measured in a process
that has just stepped thousands of robots), VMAS's flocking in the same run when ``vmas`` is installed
(also alternated with N = 10 at each thread count and sensing, ``bench_vec.py --interleave``),
the first run of the README's first snippet on an empty numba cache (``bench_first_run.py --json``), the
ParallelEnv and TorchRL views against ``make_vec`` (``bench_views.py --json``, ``bench_torchrl.py --json``),
and the training rate of the default PPO config (``train.py --config configs/aggregation.yaml``, when
stable-baselines3 and torch are installed) with its split into env steps and PPO's own work
(``bench_train_stages.py``), and writes the page: the machine, the tables and the
commands that reproduce them. ``--sizes``, ``--no-first-run`` and ``--no-training`` make a shorter run;
the page says what was measured.
"""

from __future__ import annotations

import argparse
import datetime
import json
import os
import platform
import subprocess
import sys
import tempfile
from importlib import metadata
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
#: swarm sizes of bench_vec.py's grid (N = 10 and 100 at B = 1, 16, 64, 256 copies; N = 1000 at B = 1)
SIZES = (10, 100, 1000)
TRAIN_CONFIG = "configs/aggregation.yaml"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--skip", nargs="*", default=[], help="benchmark names to skip, e.g. torch_threads")
    parser.add_argument("--markdown", nargs="?", const=str(ROOT / "docs" / "performance.md"), metavar="PATH",
                        help="measure and write the performance page (default docs/performance.md)")
    parser.add_argument("--sizes", type=int, nargs="+", default=list(SIZES), choices=SIZES,
                        help="with --markdown: swarm sizes to measure (default all)")
    parser.add_argument("--no-training", action="store_true", help="with --markdown: skip the training-rate run")
    parser.add_argument("--no-first-run", action="store_true", help="with --markdown: skip the first-run (cold numba cache) runs")
    parser.add_argument("--no-vmas", action="store_true", help="with --markdown: do not time VMAS even if installed")
    parser.add_argument("--no-adapters", action="store_true", help="with --markdown: skip the ParallelEnv and TorchRL ratios")
    parser.add_argument("--threads", type=int, nargs="+", default=None,
                        help="with --markdown: thread counts of the throughput table (default 1 and 2, at most the cores)")
    args = parser.parse_args(argv)
    if args.markdown:
        threads = args.threads or sorted({1, min(2, os.cpu_count() or 1)})
        return write_page(Path(args.markdown), args.sizes, training=not args.no_training, vmas=not args.no_vmas,
                          first_run=not args.no_first_run, adapters=not args.no_adapters, threads=threads)
    status = 0
    for script in sorted(HERE.glob("bench_*.py")):
        name = script.stem.removeprefix("bench_")
        if name in args.skip:
            continue
        print(f"\n=== {script.name} ===", flush=True)
        status |= subprocess.call([sys.executable, str(script)])
    return status


# --------------------------------------------------------------------------------------------- measuring
def _env() -> dict[str, str]:
    return {**os.environ, "PYTHONPATH": os.pathsep.join(filter(None, [str(ROOT), os.environ.get("PYTHONPATH")]))}


def _run_json(cmd: list[str]) -> dict:
    """The JSON object a benchmark script prints last, run as ``cmd`` from the repository root."""
    print("running:", " ".join(cmd[1:]), flush=True)
    out = subprocess.run(cmd, capture_output=True, text=True, env=_env(), cwd=ROOT, check=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def measure_vec(n: int, with_vmas: bool, threads: int = 1) -> dict:
    """bench_vec.py's rows for swarm size ``n`` (full and ideal sensing) on ``threads`` threads (numba; torch
    for VMAS), in a fresh process."""
    cmd = [sys.executable, str(HERE / "bench_vec.py"), "--n", str(n), "--json", "--threads", str(threads)] + ([] if with_vmas else ["--no-vmas"])
    return _run_json(cmd)


def measure_interleaved(threads: int, sensing: str, rounds: int = 5) -> dict:
    """bench_vec.py's alternated VMAS / N = 10 ratios (``--interleave``) for ``sensing`` on ``threads`` threads,
    in a fresh process: both sides of each ratio measured under the same load."""
    cmd = [sys.executable, str(HERE / "bench_vec.py"), "--interleave", str(rounds), "--sensing", sensing, "--threads", str(threads), "--json"]
    return _run_json(cmd)


def measure_first_run(runs: int = 3) -> dict:
    """bench_first_run.py's result: the README snippet on an empty numba cache, ``runs`` times, and warm."""
    cmd = [sys.executable, str(HERE / "bench_first_run.py"), "--runs", str(runs), "--json"]
    return _run_json(cmd)


def measure_views() -> dict:
    """bench_views.py's medians: the ParallelEnv against make_vec(..., 1), N = 1000, full sensing."""
    cmd = [sys.executable, str(HERE / "bench_views.py"), "--json"]
    return _run_json(cmd)


def measure_torchrl() -> dict | str:
    """bench_torchrl.py's medians (make_torchrl and the single-env PettingZooWrapper against make_vec, N = 10,
    64 copies, full sensing), or why it was not run."""
    try:
        import torchrl  # noqa: F401
    except ImportError:
        return "not measured: torchrl is not installed (`pip install -e \".[torchrl]\"`)"
    cmd = [sys.executable, str(HERE / "bench_torchrl.py"), "--json"]
    return _run_json(cmd)


def measure_training() -> dict | str:
    """Robot-steps/s of the default PPO config (training only, evaluation excluded), or why it was not run."""
    try:
        import stable_baselines3  # noqa: F401
        import torch  # noqa: F401
    except ImportError as exc:
        return f"not measured: {exc.name} is not installed (`pip install -e \".[rl]\"`)"
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, str(ROOT / "train.py"), "--config", TRAIN_CONFIG, "--output", tmp]
        print("running:", " ".join(cmd[1:]), flush=True)
        proc = subprocess.run(cmd, capture_output=True, text=True, env=_env(), cwd=ROOT)
        if proc.returncode != 0:
            return f"not measured: train.py exited with code {proc.returncode}: {proc.stderr.strip().splitlines()[-1:]}"
        timing = json.loads((Path(tmp) / "timing.json").read_text())
    return {"robot_steps": timing["robot_steps"], "train_s": timing["train_s"], "total_s": timing["total_s"],
            "robot_steps_per_s": timing["robot_steps"] / timing["train_s"]}


def measure_training_stages() -> list[tuple[str, float, float]] | str:
    """(stage, seconds, share of ``learn`` in %) of the default PPO config from ``bench_train_stages.py``, or
    why it was not run."""
    cmd = [sys.executable, str(HERE / "bench_train_stages.py"), "--config", TRAIN_CONFIG]
    print("running:", " ".join(cmd[1:]), flush=True)
    proc = subprocess.run(cmd, capture_output=True, text=True, env=_env(), cwd=ROOT)
    if proc.returncode != 0:
        return f"not measured: bench_train_stages.py exited with code {proc.returncode}: {proc.stderr.strip().splitlines()[-1:]}"
    rows = []
    for line in proc.stdout.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 3 and cells[2].endswith("%"):
            rows.append((cells[0], float(cells[1]), float(cells[2].rstrip(" %"))))
    return rows or "not measured: bench_train_stages.py printed no table"


def machine() -> dict[str, str]:
    """CPU model, cores and library versions of this machine."""
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    versions = {"Python": platform.python_version()}
    for package in ("swarm_envs", "numpy", "numba", "pymunk", "scipy", "torch", "stable-baselines3", "vmas"):
        try:
            versions[package] = metadata.version(package)
        except metadata.PackageNotFoundError:
            versions[package] = "not installed"
    return {"cpu": cpu, "cores": str(os.cpu_count()), "os": platform.platform(), **versions}


# --------------------------------------------------------------------------------------------- writing
def write_page(path: Path, sizes: list[int], training: bool, vmas: bool, first_run: bool = True, adapters: bool = True,
               threads: list[int] = (1,)) -> int:
    """Measure and write the performance page to ``path``: the throughput table at each count of ``threads``
    (VMAS on as many torch threads, measured in the first size's process)."""
    started = datetime.datetime.now(datetime.timezone.utc)
    load_before = os.getloadavg()
    info = machine()
    runs = [measure_vec(n, with_vmas=vmas and i == 0, threads=t) for t in threads for i, n in enumerate(sorted(sizes))]
    alternated = [measure_interleaved(t, s) for s in ("full", "ideal") for t in threads] if any(r.get("vmas") for r in runs) else None
    first = measure_first_run() if first_run else None
    views = measure_views() if adapters else None
    torchrl = measure_torchrl() if adapters else None
    train = measure_training() if training else "not measured (`--no-training`)"
    if isinstance(train, dict):
        train["stages"] = measure_training_stages()
    load_after = os.getloadavg()
    minutes = (datetime.datetime.now(datetime.timezone.utc) - started).total_seconds() / 60
    page = render(info, runs, train, sorted(sizes), started, minutes, load_before, load_after, first, views, torchrl, alternated)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(page, encoding="utf-8")
    print(f"wrote {path} ({minutes:.1f} min of measurements)")
    return 0


def _load(values: tuple[float, float, float]) -> str:
    return " / ".join(f"{v:.2f}" for v in values)


def render(info: dict[str, str], runs: list[dict], train: dict | str, sizes: list[int],
           started: datetime.datetime, minutes: float, load_before: tuple, load_after: tuple,
           first_run: dict | None = None, views: dict | None = None, torchrl: dict | str | None = None,
           alternated: list[dict] | None = None) -> str:
    """The performance page as markdown."""
    vmas_of = {r["numba_threads"]: r["vmas"] for r in runs if r.get("vmas")}  # VMAS per thread count
    vmas = vmas_of.get(1) or next(iter(vmas_of.values()), None)
    rows = [{**row, "threads": r["numba_threads"]} for r in runs for row in r["rows"]]
    thread_counts = sorted({r["numba_threads"] for r in runs})
    lines = [
        "# Performance",
        "",
        "This page is written by one command, which measures everything on it in one run on the machine",
        "described below:",
        "",
        "```bash",
        "pip install torch==2.13.0 && pip install -e \".[rl]\" vmas   # rl: the training rate; vmas: the peer's column",
        "python benchmarks/run_all.py --markdown  # writes docs/performance.md",
        "```",
        "",
        "## Machine",
        "",
        "| | |",
        "|---|---|",
        f"| date (UTC) | {started:%Y-%m-%d %H:%M} ({minutes:.0f} min of measurements) |",
        f"| CPU | {info['cpu']}, {info['cores']} cores |",
        f"| OS | {info['os']} |",
        f"| load average (1 / 5 / 15 min) | {_load(load_before)} before, {_load(load_after)} after |",
        f"| threads (numba; torch for VMAS) | {', '.join(map(str, thread_counts))} |",
        "| versions | " + ", ".join(f"{k} {v}" for k, v in info.items() if k not in ("cpu", "cores", "os")) + " |",
        "",
        "Timings on a shared machine drift with the other load; the load averages above say how busy it was.",
        "Every figure is a median over timed steps after warm-up, and the VMAS ratio compares figures from",
        "the same run at the same thread count. On one thread, a wall-clock time per step well above the",
        "process's CPU time means the process waited for a core that other work held.",
        "",
        "## Rollout throughput of the batched core",
        "",
        "`swarm_envs.make_vec(\"swarm_envs/Flocking-v0\", B, n_robots=N, sensing=...)` stepped with random",
        "actions: e-puck robots at the default density, B copies of N robots each, one batched core. An",
        "*env step* advances every copy by one control step (0.1 s of simulated time); *agent-steps/s* =",
        "N x B x env steps/s. Each swarm size runs in its own process (`python benchmarks/bench_vec.py",
        "--n N --threads T`) with T numba threads (`NUMBA_NUM_THREADS`): batches of at least 16 copies step",
        "their physics on T threads, and a scene with at least 16,384 candidate IR pairs (256 copies of 10,",
        "or N = 1000) runs its gain kernel and its scale-free coordinates in T chunks and range & bearing",
        "beside SwarmCom (docs/design.md, Threads); results are the same for any T.",
        "",
    ]
    if vmas:
        peers = "; ".join(f"{v['agent_steps_per_s']:,.0f} agent-steps/s ({v['s_per_step'] * 1e3:.1f} ms per step) on {t} torch "
                          f"thread{'s' if t > 1 else ''}" for t, v in sorted(vmas_of.items()))
        lines += [
            f"Peer: [VMAS](https://github.com/proroklab/VectorizedMultiAgentSimulator) {vmas['version']}, its",
            f"`flocking` scenario with {vmas['n_agents']} agents in {vmas['num_envs']} vectorised envs on the CPU,",
            f"measured in the same run: **{peers}**. VMAS simulates point-mass dynamics with exact",
            "observations; the ideal-sensing rows are the closer comparison. Each row's ratio is to VMAS on as",
            "many threads.",
            "",
        ]
    else:
        lines += [
            "Peer: VMAS was not installed for this run (`pip install vmas` adds its flocking scenario, 10 agents",
            "x 1024 envs on the CPU, as a column measured in the same run).",
            "",
        ]
    lines += ["| N | B | sensing | threads | ms / env step | CPU ms / env step | env steps/s (per copy) | agent-steps/s | vs VMAS "
              "| neighbours in IR range | µs per robot-step per neighbour |",
              "|---|---|---|---|---|---|---|---|---|---|---|"]
    for sensing in ("full", "ideal"):
        for row in sorted((r for r in rows if r["sensing"] == sensing), key=lambda r: (r["n"], r["copies"], r["threads"])):
            peer = vmas_of.get(row["threads"])
            ratio = f"{row['agent_steps_per_s'] / peer['agent_steps_per_s']:.2f}x" if peer else "-"
            near = row.get("neighbours_in_range")
            per_pair = f"{1e6 / (row['agent_steps_per_s'] * near):.2f}" if near else "-"
            lines.append(f"| {row['n']} | {row['copies']} | {sensing} | {row['threads']} | {row['s_per_step'] * 1e3:.1f} | "
                         f"{row['cpu_s_per_step'] * 1e3:.1f} | {row['env_steps_per_s']:,.1f} | "
                         f"{row['agent_steps_per_s']:,.0f} | {ratio} | {'-' if near is None else f'{near:.1f}'} | {per_pair} |")
    lines += [
        "",
        "*Neighbours in IR range*: robots of the same copy within the e-puck's IR range of a robot, averaged",
        "over the timed steps: the pairs the IR layer and every sensing stage after it work on. The default",
        "density puts 10 robots in a 0.79 m square, inside the e-puck's 1 m IR range, so a robot of a small",
        "swarm has at most N - 1 neighbours and one of a large swarm has the robots of a 1 m disc around it:",
        "the time per robot-step grows with N because the work per robot does. The last column (wall-clock",
        "time per robot-step and per neighbour in range) compares the swarm sizes at equal work.",
    ]
    if sizes != list(SIZES):
        lines += ["", f"Reduced run: only N = {', '.join(map(str, sizes))} were measured (`--sizes`); the full run "
                  f"adds N = {', '.join(str(n) for n in SIZES if n not in sizes)}."]
    if alternated:
        copies = list(alternated[0]["ratios"])
        lines += [
            "",
            "### Ratios under the same load",
            "",
            f"VMAS (as above) and N = 10 at B = {' and '.join(copies)} alternated {alternated[0]['rounds']} times in one process per row",
            "(`python benchmarks/bench_vec.py --interleave 5 --sensing S --threads T`), so that both sides of every",
            "ratio see the same load; the median ratio over the rounds, in brackets the lowest and the highest:",
            "",
            "| sensing | threads | VMAS agent-steps/s (median) | " + " | ".join(f"B = {b} vs VMAS" for b in copies) + " |",
            "|---|---|---|" + "---|" * len(copies),
        ]
        for a in alternated:
            cells = " | ".join(f"{a['ratios'][b]['median']:.2f}x [{a['ratios'][b]['min']:.2f}, {a['ratios'][b]['max']:.2f}]" for b in copies)
            lines.append(f"| {a['sensing']} | {a['numba_threads']} | {a['vmas_median_agent_steps_per_s']:,.0f} | {cells} |")
    lines += ["", "## First run", ""]
    if first_run:
        lines += [
            "The README's first snippet (`pettingzoo.make` of `swarm_envs/Aggregation-v0` with 10 e-puck robots,",
            "`reset`, one 500-step episode of random actions) run as a fresh `python` process on an empty numba",
            "cache (`NUMBA_CACHE_DIR` a new directory), timed from start to exit: the first run of the package on",
            f"a machine. **{first_run['cold_median_s']:.1f} s** (median of {first_run['runs']} runs: "
            f"{', '.join(f'{s:.1f}' for s in first_run['cold_s'])} s), of which all but the warm time is numba",
            f"compiling the kernels the snippet uses; run again on the filled cache: {first_run['warm_median_s']:.1f} s.",
            "The first run prints one line saying it compiles; when a core is idle, a background process compiles",
            "the kernels together with the snippet, both taking the longest first (it ran in",
            f"{sum(first_run.get('background_started', []))} of these {first_run['runs']} runs; it starts when the 1-minute load average is",
            "below the cores minus a half).",
            f"Load averages {_load(first_run['load_before'])} before the runs, {_load(first_run['load_after'])} after",
            "(`python benchmarks/bench_first_run.py`).",
        ]
    else:
        lines.append("The first run on an empty numba cache was not measured (`--no-first-run`).")
    lines += ["", "## Views and adapters", ""]
    if views is not None:
        lines += [
            f"**PettingZoo `ParallelEnv` against `make_vec(..., 1)`** over the same batched core, N = {views['n']}",
            f"robots, {views['sensing']} sensing ({views['env']}), {views['rounds']} alternated rounds: "
            f"{views['parallel_env_steps_per_s']:.1f} against {views['make_vec_steps_per_s']:.1f} env steps/s,",
            f"**ratio {views['ratio']:.2f}** (median of the rounds' ratios; `python benchmarks/bench_views.py`). The",
            "ParallelEnv builds its per-agent dicts (observations, rewards, nested infos) column by column over all agents.",
            "",
        ]
    if isinstance(torchrl, dict):
        single = torchrl.get("PettingZooWrapper rollout (B = 1) ratio")
        lines += [
            f"**TorchRL**: `swarm_envs.make_torchrl(..., {torchrl['copies']})` rollouts against `make_vec` with the same",
            f"{torchrl['copies']} copies of {torchrl['n']} e-pucks, {torchrl['sensing']} sensing, {torchrl['rounds']} alternated rounds:",
            f"{torchrl['make_torchrl rollout']:,.0f} against {torchrl['make_vec']:,.0f} agent-steps/s, **ratio "
            f"{torchrl['make_torchrl rollout ratio']:.2f}**"
            + (f"; TorchRL's `PettingZooWrapper` on one env: {torchrl['PettingZooWrapper rollout (B = 1)']:,.0f} agent-steps/s "
               f"(ratio {single:.3f})" if single is not None else "")
            + " (`python benchmarks/bench_torchrl.py`).",
            "",
        ]
    elif torchrl is not None:
        lines += [f"TorchRL: {torchrl}.", ""]
    if views is None and torchrl is None:
        lines += ["Not measured (`--no-adapters`).", ""]
    lines += ["## Training rate", ""]
    if isinstance(train, dict):
        lines += [
            f"`python train.py --config {TRAIN_CONFIG}` (PPO from stable-baselines3, one policy shared by all",
            "robots: 16 env copies of 10 e-puck robots, full sensing, torch on 1 thread, numba kernels already",
            f"compiled): **{train['robot_steps_per_s']:,.0f} robot-steps/s** of training ({train['robot_steps']:,}",
            f"robot-steps in {train['train_s']:.1f} s); the whole command, with the evaluation of PPO, the scripted",
            f"baseline and a random policy over 20 seeds, took {train['total_s']:.1f} s.",
        ]
        stages = train.get("stages")
        if isinstance(stages, list):
            lines += [
                "",
                "Where the time of `model.learn` goes (`python benchmarks/bench_train_stages.py`, the same config for",
                "51,200 robot-steps; *env step* is the batched core, *PPO update* stable-baselines3's epochs of",
                "minibatch gradient steps):",
                "",
                "| stage | s | share |",
                "|---|---|---|",
                *[f"| {name} | {sec:.2f} | {share:.1f} % |" for name, sec, share in stages],
            ]
        elif stages is not None:
            lines += ["", f"The split of the training time was {stages}."]
    else:
        lines.append(f"The default PPO config's training rate was {train}.")
    lines += [
        "",
        "## Reproducing parts of it",
        "",
        "```bash",
        "python benchmarks/bench_vec.py                        # the throughput table in one process, VMAS column if installed",
        "python benchmarks/bench_vec.py --n 1000 --copies 1 --sensing full --no-vmas   # one row",
        "python benchmarks/bench_vec.py --threads 2            # the table on 2 threads (VMAS on 2 torch threads)",
        "python benchmarks/bench_vec.py --interleave 5         # VMAS and N = 10 ideal alternated: ratios under the same load",
        "python benchmarks/bench_stages.py                     # one vector step split into physics, sensing, observations, rewards",
        "python benchmarks/bench_first_run.py                  # the README snippet on an empty numba cache, 3 runs, and warm",
        "python benchmarks/bench_views.py                      # the ParallelEnv against make_vec(..., 1), N = 1000",
        "python benchmarks/bench_torchrl.py                    # make_torchrl and PettingZooWrapper against make_vec",
        "python benchmarks/run_all.py                          # every component benchmark (IR layer, SwarmCom, range & bearing, scale-free)",
        "```",
        "",
        "`NUMBA_NUM_THREADS=1` keeps a process on one core. The first run on a machine also compiles the",
        "numba kernels (cached on disk afterwards; see *First run*); the throughput figures exclude that.",
        "",
    ]
    return "\n".join(lines)


if __name__ == "__main__":
    raise SystemExit(main())
