"""MAPPO and IPPO from BenchMARL on a swarm task, through the suite's BenchMARL task family.

    pip install -e ".[benchmarl]"
    python examples/benchmarl_mappo.py                                  # flocking, MAPPO then IPPO, tiny budget
    python examples/benchmarl_mappo.py --task aggregation --frames 200000 --algorithms mappo

The task is :class:`swarm_envs.benchmarl_tasks.SwarmTask` (e.g. ``SwarmTask.FLOCKING``): BenchMARL builds
one batched TorchRL env of ``--num-envs`` copies per collector (``swarm_envs.make_torchrl``), with the
default ``Dict`` observation (each part flattened to a vector by the task family's transform; BenchMARL's
MLP concatenates them) and the global ground-truth ``state`` for MAPPO's centralised critic. IPPO's
critic sees each robot's own observation only. Frames are copy-steps (each steps every robot of a copy).

BenchMARL evaluates once after the last batch (into its loggers, with ``--log-dir``: csv files); then one
evaluation rollout of the trained policy (deterministic actions, ``--num-envs``
copies, one episode) gives the printed figures: the mean episode reward per robot and the task's metrics
averaged over the episode. Torch uses 1 intra-op thread on machines with at most 2 cores and
``min(4, cores // 2)`` above (``--torch-threads`` or ``OMP_NUM_THREADS`` override it).
"""

from __future__ import annotations

import argparse
import tempfile
import time

import torch
from benchmarl.algorithms import IppoConfig, MappoConfig
from benchmarl.experiment import Experiment, ExperimentConfig
from benchmarl.models.mlp import MlpConfig

from swarm_envs.benchmarl_tasks import GROUP, SwarmTask
from swarm_envs.torch_threads import set_torch_threads

ALGORITHMS = {"mappo": MappoConfig, "ippo": IppoConfig}


def experiment_config(frames: int, frames_per_batch: int, num_envs: int, save_folder: str, loggers: list[str]) -> ExperimentConfig:
    """BenchMARL's default experiment config cut to a small CPU budget: no videos or checkpoints, one
    BenchMARL evaluation (``num_envs`` episodes) after the last batch, ``loggers`` (e.g. ``["csv"]``)."""
    config = ExperimentConfig.get_from_yaml()
    config.sampling_device = config.train_device = config.buffer_device = "cpu"
    config.max_n_frames = frames
    config.on_policy_collected_frames_per_batch = frames_per_batch
    config.on_policy_n_envs_per_worker = num_envs
    config.on_policy_n_minibatch_iters = 4
    config.on_policy_minibatch_size = min(400, frames_per_batch)
    config.lr = 3e-4
    config.evaluation = True
    config.evaluation_interval = frames_per_batch * -(-frames // frames_per_batch)  # after the last batch
    config.evaluation_episodes = num_envs
    config.render = False
    config.loggers = list(loggers)
    config.create_json = False
    config.checkpoint_at_end = False
    config.save_folder = save_folder
    return config


def run(
    algorithm: str = "mappo",
    task: str = "flocking",
    frames: int = 4000,
    frames_per_batch: int = 1000,
    num_envs: int = 10,
    n_robots: int = 6,
    max_steps: int = 50,
    sensing: str = "full",
    flatten: bool = False,
    seed: int = 0,
    torch_threads: int | None = None,
    log_dir: str | None = None,
) -> dict[str, float]:
    """Train ``algorithm`` ("mappo"/"ippo") on ``task`` for ``frames`` copy-steps, then evaluate one episode.

    With ``log_dir``, BenchMARL's csv logger writes there (collection, training, evaluation and the task's
    infos, ``collection/agents/info/<name>`` and ``collection/info/<name>``); otherwise nothing is written.

    Returns ``episode_reward`` (mean over robots and copies of the summed reward), ``mean_reward_per_step``,
    ``train_seconds`` and the task's metrics averaged over the evaluation episode.
    """
    set_torch_threads(torch_threads)
    swarm_task = SwarmTask[task.upper()].get_task(
        config={"max_steps": max_steps, "n_robots": n_robots, "sensing": sensing, "flatten": flatten, "torch_threads": torch.get_num_threads()}
    )
    model = MlpConfig(num_cells=[64, 64], layer_class=torch.nn.Linear, activation_class=torch.nn.Tanh)
    with tempfile.TemporaryDirectory() as scratch:
        folder = scratch if log_dir is None else log_dir
        experiment = Experiment(
            task=swarm_task,
            algorithm_config=ALGORITHMS[algorithm].get_from_yaml(),
            model_config=model,
            critic_model_config=model,
            seed=seed,
            config=experiment_config(frames, frames_per_batch, num_envs, folder, [] if log_dir is None else ["csv"]),
        )
        start = time.perf_counter()
        experiment.run()
        train_seconds = time.perf_counter() - start
        with torch.no_grad():
            rollout = experiment.test_env.rollout(max_steps, policy=experiment.policy, break_when_any_done=False)
        experiment.close()
    reward = rollout["next", GROUP, "reward"]  # [copies, steps, robots, 1]
    out = {
        "episode_reward": reward.sum(dim=1).mean().item(),
        "mean_reward_per_step": reward.mean().item(),
        "train_seconds": train_seconds,
    }
    metrics = rollout["next", "info"].exclude("episode_step")
    out.update({name: metrics[name].mean().item() for name in sorted(metrics.keys())})
    return out


def main(argv: list[str] | None = None) -> dict[str, dict[str, float]]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", default="flocking", choices=[t.name.lower() for t in SwarmTask])
    parser.add_argument("--algorithms", nargs="+", default=["mappo", "ippo"], choices=sorted(ALGORITHMS))
    parser.add_argument("--frames", type=int, default=4000, help="copy-steps of training per algorithm")
    parser.add_argument("--frames-per-batch", type=int, default=1000)
    parser.add_argument("--num-envs", type=int, default=10, help="env copies of the batched env")
    parser.add_argument("--n-robots", type=int, default=6)
    parser.add_argument("--max-steps", type=int, default=50, help="episode length in control steps (0.1 s each)")
    parser.add_argument("--sensing", default="full", choices=["full", "ideal"])
    parser.add_argument("--flatten", action="store_true", help="one flat observation vector instead of the Dict")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--torch-threads", type=int, default=None, help="default: 1 on <= 2 cores, else min(4, cores // 2)")
    parser.add_argument("--log-dir", default=None, help="write BenchMARL's csv logs there")
    args = parser.parse_args(argv)
    results = {}
    for algorithm in args.algorithms:
        results[algorithm] = result = run(
            algorithm, args.task, args.frames, args.frames_per_batch, args.num_envs, args.n_robots, args.max_steps,
            args.sensing, args.flatten, args.seed, args.torch_threads, args.log_dir,
        )
        print(f"{algorithm:5s} {args.task}: " + "  ".join(f"{k} {v:+.4g}" for k, v in result.items()), flush=True)
    return results


if __name__ == "__main__":
    main()
