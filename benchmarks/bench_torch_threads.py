"""Torch intra-op threads (``torch.set_num_threads``) 1 vs 2 for the small PPO MLP on this machine.

    python benchmarks/bench_torch_threads.py [--threads 1 2] [--timesteps 40000] [--repeats 3]

Measures, per thread count, in a fresh subprocess each (torch's thread pool is set once per process):
- ``predict``: ms per ``model.predict`` on a (20, D) batch (2 env copies x 10 robots, the rollout call);
- ``update``: s per PPO update phase (``model.train()``: n_epochs over a 2560-sample rollout);
- ``learn``: robot-steps/s of a whole ``model.learn`` on aggregation (``sensing="ideal"``, 2 copies x 10 robots),
  i.e. env stepping + inference + updates.
With ``--busy K`` the measurement runs while K busy-loop processes occupy cores (the situation on a shared
2-core box, e.g. tests or a second run in parallel). Prints a table; the ``train.torch_threads`` default
(``agents.config``) is 1: on an idle box 2 threads is at most ~5 % faster, with one busy core it is 4-8x slower
(intra-op threads spin-wait for the busy core).
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time

CHILD = r"""
import json, sys, time
import numpy as np, torch
threads, timesteps, repeats = int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
torch.set_num_threads(threads)
from stable_baselines3 import PPO
from swarm_envs.agents.sb3_vec_env import SwarmVecEnv
from swarm_envs import aggregation_v0
venv = SwarmVecEnv(aggregation_v0.parallel_env, 2, dict(sensing="ideal", max_cycles=200, reward_mode="local"))
venv.seed(0)
model = PPO("MlpPolicy", venv, n_steps=128, batch_size=512, n_epochs=5, policy_kwargs={"net_arch": [64, 64]}, seed=0, device="cpu")
obs = venv.reset()
model.predict(obs, deterministic=True)
t = time.perf_counter(); n = 2000
for _ in range(n):
    model.predict(obs, deterministic=True)
predict_ms = (time.perf_counter() - t) / n * 1e3
model.learn(model.n_steps * venv.num_envs)  # fills the rollout buffer
upd = []
for _ in range(repeats):
    t = time.perf_counter(); model.train(); upd.append(time.perf_counter() - t)
learn = []
for _ in range(repeats):
    t = time.perf_counter(); model.learn(timesteps, reset_num_timesteps=True); learn.append(timesteps / (time.perf_counter() - t))
print(json.dumps({"threads": threads, "predict_ms": predict_ms, "update_s": float(np.median(upd)),
                  "learn_steps_per_s": float(np.median(learn)), "torch_threads_reported": torch.get_num_threads()}))
"""


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    parser.add_argument("--timesteps", type=int, default=40_000)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--busy", type=int, default=0, help="busy-loop processes to run during the measurement")
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args(argv)
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    rows = []
    busy = [subprocess.Popen([sys.executable, "-c", "while True: pass"]) for _ in range(args.busy)]
    try:
        rows = _measure(args, root)
    finally:
        for proc in busy:
            proc.kill()
            proc.wait()
    if args.json:
        print(json.dumps(rows))
        return 0
    print(f"cpu count: {os.cpu_count()}; busy-loop processes: {args.busy}; PPO MLP [64, 64], 2 env copies x 10 robots, "
          "aggregation (ideal sensing)")
    print("| threads | predict (20 rows) ms | PPO update s | learn robot-steps/s |")
    print("|---|---|---|---|")
    for r in rows:
        print(f"| {r['threads']} | {r['predict_ms']:.3f} | {r['update_s']:.3f} | {r['learn_steps_per_s']:.0f} |")
    best = max(rows, key=lambda r: r["learn_steps_per_s"])
    print(f"best for whole training here: torch_threads = {best['threads']}")
    return 0


def _measure(args, root: str) -> list[dict]:
    rows = []
    for threads in args.threads:
        env = {**os.environ, "OMP_NUM_THREADS": str(threads), "MKL_NUM_THREADS": str(threads), "PYTHONPATH": root}
        res = subprocess.run([sys.executable, "-c", CHILD, str(threads), str(args.timesteps), str(args.repeats)],
                             capture_output=True, text=True, env=env, cwd=root, check=True)
        rows.append(json.loads(res.stdout.strip().splitlines()[-1]))
    return rows


if __name__ == "__main__":
    sys.exit(main())
