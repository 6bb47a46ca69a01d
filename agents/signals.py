"""Ctrl-C and exit codes of the training command: SIGINT ignored while a run is published, a handler that
stops training at the next step, what counts as an interrupt, and one-line error messages."""

from __future__ import annotations
import contextlib
import signal
import threading
from collections.abc import Iterator
from typing import Any

__all__ = ["EXIT_INTERRUPTED", "EXIT_BAD_INPUT", "sigint_ignored", "CtrlC", "one_line", "is_interrupt"]


#: exit code after Ctrl-C (128 + SIGINT), as shells report it
EXIT_INTERRUPTED = 130

#: exit code of bad input (config, output directory, checkpoint)
EXIT_BAD_INPUT = 2


@contextlib.contextmanager
def sigint_ignored() -> Iterator[None]:
    """Ignore Ctrl-C inside the block (main thread only), so a file move is never cut short."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


class CtrlC:
    """Ctrl-C during training and evaluation. The first one asks the work to stop at the next env step (a
    callback that returns False ends SB3's ``learn``; an evaluated policy calls :meth:`check` every step),
    so the request is never lost: raised as a ``KeyboardInterrupt`` wherever the signal lands, it can land
    in a cffi finalizer (pymunk's bodies), where CPython prints it and drops it, or in a Python call made
    from numba-compiled code, where it surfaces as a ``SystemError``. A second Ctrl-C raises
    ``KeyboardInterrupt`` at once. After an interrupted training, Ctrl-C stays ignored so the save that
    follows is never cut short."""

    def __init__(self) -> None:
        self.requested = False

    def check(self) -> None:
        """Raise ``KeyboardInterrupt`` if Ctrl-C was pressed (from ordinary code, where it is never dropped)."""
        if self.requested:
            raise KeyboardInterrupt

    def _handler(self, signum: int, frame: Any) -> None:
        if self.requested:
            raise KeyboardInterrupt
        self.requested = True

    @contextlib.contextmanager
    def installed(self) -> Iterator[None]:
        """The handler inside the block (main thread only; not where Ctrl-C is ignored already)."""
        if threading.current_thread() is not threading.main_thread() or signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
            yield
            return
        previous = signal.signal(signal.SIGINT, self._handler)
        try:
            yield
        finally:
            signal.signal(signal.SIGINT, signal.SIG_IGN if self.requested else previous)

    def callback(self) -> Any:
        """An SB3 callback that ends training once Ctrl-C was pressed."""
        from stable_baselines3.common.callbacks import BaseCallback

        ctrl_c = self

        class StopOnCtrlC(BaseCallback):
            def _on_step(self) -> bool:
                return not ctrl_c.requested

        return StopOnCtrlC()


def one_line(message: object) -> str:
    """``message`` on one line (newlines and runs of spaces collapsed)."""
    return " ".join(str(message).split())


def is_interrupt(err: BaseException) -> bool:
    """Whether ``err`` is Ctrl-C: a ``KeyboardInterrupt``, or the ``SystemError`` CPython raises in its place
    when the signal arrives just as a compiled (numba) function returns ("... returned a result with an
    exception set"): the handler runs in a Python call numba makes from compiled code (``_numba_unpickle``),
    and each C level between it and the caller wraps the ``KeyboardInterrupt`` in one more such
    ``SystemError``, so the chain of causes is followed through them."""
    for _ in range(64):
        if not isinstance(err, SystemError):
            break
        err = err.__cause__ or err.__context__
    return isinstance(err, KeyboardInterrupt)
