"""MAPPO with TorchRL on a swarm task: shared decentralised policy, centralised critic on the global state.

    pip install -e ".[torchrl]"
    python examples/torchrl_mappo.py                     # aggregation, 10 copies, ~1-2 min on 2 CPU cores
    python examples/torchrl_mappo.py --frames 200000 --n-robots 10 --num-envs 64
    python examples/torchrl_mappo.py --wrapper pettingzoo   # TorchRL's stock PettingZooWrapper, one env
    python examples/torchrl_mappo.py --import examples/custom_task.py --task swarm_examples/Dispersion-v0

The env is ``swarm_envs.make_torchrl``: ``--num-envs`` copies of the task stepped by one batched core, as
one TorchRL env with ``batch_size=[num_envs]`` (:mod:`swarm_envs.adapters.torchrl_env`), with the default ``Dict``
observation and the global ``state``. ``--wrapper pettingzoo`` uses TorchRL's stock ``PettingZooWrapper``
around the single parallel env (``return_state=True``) instead, with flat ``(group, name)`` info keys
(``swarm_envs.adapters.env.FlatInfos``; the stock wrapper does not read nested info dicts): the same model and loss
work on both.

- **Actor** (decentralised, parameters shared by all robots): each robot's Dict observation (range &
  bearing, messages, scale-free coordinates, rigidity, proprioception: sensing only) is flattened and
  concatenated by :class:`DictEncoder`, then an MLP gives a TanhNormal over (linear, angular) velocity.
- **Critic** (centralised, MAPPO): the global ground-truth ``state`` (every robot's pose and velocity,
  the task markers, progress; see ``SwarmEnv.state``) concatenated with the robot's own encoded
  observation ("agent-specific global state"), so per-robot rewards (``reward_mode="local"``) work too.
  Ground truth reaches the critic only: it is used for training, never for acting.

Each iteration prints the mean reward per step and the task metrics from the infos (batched env:
``("info", name)`` per copy; stock wrapper: ``("robot", "info", "metrics", name)``), e.g. aggregation's
``mean_distance_to_centroid`` (m). Torch uses 1 intra-op thread on machines with at most 2 cores and
``min(4, cores // 2)`` above (``--torch-threads`` or ``OMP_NUM_THREADS`` override it).
"""

from __future__ import annotations

import argparse
import time
import warnings

import torch
from tensordict.nn import TensorDictModule, TensorDictSequential
from tensordict.nn.distributions import NormalParamExtractor
from torch import nn
from torchrl.collectors import Collector
from torchrl.data.replay_buffers import ReplayBuffer
from torchrl.data.replay_buffers.samplers import SamplerWithoutReplacement
from torchrl.data.replay_buffers.storages import LazyTensorStorage
from torchrl.envs import EnvBase
from torchrl.envs.libs.pettingzoo import PettingZooWrapper
from torchrl.modules import MLP, ProbabilisticActor, TanhNormal
from torchrl.objectives import ClipPPOLoss, ValueEstimators

import swarm_envs
from swarm_envs.agents.tasks import import_task
from swarm_envs.adapters.env import FlatInfos
from swarm_envs.adapters.torch_threads import set_torch_threads

GROUP = "robot"  # the stock wrapper groups agents by name prefix (robot_0, robot_1, ... -> "robot"); make_torchrl uses it too


class DictEncoder(nn.Module):
    """Flatten each part of a robot's Dict observation and concatenate them: (..., n_agents, D)."""

    def __init__(self, event_dims: list[int]) -> None:
        super().__init__()
        self.event_dims = event_dims  # number of trailing (per-robot) dims of each part

    def forward(self, *parts: torch.Tensor) -> torch.Tensor:
        return torch.cat([p.flatten(start_dim=p.dim() - d) for p, d in zip(parts, self.event_dims)], dim=-1)


class StateAndOwnObservation(nn.Module):
    """Critic input: the global state, repeated for each agent, next to that agent's own features."""

    def forward(self, state: torch.Tensor, own: torch.Tensor) -> torch.Tensor:
        return torch.cat([state.unsqueeze(-2).expand(*own.shape[:-1], state.shape[-1]), own], dim=-1)


def make_env(task: str, n_robots: int, max_cycles: int, sensing: str, seed: int, num_envs: int = 10, wrapper: str = "batched") -> EnvBase:
    """The batched TorchRL env (``wrapper="batched"``, ``num_envs`` copies) or the stock wrapper around one env."""
    settings = dict(n_robots=n_robots, max_cycles=max_cycles, sensing=sensing)
    if wrapper == "batched":
        return swarm_envs.make_torchrl(task, num_envs, group=GROUP, seed=seed, torch_threads=0, **settings)
    return PettingZooWrapper(FlatInfos(swarm_envs.make(task, **settings)), return_state=True, seed=seed)


def build(env: EnvBase, hidden: int = 64) -> tuple[ProbabilisticActor, TensorDictSequential]:
    """(actor, critic) modules for the env's single agent group."""
    obs_spec = env.observation_spec_unbatched[GROUP, "observation"]
    part_keys = sorted(obs_spec.keys())
    event_dims = [len(obs_spec[k].shape) - 1 for k in part_keys]  # minus the agent dim
    obs_size = sum(int(obs_spec[k].shape[1:].numel()) for k in part_keys)
    state_size = env.observation_spec["state"].shape[-1]
    n_actions = env.full_action_spec[GROUP, "action"].shape[-1]
    in_keys = [(GROUP, "observation", k) for k in part_keys]

    def encoder() -> TensorDictModule:
        return TensorDictModule(DictEncoder(event_dims), in_keys=in_keys, out_keys=[(GROUP, "features")])

    actor_net = TensorDictModule(
        nn.Sequential(MLP(in_features=obs_size, out_features=2 * n_actions, num_cells=[hidden, hidden], activation_class=nn.Tanh), NormalParamExtractor()),
        in_keys=[(GROUP, "features")],
        out_keys=[(GROUP, "loc"), (GROUP, "scale")],
    )
    action_spec = env.full_action_spec_unbatched[GROUP, "action"]
    actor = ProbabilisticActor(
        module=TensorDictSequential(encoder(), actor_net),
        spec=action_spec,
        in_keys=[(GROUP, "loc"), (GROUP, "scale")],
        out_keys=[(GROUP, "action")],
        distribution_class=TanhNormal,
        distribution_kwargs={"low": action_spec.space.low[0], "high": action_spec.space.high[0]},
        return_log_prob=True,
        log_prob_key=(GROUP, "action_log_prob"),
    )
    critic = TensorDictSequential(
        encoder(),
        TensorDictModule(StateAndOwnObservation(), in_keys=["state", (GROUP, "features")], out_keys=[(GROUP, "critic_input")]),
        TensorDictModule(
            MLP(in_features=state_size + obs_size, out_features=1, num_cells=[hidden, hidden], activation_class=nn.Tanh),
            in_keys=[(GROUP, "critic_input")],
            out_keys=[(GROUP, "state_value")],
        ),
    )
    return actor, critic


def main(argv: list[str] | None = None) -> dict[str, float]:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--task", default="swarm_envs/Aggregation-v0", help="a registered env id")
    parser.add_argument("--import", dest="imports", action="append", default=[], metavar="MODULE",
                        help="import a module or .py file first, e.g. one that registers a task of your own (repeatable)")
    parser.add_argument("--n-robots", type=int, default=6)
    parser.add_argument("--max-cycles", type=int, default=100, help="episode length in control steps (0.1 s each)")
    parser.add_argument("--sensing", default="full", choices=["full", "ideal"])
    parser.add_argument("--wrapper", default="batched", choices=["batched", "pettingzoo"])
    parser.add_argument("--num-envs", type=int, default=10, help="env copies of the batched env")
    parser.add_argument("--frames", type=int, default=3000, help="total env steps (each steps every robot of one copy)")
    parser.add_argument("--frames-per-batch", type=int, default=500)
    parser.add_argument("--epochs", type=int, default=4)
    parser.add_argument("--minibatch", type=int, default=100)
    parser.add_argument("--lr", type=float, default=3e-4)
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--torch-threads", type=int, default=None, help="default: 1 on <= 2 cores, else min(4, cores // 2)")
    args = parser.parse_args(argv)
    try:
        import_task(args.imports, args.task)
    except (ImportError, ValueError) as err:
        parser.error(str(err))
    set_torch_threads(args.torch_threads)
    torch.manual_seed(args.seed)

    env = make_env(args.task, args.n_robots, args.max_cycles, args.sensing, args.seed, args.num_envs, args.wrapper)
    actor, critic = build(env)
    collector = Collector(env, actor, frames_per_batch=args.frames_per_batch, total_frames=args.frames)
    buffer = ReplayBuffer(
        storage=LazyTensorStorage(args.frames_per_batch), sampler=SamplerWithoutReplacement(), batch_size=args.minibatch
    )
    # advantages are standardised over time *and* robots on purpose: the robots are interchangeable and
    # share one policy (TorchRL warns because per-agent normalisation is its usual multi-agent advice)
    warnings.filterwarnings("ignore", message="You requested advantage normalization")
    loss = ClipPPOLoss(actor, critic, clip_epsilon=0.2, entropy_coeff=1e-3, normalize_advantage=True)
    loss.set_keys(
        reward=(GROUP, "reward"),
        action=(GROUP, "action"),
        done=(GROUP, "done"),
        terminated=(GROUP, "terminated"),
        value=(GROUP, "state_value"),
        sample_log_prob=(GROUP, "action_log_prob"),
    )
    loss.make_value_estimator(ValueEstimators.GAE, gamma=0.99, lmbda=0.95)
    optim = torch.optim.Adam(loss.parameters(), args.lr)

    start, steps, log = time.perf_counter(), 0, {}
    for i, batch in enumerate(collector):
        with torch.no_grad():
            loss.value_estimator(batch, params=loss.critic_network_params, target_params=loss.target_critic_network_params)
        buffer.extend(batch.reshape(-1))
        for _ in range(args.epochs):
            for _ in range(args.frames_per_batch // args.minibatch):
                out = loss(buffer.sample())
                total = out["loss_objective"] + out["loss_critic"] + out["loss_entropy"]
                total.backward()
                nn.utils.clip_grad_norm_(loss.parameters(), 1.0)
                optim.step()
                optim.zero_grad()
        collector.update_policy_weights_()
        steps += batch.numel()
        metrics = batch["next", GROUP, "info", "metrics"] if args.wrapper == "pettingzoo" else batch["next", "info"].exclude("episode_step")
        log = {"reward_per_step": batch["next", GROUP, "reward"].mean().item()}
        log.update({name: metrics[name].mean().item() for name in sorted(metrics.keys())})
        print(f"iter {i:3d}  env steps {steps:6d}  " + "  ".join(f"{k} {v:+.4g}" for k, v in log.items()), flush=True)
    elapsed = time.perf_counter() - start
    print(f"{steps} env steps x {args.n_robots} robots in {elapsed:.0f} s ({steps * args.n_robots / elapsed:.0f} agent-steps/s incl. training)")
    collector.shutdown()
    return log


if __name__ == "__main__":
    main()
