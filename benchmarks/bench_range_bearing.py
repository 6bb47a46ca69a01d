"""Cost per control step of the IR layer + range & bearing sensing, vs physics + ideal observations.

    python benchmarks/bench_range_bearing.py [--sizes 100 1000] [--platform droplet] [--steps 10] [--occlusion ray centre]

Issue target (measured, not asserted): R&B adds less than physics + ideal observation at n = 1000.
Density: the env's default for the platform (arena side = spacing x sqrt(N)). ``--occlusion``: the IR layer's
line-of-sight rule(s) to time (``ray``: per-ray, docs/design.md#infrared-physical-layer, the default; ``centre``: one centre-to-centre segment per pair).
"""

from __future__ import annotations

import argparse
import time

import numpy as np


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[100, 1000])
    parser.add_argument("--platform", default="droplet")
    parser.add_argument("--steps", type=int, default=10)
    parser.add_argument("--occlusion", nargs="+", default=["ray"], choices=["ray", "centre", "none"])
    args = parser.parse_args(argv)

    import swarm_envs
    from swarm_envs.ir.layer import compute_links
    from swarm_envs.sensing.range_bearing import RangeBearingSensor

    print(f"platform={args.platform}, default density (ms per control step)")
    print("| n_robots | occlusion | links/step | IR layer | R&B sensor | IR + R&B | physics | ideal obs | physics + ideal obs |")
    print("|---|---|---|---|---|---|---|---|---|")
    for n, occlusion in ((n, o) for n in args.sizes for o in args.occlusion):
        env = swarm_envs.make("swarm_envs/Aggregation-v0", n_robots=n, platform=args.platform, sensing="ideal", max_cycles=10**6)
        env.reset(seed=0)
        sensor = RangeBearingSensor(env.platform, n, np.random.default_rng(0))
        rng = np.random.default_rng(1)
        act = rng.uniform(-0.5, 0.5, (n, 2))
        sensor.step(compute_links(env.world.positions, env.world.headings, env.platform, occlusion=occlusion))  # warm-up (JIT load)
        t = dict.fromkeys(("layer", "rb", "physics", "ideal"), 0.0)
        n_links = 0
        for _ in range(args.steps):
            t0 = time.perf_counter()
            env.world.step(act[:, 0] * env.platform.max_speed, act[:, 1] * env.platform.max_angular_speed, 0.1)
            t1 = time.perf_counter()
            env.core.frame = env.sensing.step(env.world.positions, env.world.headings, None)
            env._observations()
            t2 = time.perf_counter()
            links = compute_links(env.world.positions, env.world.headings, env.platform, occlusion=occlusion)
            t3 = time.perf_counter()
            sensor.step(links)
            t4 = time.perf_counter()
            n_links += len(links)
            for key, dt in zip(("physics", "ideal", "layer", "rb"), (t1 - t0, t2 - t1, t3 - t2, t4 - t3)):
                t[key] += dt
        ms = {k: 1e3 * v / args.steps for k, v in t.items()}
        print(
            f"| {n} | {occlusion} | {n_links // args.steps} | {ms['layer']:.1f} | {ms['rb']:.1f} | {ms['layer'] + ms['rb']:.1f} | "
            f"{ms['physics']:.1f} | {ms['ideal']:.1f} | {ms['physics'] + ms['ideal']:.1f} |",
            flush=True,
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
