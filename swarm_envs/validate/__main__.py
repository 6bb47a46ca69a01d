"""Validation command line: reproduce the source papers' published figures and print ours beside theirs.

Usage: ``python -m swarm_envs.validate {range-bearing,swarmcom,scale-free,centroid,behaviours} [--json] [options]``.
Each experiment lives in its own module with a ``main(argv) -> int`` function. Options are checked by the
same rules as the env settings (:func:`swarm_envs.tasks.settings_cli.cli_type`): a bad value is a one-line usage error
naming the option (:class:`swarm_envs.tasks.settings.OneLineArgumentParser`), exit code 2; a plot directory
that cannot be written is one ``error:`` line, exit code 2.
"""

from __future__ import annotations

import importlib
import sys

EXPERIMENTS = {
    "range-bearing": ("swarm_envs.validate.range_bearing", "Droplet range & bearing error sweep [F14 Figs. 5-7]"),
    "swarmcom": ("swarm_envs.validate.swarmcom", "SwarmCom range, channels, flooding, coding [T20 Figs. 12, 13, 16, 20, 21]"),
    "scale-free": ("swarm_envs.validate.scale_free", "rigidity vs degree and 2-hop edge error [L Figs. 5.1, 6.2]"),
    "centroid": ("swarm_envs.validate.centroid", "static-anchor centroid seeking [L Sec. 6.2.2]"),
    "behaviours": ("swarm_envs.validate.behaviours", "r-one behaviours' trajectories and metrics [L Sec. 6.4, Figs. 6.7-6.10]"),
}


def main(argv: list[str] | None = None) -> int:
    """Command line of ``swarm-validate``: run the experiment ``argv[0]`` with its options; returns the exit
    code (0 ok or help, 2 an unknown experiment, a bad option or a folder that cannot be written)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or argv[0] in ("-h", "--help") or argv[0] not in EXPERIMENTS:
        print(__doc__.strip())
        print("\nexperiments:")
        for name, (_, what) in EXPERIMENTS.items():
            print(f"  {name:14s} {what}")
        if argv and argv[0] not in ("-h", "--help"):
            print(f"error: unknown experiment {argv[0]!r}; allowed: {', '.join(EXPERIMENTS)}", file=sys.stderr)
            return 2
        return 0
    module = importlib.import_module(EXPERIMENTS[argv[0]][0])
    try:
        return int(module.main(argv[1:]) or 0)
    except OSError as err:  # e.g. --out names a file, or a directory that cannot be written
        where = f" '{err.filename}'" if getattr(err, "filename", None) else ""
        print(f"error: could not write{where}: {err.strerror or err}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
