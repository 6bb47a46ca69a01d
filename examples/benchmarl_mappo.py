"""MAPPO and IPPO from BenchMARL on a swarm task, through the suite's BenchMARL task family.

    pip install -e ".[benchmarl]"
    python examples/benchmarl_mappo.py                                  # flocking, MAPPO then IPPO, MLP, tiny budget
    python examples/benchmarl_mappo.py --task aggregation --frames 200000 --algorithms mappo
    python examples/benchmarl_mappo.py --model gnn+gru --task flocking   # any chain of mlp, gru, deepsets, gnn
    python examples/benchmarl_mappo.py --config configs/benchmarl/gru.yaml --task sorted_following
    python examples/benchmarl_mappo.py --import examples/custom_task.py --task swarm_examples/Dispersion-v0

The task is :class:`swarm_envs.adapters.benchmarl_tasks.SwarmTask` (e.g. ``SwarmTask.FLOCKING``): BenchMARL builds
one batched TorchRL env of ``--num-envs`` copies per collector (``swarm_envs.make_torchrl``), with the
default ``Dict`` observation (each part flattened to a vector by the task family's transform) and the
global ground-truth ``state`` for MAPPO's centralised critic. IPPO's critic sees each robot's own
observation only. Frames are copy-steps (each steps every robot of a copy).

``--model`` picks the policy, one of BenchMARL's models or a ``+`` chain of them (BenchMARL's
``SequenceModelConfig``, ``--hidden`` features between the layers), e.g. ``gnn+gru``:

- ``mlp``: two hidden layers of ``--hidden`` units over the concatenated observation parts;
- ``gru``: a GRU of ``--hidden`` units (the hidden state carried over the episode, reset at its start),
  then an MLP head;
- ``deepsets``: a DeepSets over each robot's own range-and-bearing rows: phi (an MLP) on every row of
  ``range_bearing`` (with ``range_bearing_ids``, which describes the same rows, where the task observes
  ids), summed over the rows, then rho (an MLP) on that sum and the other observation parts. For it
  those two parts stay ``(K, F)`` per robot (:class:`NeighbourSetTask`) instead of being flattened; it
  has to be the first layer of a chain;
- ``gnn``: one graph-convolution layer (``torch_geometric``'s ``GraphConv``, mean aggregation) over the
  robots of a copy on BenchMARL's ``full`` topology: each robot's output mixes its own features with the
  mean of every other robot's. It reads no positions (BenchMARL's ``from_pos`` topology would need
  absolute positions, which only the ground truth has), so the graph connects all robots of a copy:
  the policy is not decentralised (every robot reads every robot's observation). Needs
  ``pip install torch_geometric``.

The critic is an MLP (MAPPO: on the ``state``; IPPO: on the robot's own observation), except IPPO's
with a ``deepsets`` policy, which is the same DeepSets (its input has the neighbour rows).

``--config FILE`` reads the arguments from a yaml file (keys as the options, with ``_``:
``configs/benchmarl/``); options given on the command line override it. ``n_robots: null`` or
``max_steps: null`` keeps the task's own (``TASK_DEFAULTS`` and the env's defaults).

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
from pathlib import Path
from typing import Any

import torch
import yaml
from benchmarl.algorithms import IppoConfig, MappoConfig
from benchmarl.experiment import Experiment, ExperimentConfig
from benchmarl.models import DeepsetsConfig, GnnConfig, GruConfig, MlpConfig, ModelConfig, SequenceModelConfig
from torchrl.envs import EnvBase, Transform

import swarm_envs
from swarm_envs.agents.tasks import import_modules
from swarm_envs.adapters.benchmarl_tasks import GROUP, SwarmTask, SwarmTaskClass
from swarm_envs.adapters.torch_threads import set_torch_threads

ALGORITHMS = {"mappo": MappoConfig, "ippo": IppoConfig}
#: the model layers ``--model`` chains with ``+``
LAYERS = ("mlp", "gru", "deepsets", "gnn")


class NeighbourSetTask(SwarmTaskClass):
    """The task with each robot's ``range_bearing`` rows (and ``range_bearing_ids``, one row per
    ``range_bearing`` row, where the task observes ids) kept as ``(K, F)``: the set BenchMARL's DeepSets
    pools over. The other parts are flattened as by :class:`SwarmTaskClass`."""

    SET_PARTS = ("range_bearing", "range_bearing_ids")

    def get_env_transforms(self, env: EnvBase) -> list[Transform]:
        if self.config.get("flatten", False):
            raise ValueError("deepsets reads the range_bearing rows of the Dict observation: not with flatten=True")
        return [t for t in super().get_env_transforms(env) if t.in_keys[0][-1] not in self.SET_PARTS]


def layer_config(name: str, hidden: int = 64) -> ModelConfig:
    """BenchMARL's config of one ``LAYERS`` model (module docstring), ``hidden`` units wide."""
    tanh, linear = torch.nn.Tanh, torch.nn.Linear
    if name == "mlp":
        return MlpConfig(num_cells=[hidden, hidden], layer_class=linear, activation_class=tanh)
    if name == "gru":
        return GruConfig(
            hidden_size=hidden, n_layers=1, bias=True, dropout=0.0, compile=False,
            mlp_num_cells=[hidden], mlp_layer_class=linear, mlp_activation_class=tanh,
        )
    if name == "deepsets":
        return DeepsetsConfig(
            aggr="sum", out_features_local_nn=hidden, local_nn_num_cells=[hidden], local_nn_activation_class=tanh,
            global_nn_num_cells=[hidden, hidden], global_nn_activation_class=tanh,
        )
    if name == "gnn":
        try:
            from torch_geometric.nn.conv import GraphConv
        except ImportError as error:
            raise ImportError("the gnn model needs torch_geometric: pip install torch_geometric") from error
        return GnnConfig(topology="full", self_loops=False, gnn_class=GraphConv, gnn_kwargs={"aggr": "mean"})
    raise ValueError(f"unknown model layer {name!r}: one of {', '.join(LAYERS)}")


def model_config(model: str, hidden: int = 64) -> ModelConfig:
    """The policy model ``model``: a ``LAYERS`` name or a ``+`` chain of them (``SequenceModelConfig`` with
    ``hidden`` features between the layers)."""
    names = model.split("+")
    if "deepsets" in names[1:]:
        raise ValueError(f"model {model!r}: deepsets reads the observation's neighbour rows, so it has to come first")
    layers = [layer_config(name, hidden) for name in names]
    if len(layers) == 1:
        return layers[0]
    return SequenceModelConfig(model_configs=layers, intermediate_sizes=[hidden] * (len(layers) - 1))


def critic_config(algorithm: str, model: str, hidden: int = 64) -> ModelConfig:
    """The critic (module docstring): an MLP, or IPPO's DeepSets when the policy's observation has sets."""
    if algorithm == "ippo" and uses_neighbour_sets(model):
        return layer_config("deepsets", hidden)
    return layer_config("mlp", hidden)


def uses_neighbour_sets(model: str) -> bool:
    return model.split("+")[0] == "deepsets"


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


def make_task(task: str, model: str = "mlp", **settings: Any) -> SwarmTaskClass:
    """The task ``task`` (a ``SwarmTask`` name, any case, or a registered env id such as a task of your own,
    which runs under a member with ``env_id`` in its config) with ``settings`` (``None`` values: the
    task's defaults); a :class:`NeighbourSetTask` for a ``deepsets`` policy."""
    config = {k: v for k, v in settings.items() if v is not None}
    if task.upper() in SwarmTask.__members__:
        member = SwarmTask[task.upper()]
    else:
        member, config["env_id"] = SwarmTask.AGGREGATION, task
    swarm_task = member.get_task(config=config)
    if uses_neighbour_sets(model):
        return NeighbourSetTask(name=swarm_task.name, config=swarm_task.config)
    return swarm_task


def run(
    algorithm: str = "mappo",
    task: str = "flocking",
    frames: int = 4000,
    frames_per_batch: int = 1000,
    num_envs: int = 10,
    n_robots: int | None = 6,
    max_steps: int | None = 50,
    sensing: str = "full",
    flatten: bool = False,
    seed: int = 0,
    torch_threads: int | None = None,
    log_dir: str | None = None,
    model: str = "mlp",
    hidden: int = 64,
) -> dict[str, float]:
    """Train ``algorithm`` ("mappo"/"ippo") with the policy ``model`` (module docstring) on ``task`` for
    ``frames`` copy-steps, then evaluate one episode. ``n_robots``/``max_steps`` None: the task's own.

    With ``log_dir``, BenchMARL's csv logger writes there (collection, training, evaluation and the task's
    infos, ``collection/agents/info/<name>`` and ``collection/info/<name>``); otherwise nothing is written.

    Returns ``episode_reward`` (mean over robots and copies of the summed reward), ``mean_reward_per_step``,
    ``train_seconds`` and the task's metrics averaged over the evaluation episode.
    """
    set_torch_threads(torch_threads)
    swarm_task = make_task(
        task, model, max_steps=max_steps, n_robots=n_robots, sensing=sensing, flatten=flatten,
        torch_threads=torch.get_num_threads(),
    )
    episode = swarm_task.max_steps(None)
    with tempfile.TemporaryDirectory() as scratch:
        folder = scratch if log_dir is None else log_dir
        Path(folder).mkdir(parents=True, exist_ok=True)  # BenchMARL makes only the run's own folder inside it
        experiment = Experiment(
            task=swarm_task,
            algorithm_config=ALGORITHMS[algorithm].get_from_yaml(),
            model_config=model_config(model, hidden),
            critic_model_config=critic_config(algorithm, model, hidden),
            seed=seed,
            config=experiment_config(frames, frames_per_batch, num_envs, folder, [] if log_dir is None else ["csv"]),
        )
        start = time.perf_counter()
        experiment.run()
        train_seconds = time.perf_counter() - start
        with torch.no_grad():
            rollout = experiment.test_env.rollout(episode, policy=experiment.policy, break_when_any_done=False)
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


def load_config(path: str) -> dict[str, Any]:
    """The options of a yaml config file (``configs/benchmarl/``): a mapping of option names (``_``)."""
    with open(path) as f:
        config = yaml.safe_load(f) or {}
    if not isinstance(config, dict):
        raise ValueError(f"{path}: expected a mapping of options, got {type(config).__name__}")
    return config


def parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--config", default=None, help="yaml file of these options (configs/benchmarl/); the command line overrides it")
    p.add_argument("--task", default="flocking", help=f"one of {[t.name.lower() for t in SwarmTask]} or a registered env id")
    p.add_argument("--import", dest="imports", action="append", default=[], metavar="MODULE",
                   help="import a module or .py file first, e.g. one that registers a task of your own (repeatable)")
    p.add_argument("--algorithms", nargs="+", default=["mappo", "ippo"], choices=sorted(ALGORITHMS))
    p.add_argument("--model", default="mlp", help=f"policy model: one of {', '.join(LAYERS)} or a '+' chain, e.g. gnn+gru")
    p.add_argument("--hidden", type=int, default=64, help="units of the models' layers and between chained layers")
    p.add_argument("--frames", type=int, default=4000, help="copy-steps of training per algorithm")
    p.add_argument("--frames-per-batch", type=int, default=1000)
    p.add_argument("--num-envs", type=int, default=10, help="env copies of the batched env")
    p.add_argument("--n-robots", type=int, default=6)
    p.add_argument("--max-steps", type=int, default=50, help="episode length in control steps (0.1 s each)")
    p.add_argument("--sensing", default="full", choices=["full", "ideal"])
    p.add_argument("--flatten", action="store_true", help="one flat observation vector instead of the Dict")
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--torch-threads", type=int, default=None, help="default: 1 on <= 2 cores, else min(4, cores // 2)")
    p.add_argument("--log-dir", default=None, help="write BenchMARL's csv logs there")
    return p


def parse_args(argv: list[str] | None = None) -> argparse.Namespace:
    """The options: the ``--config`` file's, overridden by those on the command line."""
    p = parser()
    args = p.parse_args(argv)
    if args.config is not None:
        config = load_config(args.config)
        options = {a.dest: a for a in p._actions if a.dest not in ("help", "config")}
        unknown = sorted(set(config) - set(options))
        if unknown:
            p.error(f"{args.config}: unknown options {unknown}; known: {sorted(options)}")
        p.set_defaults(**config)
        args = p.parse_args(argv)
        for name, value in vars(args).items():  # the file's values pass the same checks as the command line's
            choices = options[name].choices if name in options else None
            values = value if isinstance(value, list) else [value]
            if choices is not None and any(v not in choices for v in values):
                p.error(f"{args.config}: {name} {value!r} is not one of {list(choices)}")
    if isinstance(args.algorithms, str):
        args.algorithms = [args.algorithms]
    try:
        import_modules([args.imports] if isinstance(args.imports, str) else args.imports)
    except ImportError as err:
        p.error(str(err))
    names = [t.name.lower() for t in SwarmTask]
    if args.task.lower() not in names and args.task not in swarm_envs.list_envs():
        p.error(f"--task {args.task!r} is neither one of {names} nor a registered env id (--import registers yours)")
    for name in args.model.split("+"):
        if name not in LAYERS:
            p.error(f"--model {args.model!r}: {name!r} is not one of {', '.join(LAYERS)}")
    return args


def main(argv: list[str] | None = None) -> dict[str, dict[str, float]]:
    args = parse_args(argv)
    results = {}
    for algorithm in args.algorithms:
        results[algorithm] = result = run(
            algorithm, args.task, args.frames, args.frames_per_batch, args.num_envs, args.n_robots, args.max_steps,
            args.sensing, args.flatten, args.seed, args.torch_threads, args.log_dir, args.model, args.hidden,
        )
        print(f"{algorithm:5s} {args.model} {args.task}: " + "  ".join(f"{k} {v:+.4g}" for k, v in result.items()), flush=True)
    return results


if __name__ == "__main__":
    main()
