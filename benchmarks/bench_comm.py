"""SwarmCom cost per control step: ``compute_links`` + ``Network.step`` (bit-level simulation).

    python benchmarks/bench_comm.py [--sizes 100 1000] [--steps 30] [--bitrate 310]

Scene: e-puck, the env's default density (arena side = 0.25 m x sqrt(N), i.e. 16 robots/m^2), robots on a
jittered grid with random headings, moving a little every step (links recomputed every step). Two loads:
``10%`` (each robot queues an 8-bit message with probability 0.1 per step, ~1 message/s) and ``all``
(every robot queues a message every step, the saturated case of an env whose agents always talk).
One process, one thread; numbers are milliseconds per 0.1 s control step.
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


def measure(n: int, load: float, steps: int, bitrate: float, seed: int = 0, code=(15, 15), mode="broadcast") -> dict[str, float]:
    rng = np.random.default_rng(seed)
    pos, head = scene(n, rng)
    net = Network("epuck", n, rng, bitrate=bitrate, code=code, comm_mode=mode)
    t_links = t_step = 0.0
    n_links = 0
    warm = 5
    for k in range(steps + warm):
        head = head + rng.uniform(-0.05, 0.05, n)  # small motion so links change
        send = np.flatnonzero(rng.random(n) < load)
        net.send_many(send, rng.integers(0, 2, (send.size, 8)).astype(bool))
        t0 = time.perf_counter()
        links = compute_links(pos, head, "epuck")
        t1 = time.perf_counter()
        net.step(links)
        t2 = time.perf_counter()
        if k >= warm:
            t_links += t1 - t0
            t_step += t2 - t1
            n_links += len(links)
    s = net.stats
    return {
        "links_ms": 1e3 * t_links / steps,
        "step_ms": 1e3 * t_step / steps,
        "links": n_links / steps,
        "delivered_per_step": s["rx_delivered"] / (steps + warm),
        "frames_per_step": s["tx_started"] / (steps + warm),
    }


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[100, 1000])
    ap.add_argument("--steps", type=int, default=30)
    ap.add_argument("--bitrate", type=float, default=310)
    args = ap.parse_args()
    print(f"e-puck, {args.bitrate:.0f} bps ({args.bitrate * 0.1:.0f} bit slots per step), density 16 robots/m^2, code [15,15], broadcast")
    print(f"{'N':>6} {'load':>5} | {'links/step':>10} | {'compute_links ms':>16} | {'Network.step ms':>15} | {'total ms':>8} | {'frames/step':>11} | {'delivered/step':>14}")
    for n in args.sizes:
        for load, label in ((0.1, "10%"), (1.0, "all")):
            r = measure(n, load, args.steps, args.bitrate)
            print(
                f"{n:>6} {label:>5} | {r['links']:10.0f} | {r['links_ms']:16.1f} | {r['step_ms']:15.1f} | "
                f"{r['links_ms'] + r['step_ms']:8.1f} | {r['frames_per_step']:11.1f} | {r['delivered_per_step']:14.1f}"
            )


if __name__ == "__main__":
    main()
