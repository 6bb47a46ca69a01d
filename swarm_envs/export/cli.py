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
    parser.add_argument("--evaluate", action="store_true", help="then compile the C on this machine and evaluate it and the torch "
                        "policy in the loop over the run's evaluation seeds (needs a C compiler)")
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
    if args.evaluate:
        from pathlib import Path

        from swarm_envs.export.compare import action_difference, evaluate_export
        from swarm_envs.export.host import compile_shared, compiler, object_sizes
        from swarm_envs.export.run import load_run

        if compiler() is None:
            print("swarm-export: error: --evaluate needs a C compiler (cc, gcc or clang)", file=sys.stderr)
            return 2
        run, folder = load_run(args.run_dir), Path(args.output)
        sizes = object_sizes(folder)
        print(f"policy.o (host, -Os): text {sizes['text']} B, data {sizes['data']} B, bss {sizes['bss']} B")
        ev = run.cfg["eval"]
        worst, _ = action_difference(run, compile_shared(folder), [ev["seed_start"]], 50)
        print(f"largest |C - torch| action difference over the first 50 steps (or the whole episode) of seed {ev['seed_start']}: {worst:.3g}")
        print(evaluate_export(run, folder).text())
    return 0
