#!/usr/bin/env python
"""Train PPO on a swarm task and compare it with the scripted and random baselines: see :mod:`swarm_envs.agents.train`.

    python train.py --config configs/aggregation.yaml [--output DIR] [--render] [--set key=value ...]
    python train.py --config configs/aggregation.yaml --eval-only CHECKPOINT [--output DIR [--force]]
    python train.py --list-partial DIR | --clean-partial DIR
"""

import signal
import threading

if __name__ == "__main__":
    # Ctrl-C while the package loads is noted, not raised, and is one line too: swarm_envs.agents.launch.note_ctrl_c,
    # which cannot be imported before the package has loaded
    pressed: list = []
    previous = None
    if threading.current_thread() is threading.main_thread() and signal.getsignal(signal.SIGINT) is signal.default_int_handler:
        previous = signal.signal(signal.SIGINT, lambda signum, frame: pressed.append(signum))
    from swarm_envs.agents.launch import train

    raise SystemExit(train(noted=(pressed, previous)))
