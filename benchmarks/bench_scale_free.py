"""Cost per control step of the bearing-only stack: IR links (shared layer, for reference), r-one sector
sensing, ideal bearing exchange and batched 2-hop scale-free coordinates.

Usage: ``python benchmarks/bench_scale_free.py [--sizes 100 1000] [--density 3.0] [--k 16] [--reps 10]``

Robots (r-one, 11 cm) are placed uniformly without overlap in a square arena whose side gives
``density`` robots per m^2 (3/m^2 ~ the thesis' N = 40 in a 4 m disc); random headings.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from swarm_envs.ir.layer import compute_links
from swarm_envs.sensing.bearing_sensor import sense_bearings
from swarm_envs.sensing.exchange import BearingExchange
from swarm_envs.sensing.scale_free import coordinates_all


def place(rng: np.random.Generator, n: int, side: float, r: float) -> np.ndarray:
    from scipy.spatial import cKDTree

    pts = rng.uniform(r, side - r, (n, 2))
    for _ in range(200):  # resample overlapping robots until none overlap
        pairs = cKDTree(pts).query_pairs(2 * r, output_type="ndarray")
        if len(pairs) == 0:
            return pts
        bad = np.unique(pairs[:, 1])
        pts[bad] = rng.uniform(r, side - r, (len(bad), 2))
    raise RuntimeError("could not place robots")


def timeit(fn, reps: int) -> tuple[float, object]:
    out = fn()  # warm-up
    t0 = time.perf_counter()
    for _ in range(reps):
        out = fn()
    return (time.perf_counter() - t0) / reps * 1e3, out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--sizes", type=int, nargs="+", default=[100, 1000])
    ap.add_argument("--density", type=float, default=3.0, help="robots per m^2")
    ap.add_argument("--k", type=int, default=16, help="neighbour slots K")
    ap.add_argument("--reps", type=int, default=10)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    rng = np.random.default_rng(args.seed)
    rows = []
    for n in args.sizes:
        side = float(np.sqrt(n / args.density))
        pos = place(rng, n, side, 0.055)
        hd = rng.uniform(-np.pi, np.pi, n)
        t_links, links = timeit(lambda: compute_links(pos, hd, "rone"), args.reps)
        t_sense, rd = timeit(lambda: sense_bearings(links, "rone"), args.reps)
        ex = BearingExchange(n, "ideal", k_max=args.k)
        t_ex, kn = timeit(lambda: ex.step(rd), args.reps)
        t_ns, res = timeit(lambda: coordinates_all(kn, noise_sensitivity=True), args.reps)
        t_bfs, _ = timeit(lambda: coordinates_all(kn, noise_sensitivity=False), args.reps)
        deg = (kn.ids >= 0).sum(1)
        rows.append((n, side, deg.mean(), deg.max(), t_links, t_sense, t_ex, t_ns, t_bfs, res.rigid.mean()))
    print(f"bearing-only stack per step (K = {args.k}, density {args.density}/m^2, mean of {args.reps} reps, ms)")
    hdr = ("N", "arena m", "mean deg", "max deg", "IR links*", "sense", "exchange", "2hop NS", "2hop BFS", "sense+ex+NS", "rigid %")
    print(" | ".join(f"{h:>10}" for h in hdr))
    for n, side, dm, dx, tl, ts, te, tn, tb, rig in rows:
        vals = (n, f"{side:.1f}", f"{dm:.1f}", dx, f"{tl:.2f}", f"{ts:.2f}", f"{te:.2f}", f"{tn:.2f}", f"{tb:.2f}", f"{ts + te + tn:.2f}", f"{rig * 100:.0f}")
        print(" | ".join(f"{v!s:>10}" for v in vals))
    print("* IR links = shared layer (swarm_envs.ir.layer.compute_links), not part of this module; shown for scale.")


if __name__ == "__main__":
    main()
