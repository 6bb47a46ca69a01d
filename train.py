#!/usr/bin/env python
"""Train PPO on a swarm task and compare it with the scripted and random baselines: see :mod:`swarm_envs.agents.train`.

    python train.py --config configs/aggregation.yaml [--output DIR] [--render] [--set key=value ...]
    python train.py --config configs/aggregation.yaml --eval-only CHECKPOINT [--output DIR [--force]]
    python train.py --list-partial DIR | --clean-partial DIR
"""

import sys

if __name__ == "__main__":
    try:  # Ctrl-C while the package loads is one line too
        from swarm_envs.agents.launch import train
    except KeyboardInterrupt:
        print("interrupted by Ctrl-C while starting; nothing was written", file=sys.stderr)
        raise SystemExit(130) from None
    raise SystemExit(train())
