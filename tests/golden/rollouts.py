"""Fixed-seed rollouts of every registered env, reduced to digests: the golden record of what the suite computes.

    python tests/golden/rollouts.py            # rewrite tests/golden/rollouts.json (only for an intended change)

Each case (env id x sensing x platform) resets with seed 0 and steps ``STEPS`` times with actions drawn from
``numpy.random.default_rng(1)``; the observations, rewards, terminations, truncations and infos of every
step are rounded to ``DECIMALS`` decimals and hashed (SHA-256). ``tests/integration/test_golden.py`` recomputes them.
"""

from __future__ import annotations

import hashlib
import json
from pathlib import Path
from typing import Any

import numpy as np

import swarm_envs

RECORD = Path(__file__).with_name("rollouts.json")
PLATFORMS = ("epuck", "rone", "droplet")
SENSING = ("full", "ideal")
STEPS = 25
N_ROBOTS = 6
DECIMALS = 5


def cases() -> list[tuple[str, str, str]]:
    """(env id, sensing, platform) of the suite's own registered envs."""
    return [(env_id, sensing, platform) for env_id in swarm_envs.list_envs() if env_id.startswith("swarm_envs/")
            for sensing in SENSING for platform in PLATFORMS]


def _leaves(value: Any, path: str = "") -> dict[str, Any]:
    """``value``'s leaves by path (``"robot_0/metrics/n_clusters"``): nested dicts and dicts keyed by tuples
    give the same paths, so the digest holds the content, not the dict layout."""
    if not isinstance(value, dict):
        return {path: value}
    out: dict[str, Any] = {}
    for key, item in value.items():
        name = "/".join(map(str, key)) if isinstance(key, tuple) else str(key)
        out.update(_leaves(item, f"{path}/{name}" if path else name))
    return out


def _feed(h: "hashlib._Hash", value: Any) -> None:
    """Hash ``value`` (nested dicts, sequences, numbers, arrays), floats rounded to ``DECIMALS`` decimals."""
    if isinstance(value, dict):
        leaves = _leaves(value)
        for path in sorted(leaves):
            h.update(path.encode())
            _feed(h, leaves[path])
        return
    array = np.asarray(value)
    if array.dtype == object:
        for item in value:
            _feed(h, item)
        return
    if array.dtype.kind in "fc":
        array = np.round(array.astype(np.float64), DECIMALS) + 0.0  # + 0.0: -0.0 and 0.0 hash alike
    h.update(str(array.shape).encode())
    h.update(np.ascontiguousarray(array).tobytes())


def rollout(env_id: str, sensing: str, platform: str) -> str | None:
    """The digest of one case, or None when the env does not take that platform."""
    try:
        env = swarm_envs.make(env_id, sensing=sensing, platform=platform, n_robots=N_ROBOTS)
    except ValueError:
        return None
    rng = np.random.default_rng(1)
    h = hashlib.sha256()
    obs, infos = env.reset(seed=0)
    _feed(h, obs)
    _feed(h, infos)
    for _ in range(STEPS):
        actions = {a: rng.uniform(-1, 1, env.action_space(a).shape).astype(np.float32) for a in env.agents}
        for part in env.step(actions):
            _feed(h, part)
    env.close()
    return h.hexdigest()


def record() -> dict[str, str | None]:
    return {" ".join(case): rollout(*case) for case in cases()}


if __name__ == "__main__":
    RECORD.write_text(json.dumps(record(), indent=1) + "\n")
    print(f"wrote {RECORD}")
