"""Check an export folder against the trained torch policy on the simulator: the actions on the same
observations, and the task metrics of in-the-loop evaluation episodes."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from swarm_envs.export.host import CPolicy, compile_shared
from swarm_envs.export.run import LoadedRun

__all__ = ["action_difference", "evaluate_export", "Comparison"]


def _torch_policy(run: LoadedRun, env: Any):
    from swarm_envs.agents.policies import TrainedPolicy

    return TrainedPolicy(run.model, env.platform, env.layout, run.spec, deterministic=True)


def _c_policy(run: LoadedRun, library: Path, env: Any) -> CPolicy:
    return CPolicy(library, env.platform, env.layout, run.obs_size, run.action_size)


def action_difference(run: LoadedRun, library: Path, seeds: list[int], steps: int) -> tuple[float, int]:
    """(largest |C action - torch action|, empty observation rows seen) over ``steps`` control steps of
    each seed's episode (fewer if it ends first), both policies fed the same observations (the env driven by the torch actions;
    both reset at every episode start)."""
    from swarm_envs.agents.evaluation import make_env

    env = make_env(run.cfg["task"], **run.env_kwargs)
    reference, c = _torch_policy(run, env), _c_policy(run, library, env)
    worst, empty = 0.0, 0
    try:
        for seed in seeds:
            env.reset(seed=seed)
            reference.reset(env.n_agents)
            c.reset(env.n_agents)
            for _ in range(steps):
                parts = {k: v[env.agent_robots] for k, v in env.batched_observations().items()}
                empty += int((parts["range_bearing"][..., 0] < 0.5).all(axis=1).sum())
                a, b = reference.act_batch(parts), c.act_batch(parts)
                worst = max(worst, float(np.abs(a - b).max()))
                *_, terminations, truncations, _ = env.step({agent: a[i] for i, agent in enumerate(env.possible_agents)})
                if all(terminations.values()) or all(truncations.values()):
                    break  # the episode ended before ``steps``
    finally:
        env.close()
    return worst, empty


@dataclass
class Comparison:
    """Per-seed values of the task's headline metric for the torch and the C policy."""

    metric: str
    torch: np.ndarray
    c: np.ndarray

    def text(self) -> str:
        diff = np.abs(self.torch - self.c)
        return (f"{self.metric} over {len(self.c)} seeds: torch {self.torch.mean():.4f} (+-{self.torch.std():.4f}), "
                f"C {self.c.mean():.4f} (+-{self.c.std():.4f}); largest per-seed difference {diff.max():.3g}, "
                f"seeds with identical values {int((diff == 0).sum())}/{len(diff)}")


def evaluate_export(run: LoadedRun, folder: Path, seeds: list[int] | None = None, max_cycles: int | None = None) -> Comparison:
    """Compile ``folder`` and evaluate it and the torch policy in the loop (the run's evaluation seeds and
    ``eval.max_cycles`` unless given): the headline metric per seed of each."""
    from swarm_envs.agents.evaluation import evaluate
    from swarm_envs.agents.tasks import headline

    library = compile_shared(folder)
    ev = run.cfg["eval"]
    seeds = seeds if seeds is not None else list(range(ev["seed_start"], ev["seed_start"] + ev["n_seeds"]))
    kwargs = dict(run.env_kwargs)
    if (max_cycles or ev["max_cycles"]) is not None:
        kwargs["max_cycles"] = max_cycles or ev["max_cycles"]
    best = headline(run.cfg["task"])
    metric = best[0] if best else "episode_return"
    torch_values = evaluate(run.cfg["task"], kwargs, lambda env: _torch_policy(run, env), seeds)[metric]
    c_values = evaluate(run.cfg["task"], kwargs, lambda env: _c_policy(run, library, env), seeds)[metric]
    return Comparison(metric, torch_values, c_values)
