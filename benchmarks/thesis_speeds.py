"""The scripted thesis behaviours at their default speeds and at the thesis's 20 mm/s [L Algs. 5-8].

    python benchmarks/thesis_speeds.py [--seeds 10] [--json PATH]

Each behaviour of ``swarm-validate behaviours`` (the r-one, ``sensing="full"``, the scripted agent of the
task) runs over ``--seeds`` evaluation seeds three ways: at the controller's default speed, at the thesis's
``PoseSet(tv = 20 mm/sec)`` (all of the controller's speeds set to 20 mm/s, the r-one's maximum being
0.30 m/s) over the same episode length, and at 20 mm/s over three times the episode. Printed per run:
every metric's mean over the seeds with its bootstrap 95 % interval; ``--json`` writes them too. This is
the evidence docs/design.md (item 32, Speed) cites for the controllers' default speeds.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np

import swarm_envs
from swarm_envs.agents.evaluation import confidence_interval, evaluate
from swarm_envs.agents.scripted import make_scripted
from swarm_envs.agents.tasks import headline, scripted_policy
from swarm_envs.validate.behaviours import BEHAVIOURS

#: the thesis's driving speed [L Algs. 5-8], m/s
THESIS_SPEED = 0.020
#: the controllers' speed keywords (fractions of the platform's maximum speed)
SPEED_KEYWORDS = {"sorted_following": ("speed", "leader_speed")}


def measure(name: str, seeds: list[int]) -> dict[str, dict[str, list[float]]]:
    """{run: {metric: [mean, low, high]}} of behaviour ``name`` at the default and the thesis's speed."""
    env_id, settings, _, _ = BEHAVIOURS[name]
    env = swarm_envs.make(env_id, sensing="full", **settings)
    cycles, fraction = env.max_cycles, THESIS_SPEED / env.platform.max_speed
    policy = scripted_policy(env_id)
    slow = {key: fraction for key in SPEED_KEYWORDS.get(name, ("speed",))}
    out = {}
    for run, kwargs, length in (("default speed", {}, cycles), ("20 mm/s", slow, cycles), ("20 mm/s, 3x the episode", slow, 3 * cycles)):
        metrics = evaluate(env_id, dict(settings, sensing="full", max_cycles=length), lambda e, kw=kwargs: make_scripted(policy, e, **kw), seeds)
        out[run] = {m: [float(x) for x in confidence_interval(np.asarray(v))] for m, v in metrics.items()}
        cells = ", ".join(f"{m} {a:.3f} [{lo:.3f}, {hi:.3f}]" for m, (a, lo, hi) in out[run].items())
        print(f"{name} ({headline(env_id)[0]}), {run}, {length} steps: {cells}", flush=True)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=10, help="evaluation seeds 0..S-1")
    parser.add_argument("--json", type=Path, help="also write the results to this file")
    args = parser.parse_args()
    seeds = list(range(args.seeds))
    names = [n for n in ("flocking", "sorted_following", "parity_clustering", "mid_angle_navigation")]
    result = {"thesis_speed_m_s": THESIS_SPEED, "seeds": args.seeds, "behaviours": {n: measure(n, seeds) for n in names}}
    if args.json:
        args.json.write_text(json.dumps(result, indent=1) + "\n")


if __name__ == "__main__":
    main()
