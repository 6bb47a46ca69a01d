"""Smoke test of an installed swarm_envs wheel, run by .ci/run from a directory outside the repository.

    <wheel-venv>/bin/python /path/to/.ci/wheel_smoke.py

Checks that the installed package (not a source tree) works with what the wheel brought: every registered
environment is made with full sensing, reset and stepped a few times with observations inside their
spaces; ``make_vec`` steps two copies; the console commands run (``swarm-demo`` writes a GIF,
``swarm-validate --help``, ``swarm-benchmark --help``, ``swarm-train --help``, ``swarm-export --help``: the wheel is installed
without the ``rl`` extra, so no torch, and the commands' help must not need it). Exits non-zero with a
one-line reason on the first failure.
"""

from __future__ import annotations

import subprocess
import sys
import time
from pathlib import Path

import numpy as np


def check(condition: bool, message: str) -> None:
    if not condition:
        raise SystemExit(f"wheel smoke test FAILED: {message}")


def main() -> int:
    t0 = time.perf_counter()
    import swarm_envs

    location = Path(swarm_envs.__file__).resolve()
    check("site-packages" in location.parts, f"swarm_envs imported from {location}, not from the installed wheel")
    check(not (Path.cwd() / "pyproject.toml").exists(), f"run from outside the repository, not {Path.cwd()}")
    import swarm_envs.agents.scripted  # noqa: F401  (agents/ installs as swarm_envs.agents)

    print(f"swarm_envs {swarm_envs.__version__} from {location.parent}")
    check(swarm_envs.__version__ != "0+unknown", "no version metadata in the installed package")

    for env_id in swarm_envs.list_envs():
        env = swarm_envs.make(env_id, sensing="full")
        observations, infos = env.reset(seed=0)
        rng = np.random.default_rng(0)
        for _ in range(3):
            actions = {agent: rng.uniform(-1, 1, env.action_space(agent).shape).astype(np.float32) for agent in env.agents}
            observations, rewards, terminations, truncations, infos = env.step(actions)
        for agent, obs in observations.items():
            check(env.observation_space(agent).contains(obs), f"{env_id}: {agent}'s observation is outside its space")
        check(all(np.isfinite(r) for r in rewards.values()), f"{env_id}: non-finite reward")
        print(f"  {env_id}: {len(env.agents)} agents, reset + 3 steps with full sensing ok")

    first = swarm_envs.list_envs()[0]
    vec = swarm_envs.make_vec(first, 2, n_robots=4)
    vec.reset(seed=0)
    _, rewards, *_ = vec.step(np.zeros((2, 4, vec.layout.action_size)))
    check(rewards.shape == (2, 4), f"make_vec rewards have shape {rewards.shape}")
    print(f"  make_vec({first!r}, 2): ok")

    bin_dir = Path(sys.executable).parent
    gif = Path.cwd() / "x.gif"
    commands = [
        ["swarm-demo", "--steps", "5", "--out", str(gif)],
        ["swarm-validate", "--help"],
        ["swarm-benchmark", "--help"],
        ["swarm-train", "--help"],  # its help needs no torch; training itself needs the 'rl' extra
        ["swarm-export", "--help"],  # likewise: exporting a run needs the 'rl' extra
    ]
    for command in commands:
        proc = subprocess.run([str(bin_dir / command[0]), *command[1:]], capture_output=True, text=True)
        check(proc.returncode == 0, f"{' '.join(command)} exited with {proc.returncode}: {proc.stderr.strip()[-300:]}")
        print(f"  {' '.join(command[:2])}: ok")
    check(gif.is_file() and gif.stat().st_size > 0, f"swarm-demo wrote no GIF at {gif}")

    print(f"wheel smoke test passed in {time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
