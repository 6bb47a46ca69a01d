"""Run a short episode with a simple scripted behaviour and write a GIF.

``python -m swarm_envs.demo --task flocking --out demo.gif [--platform epuck] [--sensing full] [--steps 150]``

The behaviour is a minimal one that reads only the observation (steer towards the mean bearing of
the neighbours, away when too close), so the GIF shows what the sensing stack lets a robot do.
"""

from __future__ import annotations

import argparse
import sys

import numpy as np

from swarm_envs.env import info_group

TASKS = {"aggregation": "swarm_envs/Aggregation-v0", "flocking": "swarm_envs/Flocking-v0", "centroid_seeking": "swarm_envs/CentroidSeeking-v0"}


def cohesive_walk(obs: dict[str, np.ndarray], diameter: float) -> np.ndarray:
    """Turn towards the neighbours' mean bearing (away from any closer than 1.5 diameters)."""
    rb = obs["range_bearing"]
    valid = rb[:, 0] > 0
    if not valid.any():
        return np.array([0.6, 0.3], np.float32)
    vec = (rb[valid, 2:4]).sum(axis=0)
    if np.any(rb[valid, 1] < 1.5 * diameter):
        vec = -(rb[valid & (rb[:, 1] < 1.5 * diameter), 2:4]).sum(axis=0)
    turn = np.arctan2(vec[1], vec[0])
    return np.array([0.8 * max(np.cos(turn), 0.0), np.clip(turn, -1, 1)], np.float32)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m swarm_envs.demo", description=__doc__.split("\n\n")[0])
    parser.add_argument("--task", choices=sorted(TASKS), default="flocking")
    parser.add_argument("--out", default="demo.gif", help="GIF path")
    parser.add_argument("--platform", default="epuck")
    parser.add_argument("--sensing", default="full", choices=["full", "ideal"])
    parser.add_argument("--n-robots", type=int, default=None)
    parser.add_argument("--steps", type=int, default=150)
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args(argv)

    import imageio.v3 as iio

    import swarm_envs

    kwargs = {"platform": args.platform, "sensing": args.sensing, "render_mode": "rgb_array", "max_cycles": args.steps}
    if args.n_robots is not None:
        kwargs["n_robots"] = args.n_robots
    env = swarm_envs.make(TASKS[args.task], **kwargs)
    obs, _ = env.reset(seed=args.seed)
    frames = [env.render()]
    infos = {}
    while env.agents:
        actions = {a: cohesive_walk(obs[a], env.platform.diameter) for a in env.agents}
        obs, _, _, _, infos = env.step(actions)
        frames.append(env.render())
    env.close()
    # Pillow's GIF writer takes the frame delay in milliseconds (a GIF stores centiseconds):
    # one control step per frame, shown at the env's render_fps (10 fps = 100 ms per frame).
    frame_ms = 1000.0 / env.metadata["render_fps"]
    iio.imwrite(args.out, np.stack(frames), plugin="pillow", extension=".gif", duration=frame_ms, loop=0)
    metrics = info_group(next(iter(infos.values())), "metrics") if infos else {}
    print(f"wrote {args.out}: {len(frames)} frames; final metrics: " + ", ".join(f"{k}={v:.3f}" for k, v in metrics.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
