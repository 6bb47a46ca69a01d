"""The ``swarm-train`` command's entry point: Ctrl-C while the trainer's modules load (numpy, torch,
stable-baselines3 take a few seconds) is one line and exit code 130, as everywhere else in the command.

While the modules load, Ctrl-C is noted instead of raised: a ``KeyboardInterrupt`` raised inside a
compiled module's initialisation (torch's or scipy's pybind11 modules) can abort the interpreter with a
C++ error instead of stopping the import. The command stops once the modules are loaded."""

from __future__ import annotations

import signal
import sys
import threading
from typing import Any

__all__ = ["train", "note_ctrl_c"]

#: the exit code of a command stopped with Ctrl-C (128 + SIGINT)
EXIT_INTERRUPTED = 130


def note_ctrl_c() -> tuple[list[int], Any]:
    """Note Ctrl-C in the returned list instead of raising ``KeyboardInterrupt``, until the returned
    handler (None: nothing to restore) is set again. An ignored Ctrl-C (a job started in the background)
    stays ignored, and off the main thread nothing changes."""
    pressed: list[int] = []
    if threading.current_thread() is not threading.main_thread() or signal.getsignal(signal.SIGINT) is not signal.default_int_handler:
        return pressed, None
    return pressed, signal.signal(signal.SIGINT, lambda signum, frame: pressed.append(signum))


def train(argv: list[str] | None = None, noted: tuple[list[int], Any] | None = None) -> int:
    """Import :mod:`swarm_envs.agents.train` and run its ``main(argv)``, Ctrl-C noted while it loads
    (:func:`note_ctrl_c`). ``noted``: the result of a :func:`note_ctrl_c` the caller started before it
    imported this package (``train.py``), default one started here."""
    pressed, previous = note_ctrl_c() if noted is None else noted
    try:
        from swarm_envs.agents.train import main
    finally:
        if previous is not None:
            signal.signal(signal.SIGINT, previous)
    if pressed:
        print("interrupted by Ctrl-C while starting; nothing was written", file=sys.stderr)
        return EXIT_INTERRUPTED
    return main(argv)


if __name__ == "__main__":
    sys.exit(train())
