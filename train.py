#!/usr/bin/env python
"""Train PPO on a swarm task and compare it with the scripted and random baselines: see :mod:`swarm_envs.agents.train`.

    python train.py --config configs/aggregation.yaml [--output DIR] [--render] [--set key=value ...]
    python train.py --config configs/aggregation.yaml --eval-only CHECKPOINT [--output DIR [--force]]
"""

from swarm_envs.agents.train import main

if __name__ == "__main__":
    raise SystemExit(main())
