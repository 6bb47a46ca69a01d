"""``swarm-export RUN_DIR --output DIR [--fixed q15|int8 | --int8]``: a trained run as C sources for the robot."""

from __future__ import annotations

import argparse
import sys

__all__ = ["main"]


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="swarm-export", description="Export a train.py run (model.zip + config.yaml) as dependency-free C99: "
                                     "policy.h/.c, actions.h/.c, README.md (docs/export.md).")
    parser.add_argument("run_dir", help="the run's output folder (holds config.yaml and model.zip)")
    parser.add_argument("--output", "-o", required=True, help="folder to write the C sources into")
    group = parser.add_mutually_exclusive_group()
    group.add_argument("--fixed", choices=("q15", "int8"), help="integer build: int16 (q15) or int8 weights, integer arithmetic")
    group.add_argument("--int8", action="store_true", help="same as --fixed int8")
    parser.add_argument("--no-onnx", action="store_true", help="do not write policy.onnx")
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the CLI; returns the exit code (0 done, 2 bad arguments or a run that cannot be exported)."""
    args = _parser().parse_args(argv)
    from swarm_envs.export.export import export_run
    from swarm_envs.export.run import ExportError

    fixed = "int8" if args.int8 else args.fixed
    try:
        files = export_run(args.run_dir, args.output, fixed=fixed, onnx=not args.no_onnx)
    except ExportError as err:
        print(f"swarm-export: error: {err}", file=sys.stderr)
        return 2
    print(f"wrote {len(files)} files to {args.output}: {', '.join(f.name for f in files)}")
    return 0
