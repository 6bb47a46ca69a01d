"""Settings on the command line: an argparse ``type`` that applies a setting's rule to a string, and the parser
whose usage errors are one line (the command-line tools' errors, like train.py's, exit code 2)."""

from __future__ import annotations
from collections.abc import Callable
import argparse
from typing import Any
from swarm_envs._text import shown

from swarm_envs.tasks.settings import Int, Real, Setting, SettingsError

__all__ = ["cli_type", "OneLineArgumentParser"]


def cli_type(setting: Setting, what: str = "value") -> Callable[[str], Any]:
    """An argparse ``type`` that applies ``setting``'s rule to a command-line string: a bad value (``--trials
    0``, ``--noise nan``) is argparse's usage error naming the option, exit code 2, like a bad env setting."""
    def parse(text: str) -> Any:
        value: Any = text
        if isinstance(setting, (Int, Real)):
            if getattr(setting, "allow_none", False) and text.strip().lower() == "none":
                value = None
            else:
                try:
                    value = int(text) if isinstance(setting, Int) else float(text)
                except ValueError:
                    raise argparse.ArgumentTypeError(f"{what} must be {setting.rule()}, got {shown(text)}") from None
        try:
            return setting.check(what, value)
        except SettingsError as err:
            raise argparse.ArgumentTypeError(str(err)) from None

    parse.__name__ = setting.rule()
    return parse


class OneLineArgumentParser(argparse.ArgumentParser):
    """argparse whose usage errors are one line, ``prog: error: message (see --help)``, exit code 2 (the
    command-line tools' errors, like train.py's)."""

    def error(self, message: str) -> None:  # type: ignore[override]
        self.exit(2, f"{self.prog}: error: {' '.join(message.split())} (see --help)\n")
