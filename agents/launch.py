"""The ``swarm-train`` command's entry point: Ctrl-C while the trainer's modules load (numpy, torch,
stable-baselines3 take a few seconds) is one line and exit code 130, as everywhere else in the command."""

from __future__ import annotations

import sys

__all__ = ["train"]

#: the exit code of a command stopped with Ctrl-C (128 + SIGINT)
EXIT_INTERRUPTED = 130


def train(argv: list[str] | None = None) -> int:
    """Import :mod:`swarm_envs.agents.train` and run its ``main(argv)``."""
    try:
        from swarm_envs.agents.train import main
    except KeyboardInterrupt:
        print("interrupted by Ctrl-C while starting; nothing was written", file=sys.stderr)
        return EXIT_INTERRUPTED
    return main(argv)


if __name__ == "__main__":
    sys.exit(train())
