"""Batched 2-hop scale-free coordinates: compiled path vs the numpy reference (same inputs, same outputs).

Usage: ``python benchmarks/bench_two_hop_kernels.py [--sizes 100 1000 2560] [--k 16] [--reps 10]``

Knowledge comes from an ideal bearing exchange over r-one sector readings in a random arena (as in
``bench_scale_free.py``); both paths are timed on it and checked to agree bit for bit. Prints ms per call
(mean of ``reps`` after a warm-up); the machine may be shared, so the same-run ratio is the figure to quote.
"""

from __future__ import annotations

import argparse
import os
import sys

import numpy as np

os.environ.setdefault("OMP_NUM_THREADS", "1")
sys.path.insert(0, os.path.dirname(__file__))

from bench_scale_free import place, timeit  # noqa: E402

from swarm_envs.ir.layer import compute_links  # noqa: E402
from swarm_envs.sensing.bearing_sensor import sense_bearings  # noqa: E402
from swarm_envs.sensing.exchange import BearingExchange  # noqa: E402
from swarm_envs._compile.reference import coordinates_all as coordinates_all_numpy  # noqa: E402
from swarm_envs.sensing.scale_free import coordinates_all  # noqa: E402


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[100, 1000, 2560])
    ap.add_argument("--density", type=float, default=3.0, help="robots per m^2")
    ap.add_argument("--k", type=int, default=16, help="neighbour slots K")
    ap.add_argument("--reps", type=int, default=10)
    args = ap.parse_args()
    rng = np.random.default_rng(0)
    print("| N | K | mean deg | numpy ms | compiled ms | ratio | NS and BFS identical |")
    print("|---|---|---|---|---|---|---|")
    for n in args.sizes:
        side = float(np.sqrt(n / args.density))
        pos = place(rng, n, side, 0.055)
        links = compute_links(pos, rng.uniform(-np.pi, np.pi, n), "rone")
        kn = BearingExchange(n, "ideal", k_max=args.k).step(sense_bearings(links, "rone"))
        t_ref, ref = timeit(lambda: coordinates_all_numpy(kn), args.reps)
        t_new, new = timeit(lambda: coordinates_all(kn), args.reps)
        same = all(
            np.array_equal(getattr(a, f), getattr(b, f), equal_nan=getattr(a, f).dtype.kind == "f")
            for a, b in [(ref, new), (coordinates_all_numpy(kn, False), coordinates_all(kn, False))]
            for f in ("xy", "valid", "rigid", "length")
        )
        deg = (kn.ids >= 0).sum(1).mean()
        print(f"| {n} | {args.k} | {deg:.1f} | {t_ref:.2f} | {t_new:.2f} | {t_ref / t_new:.1f}x | {same} |")


if __name__ == "__main__":
    main()
