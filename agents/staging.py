"""Run directories: a run is written into a private staging directory next to its output and published by one
rename, so a crash or Ctrl-C never leaves a half-written run and two runs into one output never mix; the staging
directories a run left behind are listed and cleaned."""

from __future__ import annotations
import contextlib
import errno
import os
import re
import shutil
import sys
import tempfile
import time
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

from swarm_envs.agents.signals import EXIT_BAD_INPUT, one_line, sigint_ignored

__all__ = ["RESULT_FILES", "RUN_ENTRIES", "TrainError", "run_entries", "Staging", "UNKNOWN_OWNER_S", "StagingDir", "staging_dirs", "report_staging_dirs", "clean_staging_dirs", "errors_naming", "check_output", "eval_output_dir"]


RESULT_FILES = ("results.csv", "results.md", "per_seed.json")

#: the entries a run of train.py writes (besides ``eval-*`` directories): a directory holding any is a run
RUN_ENTRIES = ("config.yaml", "model.zip", "progress.csv", "learning_curve.png", "results.csv", "results.md",
               "results.png", "per_seed.json", "timing.json", "episode.gif", "checkpoints", "tensorboard")


class TrainError(Exception):
    """Bad input or a failed write found by train.py (output directory, checkpoint, disk); reported as one
    line, exit code 2."""


def run_entries(directory: Path) -> list[str]:
    """The names in ``directory`` that belong to a run (:data:`RUN_ENTRIES` and ``eval-*`` directories)."""
    try:
        names = sorted(p.name for p in directory.iterdir())
    except OSError:  # missing, or not a directory
        return []
    return [n for n in names if n in RUN_ENTRIES or (n.startswith("eval-") and (directory / n).is_dir())]


class Staging:
    """A hidden directory beside ``out`` that a command writes its files into; :meth:`publish` moves them
    into ``out`` at the end, so a run already in ``out`` changes only then, and only as a whole.

    Raises :class:`TrainError` if the directory cannot be made (``out`` is not writable)."""

    def __init__(self, out: Path) -> None:
        self.out = Path(os.path.abspath(out))  # "." or "runs/.." get a real name and parent
        try:
            self.out.parent.mkdir(parents=True, exist_ok=True)
            self.path = Path(tempfile.mkdtemp(prefix=f".{self.out.name}.{os.getpid()}-", suffix=".partial", dir=self.out.parent))
        except OSError as err:
            raise TrainError(f"output directory '{out}' is not writable: {err.strerror or err}") from None

    def final(self, path: Path) -> Path:
        """Where the staged ``path`` ends up in ``out``."""
        try:
            return self.out / Path(path).relative_to(self.path)
        except ValueError:
            return Path(path)

    @contextlib.contextmanager
    def writing(self, path: Path) -> Iterator[Path]:
        """Yield a temporary name beside ``path`` to write to; it becomes ``path`` only when the block ends
        without error. An ``OSError`` (a full disk) becomes a :class:`TrainError` naming the file."""
        tmp = path.with_name(f".tmp-{os.getpid()}-{path.name}")  # keeps the suffix: writers pick the format by it
        try:
            yield tmp
            os.replace(tmp, path)
        except OSError as err:
            with contextlib.suppress(OSError):
                tmp.unlink()
            raise TrainError(f"could not write '{self.final(path)}': {err.strerror or err}") from None

    def publish(self, replace: bool = False) -> Path:
        """Move the staged files into ``out`` and return where they went. The claim of ``out`` is atomic: a
        new ``out`` is the staging directory renamed (which fails if another run got there first); an
        existing ``out`` is claimed by linking the staged ``config.yaml`` into it (which fails if it holds
        one). A run already in ``out`` is replaced only with ``replace`` (``--force``): it is first moved
        aside and deleted once the staged files are in, keeping ``out`` itself (a shell inside it stays
        there) and its other files. Without ``replace``, a run that finds ``out`` taken keeps its files
        under the first free name ``out.2``, ``out.3``, ... and returns that path. Ctrl-C waits until it
        ends."""
        with sigint_ignored():
            try:
                if not replace:
                    if not self.out.exists() and self._rename_to(self.out):
                        return self.out
                    if self.out.is_dir() and not run_entries(self.out) and self._claim(self.out):
                        self._move_into(self.out, skip="config.yaml")
                        return self.out
                    for k in range(2, 10_000):
                        other = self.out.with_name(f"{self.out.name}.{k}")
                        if not other.exists() and self._rename_to(other):
                            return other
                    raise OSError(f"no free name beside {self.out}")
                if not self.out.exists():
                    os.replace(self.path, self.out)
                    return self.out
                old, aside = run_entries(self.out), None
                if old:
                    aside = Path(tempfile.mkdtemp(prefix=f".{self.out.name}.", suffix=".replaced", dir=self.out.parent))
                    for name in old:
                        os.replace(self.out / name, aside / name)
                self._move_into(self.out)
                if aside is not None:
                    shutil.rmtree(aside, ignore_errors=True)
                return self.out
            except OSError as err:
                raise TrainError(
                    f"could not move the finished files from '{self.path}' into '{self.out}': {err.strerror or err}"
                ) from None

    def _rename_to(self, target: Path) -> bool:
        """Rename the staging directory to the new ``target``; False if another run took it first."""
        try:
            os.rename(self.path, target)  # fails if target exists and is not an empty directory
        except OSError as err:
            if err.errno in (errno.EEXIST, errno.ENOTEMPTY, errno.ENOTDIR):
                return False
            raise
        self.path = target
        return True

    def _claim(self, target: Path) -> bool:
        """Claim the existing directory ``target`` by linking the staged config into it; False if taken."""
        try:
            os.link(self.path / "config.yaml", target / "config.yaml")
        except FileExistsError:
            return False
        return True

    def _move_into(self, target: Path, skip: str | None = None) -> None:
        for entry in self.path.iterdir():
            if entry.name != skip:
                os.replace(entry, target / entry.name)
        if skip is not None:
            (self.path / skip).unlink()
        self.path.rmdir()

    def abandon(self) -> str:
        """After a failure: delete the staging directory, unless it holds a trained model, which is kept;
        returns a note for the error message (empty if nothing was kept)."""
        if (self.path / "model.zip").is_file():
            return f"; the trained model is kept in '{self.path}'"
        shutil.rmtree(self.path, ignore_errors=True)
        return ""

#: a staging directory's name between ``.<output name>.`` and ``.partial``: the owner's process id and
#: mkdtemp's 8 random characters (names made without the process id have the random characters only)
_STAGING_TAIL = re.compile(r"(?:(?P<pid>[0-9]+)-)?[a-z0-9_]{8}")

#: a staging directory whose name carries no process id counts as in use until this long after its last write
UNKNOWN_OWNER_S = 3600.0


@dataclass(frozen=True)
class StagingDir:
    """A staging directory found on disk (:func:`staging_dirs`): its ``path``, the output it belongs to, the
    process id in its name (None in names without one), seconds since its last write, whether it holds a
    trained model."""

    path: Path
    out: Path
    pid: int | None
    age_s: float
    has_model: bool

    @property
    def owner_running(self) -> bool:
        """Whether the process that made it still runs on this machine (its pid in the name is alive); a
        name without a pid counts as running for :data:`UNKNOWN_OWNER_S` after the last write."""
        if self.pid is None:
            return self.age_s < UNKNOWN_OWNER_S
        if self.pid == os.getpid():
            return True
        try:
            os.kill(self.pid, 0)
        except ProcessLookupError:
            return False
        except OSError:  # exists, owned by another user
            return True
        return True

    def describe(self) -> str:
        """``PATH (3.2 h old, holds a trained model)``."""
        notes = [f"{_age(self.age_s)} old"] + (["holds a trained model"] if self.has_model else [])
        if self.owner_running:
            notes.append(f"in use by process {self.pid}" if self.pid is not None else "written less than an hour ago: may be in use")
        return f"{self.path} ({', '.join(notes)})"


def _age(seconds: float) -> str:
    if seconds < 90:
        return f"{max(seconds, 0):.0f} s"
    if seconds < 90 * 60:
        return f"{seconds / 60:.0f} min"
    if seconds < 48 * 3600:
        return f"{seconds / 3600:.1f} h"
    return f"{seconds / 86400:.1f} days"


def _last_write(path: Path) -> float:
    """The newest modification time of ``path`` and the entries in it (and in its ``checkpoints/``)."""
    times = [path.stat().st_mtime]
    for folder in (path, path / "checkpoints"):
        with contextlib.suppress(OSError):
            for entry in os.scandir(folder):
                with contextlib.suppress(OSError):
                    times.append(entry.stat(follow_symlinks=False).st_mtime)
    return max(times)


def staging_dirs(folder: str | Path) -> list[StagingDir]:
    """The staging directories (``.NAME.<pid>-<random>.partial``) of the output ``folder`` (beside it) and of
    the outputs inside ``folder``, oldest first."""
    folder = Path(os.path.abspath(folder))
    found: list[StagingDir] = []
    try:
        inside = folder.is_dir()
    except OSError:  # e.g. a name too long for the file system: nothing inside it
        inside = False
    places = [(folder.parent, folder.name)] + ([(folder, None)] if inside else [])
    now = time.time()
    for parent, name in places:
        try:
            entries = list(os.scandir(parent))
        except OSError:
            continue
        for entry in entries:
            if not entry.name.startswith(".") or not entry.name.endswith(".partial"):
                continue
            out_name, _, tail = entry.name[1:-len(".partial")].rpartition(".")
            match = _STAGING_TAIL.fullmatch(tail)
            if not match or not out_name or (name is not None and out_name != name):
                continue
            path = Path(entry.path)
            try:
                if not entry.is_dir(follow_symlinks=False):
                    continue
                age = now - _last_write(path)
            except OSError:
                continue
            pid = int(match["pid"]) if match["pid"] else None
            found.append(StagingDir(path, parent / out_name, pid, age, (path / "model.zip").is_file()))
    return sorted(found, key=lambda d: -d.age_s)


def report_staging_dirs(out: Path, command: str) -> list[StagingDir]:
    """Print one line (stderr) per staging directory of ``out`` that another process left or is writing;
    returns them."""
    found = [d for d in staging_dirs(out) if d.out == Path(os.path.abspath(out)) and d.pid != os.getpid()]
    for d in found:
        if d.owner_running and d.pid is not None:
            print(one_line(f"note: process {d.pid} is also writing a run for {out}: {d.describe()}"), file=sys.stderr)
        else:
            print(one_line(f"note: staging directory left by an earlier run of {out}: {d.describe()}; list or remove "
                            f"such directories with: {command} --list-partial / --clean-partial {out}"), file=sys.stderr)
    return found


def clean_staging_dirs(folder: str | Path, remove: bool, command: str) -> int:
    """``--list-partial`` / ``--clean-partial FOLDER``: list the staging directories of the output ``folder``
    and of the outputs in it; with ``remove``, delete those whose process no longer runs. Returns the exit
    code (2 if one could not be removed)."""
    found = staging_dirs(folder)
    if not found:
        print(f"no staging directories for {folder}")
        return 0
    code, removed = 0, 0
    for d in found:
        if not remove:
            print(d.describe())
        elif d.owner_running:
            print(f"kept {d.describe()}")
        else:
            try:
                shutil.rmtree(d.path)
            except OSError as err:
                print(one_line(f"error: could not remove '{d.path}': {err.strerror or err}"), file=sys.stderr)
                code = EXIT_BAD_INPUT
                continue
            removed += 1
            print(f"removed {d.describe()}")
    if remove:
        print(f"removed {removed} of {len(found)} staging directories")
    else:
        free = sum(not d.owner_running for d in found)
        print(f"{len(found)} staging directories, {free} not in use; remove those with: {command} --clean-partial {folder}")
    return code


@contextlib.contextmanager
def errors_naming(path: Path) -> Iterator[None]:
    """Turn an ``OSError`` inside the block (a full disk) into a :class:`TrainError` naming ``path``."""
    try:
        yield
    except OSError as err:
        raise TrainError(f"could not write '{path}': {err.strerror or err}") from None


def check_output(out: Path, force: bool, eval_only: bool = False) -> None:
    """:class:`TrainError` if ``out`` is a file, or holds a run (:func:`run_entries`) and ``force`` is not
    set. Reads only; the staging directory (:class:`Staging`) is the write test."""
    try:
        is_file = out.exists() and not out.is_dir()
    except OSError as err:  # e.g. a name too long for the file system
        raise TrainError(f"output directory '{out}' cannot be used: {err.strerror or err}") from None
    if is_file:
        raise TrainError(f"output directory '{out}' exists and is a file, not a directory")
    existing = run_entries(out)
    if existing and not force:
        kind = "results" if eval_only and set(existing) & set(RESULT_FILES) else "a run"
        shown = [n for n in existing if n in RESULT_FILES] if kind == "results" else existing
        hint = "omit it (a new eval-<timestamp> directory)" if eval_only else "use another --output"
        raise TrainError(f"output directory '{out}' already holds {kind} ({', '.join(shown[:6])}); {hint}, "
                         "or add --force to replace it")


def eval_output_dir(checkpoint: Path, output: str | None, force: bool) -> Path:
    """Where ``--eval-only`` writes: ``output`` (refused if it holds a run, unless ``force``, and if it holds
    the checkpoint), else a new ``eval-<UTC timestamp>`` directory beside the checkpoint (its run directory
    for ``checkpoints/*.zip``)."""
    if output is not None:
        out = Path(output)
        if out.resolve() in checkpoint.resolve().parents:
            raise TrainError(f"--output '{out}' holds the checkpoint being evaluated; omit --output (a new "
                             "eval-<timestamp> directory is made beside it) or choose another directory")
        check_output(out, force, eval_only=True)
        return out
    run = checkpoint.parent.parent if checkpoint.parent.name == "checkpoints" else checkpoint.parent
    stamp = time.strftime("%Y%m%d-%H%M%S", time.gmtime())
    out = run / f"eval-{stamp}"
    k = 2
    while out.exists():
        out, k = run / f"eval-{stamp}-{k}", k + 1
    return out
