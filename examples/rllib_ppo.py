"""One shared PPO policy for every robot with RLlib (new API stack), from one machine to a Ray cluster.

    pip install -e ".[rllib]"
    python examples/rllib_ppo.py --task swarm_envs/Flocking-v0 --num-env-runners 2
    python examples/rllib_ppo.py --import examples/custom_task.py --task swarm_examples/Dispersion-v0
    # on a running Ray cluster (see below):
    python examples/rllib_ppo.py --address auto --num-env-runners 32 --iterations 200

**Observation.** The env keeps its default ``Dict`` observation (range & bearing, messages,
scale-free coordinates, rigidity, proprioception). RLlib's default RLModule has no encoder for a
``Dict`` (``No default encoder config for obs space=Dict(...)``), so the env-to-module pipeline gets
RLlib's own :class:`~ray.rllib.connectors.env_to_module.FlattenObservations` connector
(``multi_agent=True``), which flattens each robot's Dict into one vector before the MLP. Why a
connector and not the env's ``flatten=True``: the env stays exactly the one every other library
and the suite's own tools see (same observation, infos and metrics), and the flattening is declared
in the algorithm config, RLlib's documented place for observation preprocessing, so it travels
with the config to every env runner. (``flatten=True`` works too: ``--env-flatten`` skips the
connector and flattens in the env instead.)

**Shared policy.** Every robot maps to one module ``"shared"`` (``policy_mapping_fn``): the robots
are interchangeable, and all their experience trains the same weights.

**More env runners, more machines.** ``--num-env-runners K`` starts K Ray actors that each step their
own copy of the env (one CPU each) while the learner trains on the local process. To go beyond one
machine, start a Ray cluster and pass its address:

    # head node                                  # every worker node
    ray start --head --port=6379                 ray start --address=HEAD_IP:6379
    # then, on the head node (or any machine that can reach it):
    python examples/rllib_ppo.py --address auto --num-env-runners 64

Every node needs the same Python, ``swarm_envs[rllib]`` and Ray version installed (or pass a
``runtime_env`` to ``ray.init``). Env runners are spread over the cluster's CPUs by Ray; the batch
per iteration (``--batch``, env steps: RLlib counts env steps, each one steps every robot)
should grow with K so that each runner samples at least one episode per iteration.

**Threads.** The driver (which runs the learner) uses 1 torch intra-op thread on machines with at most
2 cores and ``min(4, cores // 2)`` above (``--torch-threads`` or ``OMP_NUM_THREADS`` override it); Ray
gives each env runner ``OMP_NUM_THREADS`` = its CPUs (1).
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path
from typing import Any

import ray
from ray.rllib.algorithms.ppo import PPOConfig
from ray.rllib.connectors.env_to_module import FlattenObservations
from ray.rllib.core.rl_module.multi_rl_module import MultiRLModuleSpec
from ray.rllib.core.rl_module.rl_module import RLModuleSpec
from ray.rllib.env.wrappers.pettingzoo_env import ParallelPettingZooEnv
from ray.tune.registry import register_env

import swarm_envs
from swarm_envs.agents.tasks import import_modules, import_task
from swarm_envs.adapters.torch_threads import set_torch_threads

ENV_NAME = "swarm_envs_parallel"
POLICY = "shared"


def env_creator(config: dict[str, Any]) -> ParallelPettingZooEnv:
    """RLlib env factory: ``config = {"task": env id, "imports": modules, **env kwargs}`` (runs inside each
    env runner, which first imports the modules that register a task of your own)."""
    config = dict(config)
    import_modules(config.pop("imports", []))
    return ParallelPettingZooEnv(swarm_envs.make(config.pop("task"), **config))


def flatten_connector(env: Any = None, spaces: Any = None, device: Any = None) -> FlattenObservations:
    """Env-to-module connector: flatten every agent's Dict observation into one vector."""
    return FlattenObservations(multi_agent=True)


def build_config(
    task: str,
    env_kwargs: dict[str, Any],
    num_env_runners: int,
    batch: int,
    minibatch: int,
    epochs: int,
    lr: float,
    seed: int,
    flatten_in_env: bool = False,
    hidden: int = 64,
    imports: list[str] | None = None,
) -> PPOConfig:
    """PPO with one module shared by all robots; ``num_env_runners`` = 0 samples on the driver; ``imports``:
    modules (or .py files) each env runner imports before making the env, e.g. one registering ``task``."""
    imports = [str(Path(m).resolve()) if m.endswith(".py") else m for m in imports or []]
    env_config = {"task": task, "imports": imports, **env_kwargs, "flatten": flatten_in_env}
    runners: dict[str, Any] = {"num_env_runners": num_env_runners, "num_envs_per_env_runner": 1}
    if not flatten_in_env:
        runners["env_to_module_connector"] = flatten_connector
    return (
        PPOConfig()
        .environment(ENV_NAME, env_config=env_config)
        .env_runners(**runners)
        .multi_agent(policies={POLICY}, policy_mapping_fn=lambda agent_id, episode, **kw: POLICY)
        .rl_module(
            rl_module_spec=MultiRLModuleSpec(
                rl_module_specs={POLICY: RLModuleSpec(model_config={"fcnet_hiddens": [hidden, hidden], "fcnet_activation": "tanh"})}
            )
        )
        .training(train_batch_size_per_learner=batch, minibatch_size=minibatch, num_epochs=epochs, lr=lr)
        .debugging(seed=seed)
    )


def main(argv: list[str] | None = None) -> list[dict[str, float]]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", default="swarm_envs/Aggregation-v0", help="a registered env id")
    parser.add_argument("--import", dest="imports", action="append", default=[], metavar="MODULE",
                        help="import a module or .py file first (here and in every env runner), e.g. one that registers a task of your own")
    parser.add_argument("--n-robots", type=int, default=6)
    parser.add_argument("--max-cycles", type=int, default=100, help="episode length in control steps (0.1 s each)")
    parser.add_argument("--sensing", default="full", choices=["full", "ideal"])
    parser.add_argument("--num-env-runners", type=int, default=2, help="Ray actors that step envs (0: sample on the driver)")
    parser.add_argument("--address", default=None, help="Ray cluster to join, e.g. 'auto' or HEAD_IP:6379 (default: start Ray locally)")
    parser.add_argument("--iterations", type=int, default=5)
    parser.add_argument("--batch", type=int, default=400, help="env steps per training iteration (each steps every robot)")
    parser.add_argument("--minibatch", type=int, default=100, help="RLlib's minibatch_size")
    parser.add_argument("--epochs", type=int, default=4)
    parser.add_argument("--lr", type=float, default=3e-4)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--env-flatten", action="store_true", help="use the env's flatten=True instead of the connector")
    parser.add_argument("--torch-threads", type=int, default=None, help="the driver's (learner's) torch threads; default: 1 on <= 2 cores, else min(4, cores // 2)")
    args = parser.parse_args(argv)
    try:
        import_task(args.imports, args.task)
    except (ImportError, ValueError) as err:
        parser.error(str(err))
    set_torch_threads(args.torch_threads)  # Ray's env runners get OMP_NUM_THREADS = their CPUs (1) from Ray

    register_env(ENV_NAME, env_creator)
    started_here = not ray.is_initialized()
    if started_here:
        ray.init(address=args.address, include_dashboard=False, log_to_driver=False)
    env_kwargs = {"n_robots": args.n_robots, "max_cycles": args.max_cycles, "sensing": args.sensing}
    config = build_config(
        args.task, env_kwargs, args.num_env_runners, args.batch, args.minibatch, args.epochs, args.lr, args.seed, args.env_flatten,
        imports=args.imports,
    )
    algo = config.build_algo()
    history = []
    try:
        for i in range(args.iterations):
            start = time.perf_counter()
            result = algo.train()
            elapsed = time.perf_counter() - start
            runners = result["env_runners"]
            steps = runners["num_agent_steps_sampled"]  # per agent id
            row = {
                "iteration": i,
                "agent_steps": float(sum(steps.values()) if isinstance(steps, dict) else steps),
                "seconds": elapsed,
                # wall time of the (parallel) sampling phase alone, as RLlib's PPO timed it
                "sample_seconds": float(result.get("timers", {}).get("env_runner_sampling_timer", float("nan"))),
                "episode_return_mean": float(runners.get("episode_return_mean", float("nan"))),
            }
            row["agent_steps_per_s"] = row["agent_steps"] / elapsed
            row["sample_agent_steps_per_s"] = row["agent_steps"] / row["sample_seconds"]
            history.append(row)
            print(
                f"iter {i:3d}  agent steps {row['agent_steps']:6.0f}  sampling {row['sample_agent_steps_per_s']:5.0f} agent-steps/s  "
                f"whole iteration {row['agent_steps_per_s']:5.0f} agent-steps/s  episode return {row['episode_return_mean']:+.4f}",
                flush=True,
            )
    finally:
        algo.stop()
        if started_here:
            ray.shutdown()
    return history


if __name__ == "__main__":
    main()
