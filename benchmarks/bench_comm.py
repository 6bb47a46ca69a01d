"""SwarmCom cost per control step: ``Network.step`` (bit-level simulation), numpy reference vs numba kernel.

    python benchmarks/bench_comm.py [--sizes 10 100 1000] [--steps 30] [--bitrate 310]

Scene: e-puck, the env's default density (arena side = 0.25 m x sqrt(N), i.e. 16 robots/m^2), robots on a
jittered grid with random headings, moving a little every step (links recomputed every step, timed apart).
Loads: ``idle`` (nothing queued: detectors, ADC noise and ambient tracking only), ``exchange`` (bearing-
exchange-like system traffic: every robot queues one ~60-bit message every 10 steps with its own phase,
as :class:`swarm_envs.sensing.exchange.BearingExchange`), ``all`` (every robot queues an 8-bit message
every step, the saturated case). Both backends see the same scenes and traffic and must deliver the same
frames (checked). One process, one thread; milliseconds per 0.1 s control step (the first, compiling
steps are not timed).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from swarm_envs.comm.network import Network
from swarm_envs.ir.layer import compute_links


def scene(n: int, rng: np.random.Generator, spacing: float = 0.25) -> tuple[np.ndarray, np.ndarray]:
    g = int(np.ceil(np.sqrt(n)))
    xs = (np.arange(g) + 0.5) * spacing
    pos = np.stack(np.meshgrid(xs, xs), -1).reshape(-1, 2)[:n]
    pos = pos + rng.uniform(-0.08, 0.08, pos.shape)
    return pos, rng.uniform(-np.pi, np.pi, n)


def measure(n: int, load: str, steps: int, bitrate: float, backend: str, seed: int = 0, code=(15, 15), mode="broadcast") -> dict[str, float]:
    rng = np.random.default_rng(seed)
    pos, head = scene(n, rng)
    net = Network("epuck", n, np.random.default_rng(seed + 1), bitrate=bitrate, code=code, comm_mode=mode, backend=backend)
    phase = rng.integers(0, 10, n)
    ex_bits = 4 + 5 * (net.fmt.id_bits + 4)  # count + 5 x (neighbour id, bearing sector)
    t_links = t_step = 0.0
    delivered = 0
    warm = 3
    for k in range(steps + warm):
        head = head + rng.uniform(-0.05, 0.05, n)  # small motion so links change
        if load == "all":
            net.send_many(np.arange(n), rng.integers(0, 2, (n, 8)).astype(bool))
        elif load == "exchange":
            who = np.flatnonzero((k - phase) % 10 == 0)
            if who.size:
                net.queue_system(who, rng.integers(0, 2, (who.size, ex_bits)).astype(bool), "bearing")
        t0 = time.perf_counter()
        links = compute_links(pos, head, "epuck")
        t1 = time.perf_counter()
        d = net.step(links)
        t2 = time.perf_counter()
        delivered += len(d)
        if k >= warm:
            t_links += t1 - t0
            t_step += t2 - t1
    return {
        "links_ms": 1e3 * t_links / steps,
        "step_ms": 1e3 * t_step / steps,
        "frames_per_step": net.stats["tx_started"] / (steps + warm),
        "delivered": delivered,
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[10, 100, 1000])
    ap.add_argument("--steps", type=int, default=30)
    ap.add_argument("--bitrate", type=float, default=310)
    args = ap.parse_args()
    print(f"e-puck, {args.bitrate:.0f} bps ({args.bitrate * 0.1:.0f} bit slots per step), density 16 robots/m^2, code [15,15], broadcast")
    print(f"{'N':>6} {'load':>8} | {'compute_links ms':>16} | {'numpy step ms':>13} | {'numba step ms':>13} | {'speed-up':>8} | {'frames/step':>11} | {'delivered':>9}")
    for n in args.sizes:
        for load in ("idle", "exchange", "all"):
            r = {b: measure(n, load, args.steps, args.bitrate, b) for b in ("numpy", "numba")}
            same = "" if r["numpy"]["delivered"] == r["numba"]["delivered"] else "  MISMATCH"
            print(
                f"{n:>6} {load:>8} | {r['numba']['links_ms']:16.2f} | {r['numpy']['step_ms']:13.2f} | {r['numba']['step_ms']:13.2f} | "
                f"{r['numpy']['step_ms'] / r['numba']['step_ms']:7.1f}x | {r['numba']['frames_per_step']:11.1f} | {r['numba']['delivered']:9d}{same}"
            )


if __name__ == "__main__":
    main()
