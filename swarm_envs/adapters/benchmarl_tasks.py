"""BenchMARL: the suite's tasks as a BenchMARL task family over the batched TorchRL env.

:class:`SwarmTask` is a BenchMARL ``Task`` enum of the suite's tasks (``AGGREGATION``, ``FLOCKING``,
``CENTROID_SEEKING``, ``SORTED_FOLLOWING``, ``PARITY_CLUSTERING``, ``MID_ANGLE_NAVIGATION``);
``SwarmTask.FLOCKING.get_task()`` gives a :class:`SwarmTaskClass` with that task's defaults
(:data:`TASK_DEFAULTS`), and ``get_task(config={...})`` with any settings (every key besides
``max_steps`` and ``env_id`` is a setting of the env, e.g. ``n_robots``, ``sensing``, ``flatten``). A task
of your own that is registered (``swarm_envs.register``) runs under any member with ``config={"env_id":
"my_lab/MyTask-v0", ...}``. BenchMARL then builds
the env with :meth:`SwarmTaskClass.get_env_fun`: ``swarm_envs.make_torchrl(env_id, num_envs, ...)``, one
batched env of ``num_envs`` copies (BenchMARL sees ``batch_size=[num_envs]`` and does not wrap it in
``SerialEnv``/``ParallelEnv``).

- group ``"agents"`` (every robot), continuous actions in [-1, 1];
- observation spec: the group's ``observation``. With the default ``Dict`` observation every part
  reaches the models as its own key; BenchMARL's MLP concatenates the keys of a group but takes one
  feature dimension per key, so the family flattens each part with more than one feature dimension
  (``range_bearing`` (K, 7), ``messages`` (M, 2 + b), ``scale_free`` (K, 3)) to a vector with TorchRL's
  ``FlattenObservation`` transform. ``flatten=True`` instead makes the env concatenate all parts;
- state spec: the global ground-truth ``state`` (MAPPO's and MASAC's centralised critics use it);
- info: the group's per-agent infos and the root per-copy metrics (``("info", name)``), flat, as
  BenchMARL's logger reads them (``collection/agents/info/<name>``, ``collection/info/<name>``);
- ``max_steps``: the episode length ``max_cycles`` (control steps of 0.1 s).

Example::

    from benchmarl.algorithms import MappoConfig
    from benchmarl.experiment import Experiment, ExperimentConfig
    from benchmarl.models.mlp import MlpConfig
    from swarm_envs.adapters.benchmarl_tasks import SwarmTask

    task = SwarmTask.FLOCKING.get_task(config={"n_robots": 10, "max_steps": 100, "sensing": "full"})
    Experiment(task=task, algorithm_config=MappoConfig.get_from_yaml(), model_config=MlpConfig.get_from_yaml(),
               critic_model_config=MlpConfig.get_from_yaml(), seed=0, config=ExperimentConfig.get_from_yaml()).run()

See ``examples/benchmarl_mappo.py``. Needs ``pip install -e ".[benchmarl]"``.
"""

from __future__ import annotations

import copy
from collections.abc import Callable
from typing import Any

from benchmarl.environments.common import Task, TaskClass
from torchrl.data import Composite
from torchrl.envs import EnvBase, FlattenObservation, Transform

from swarm_envs.adapters.torchrl_env import SwarmTorchRLEnv

__all__ = ["SwarmTask", "SwarmTaskClass", "TASK_DEFAULTS", "TASK_IDS", "GROUP"]

#: the agent group of every task
GROUP = "agents"
#: task name (the enum member) -> registered env id
TASK_IDS = {
    "AGGREGATION": "swarm_envs/Aggregation-v0",
    "FLOCKING": "swarm_envs/Flocking-v0",
    "CENTROID_SEEKING": "swarm_envs/CentroidSeeking-v0",
    "SORTED_FOLLOWING": "swarm_envs/SortedFollowing-v0",
    "PARITY_CLUSTERING": "swarm_envs/ParityClustering-v0",
    "MID_ANGLE_NAVIGATION": "swarm_envs/MidAngleNavigation-v0",
}
#: per-task default config: ``max_steps`` (the episode length, ``max_cycles``) and env settings
TASK_DEFAULTS: dict[str, dict[str, Any]] = {
    "AGGREGATION": {"max_steps": 100, "n_robots": 10, "sensing": "full", "flatten": False},
    "FLOCKING": {"max_steps": 100, "n_robots": 10, "sensing": "full", "flatten": False},
    "CENTROID_SEEKING": {"max_steps": 100, "n_robots": 10, "sensing": "full", "flatten": False},
    # the r-one behaviours with their own robot counts and platform; the seeker needs ~50 s to cross
    "SORTED_FOLLOWING": {"max_steps": 100, "sensing": "full", "flatten": False},
    "PARITY_CLUSTERING": {"max_steps": 100, "sensing": "full", "flatten": False},
    "MID_ANGLE_NAVIGATION": {"max_steps": 600, "sensing": "full", "flatten": False},
}


class SwarmTaskClass(TaskClass):
    """One swarm task with its config (module docstring); made by :meth:`SwarmTask.get_task`."""

    def _env_settings(self) -> dict[str, Any]:
        settings = copy.deepcopy(dict(self.config))
        settings.pop("env_id", None)
        if "max_cycles" in settings:
            raise ValueError("task config: give the episode length as max_steps (BenchMARL's name), not max_cycles")
        settings["max_cycles"] = settings.pop("max_steps", TASK_DEFAULTS[self.name]["max_steps"])
        return settings

    def get_env_fun(self, num_envs: int, continuous_actions: bool, seed: int | None, device: Any) -> Callable[[], EnvBase]:
        """A constructor of the batched env: ``num_envs`` copies, seeded with ``seed`` (copy b: ``seed + b``)."""
        if not continuous_actions:
            raise ValueError("the swarm tasks have continuous actions only (continuous_actions=False was asked)")
        env_id, settings = self.env_id, self._env_settings()
        return lambda: SwarmTorchRLEnv(env_id, num_envs, device=device, group=GROUP, seed=seed, **settings)

    @property
    def env_id(self) -> str:
        """The registered env id this task makes: the config's ``env_id`` (a task of your own), else the
        member's (:data:`TASK_IDS`)."""
        return str(self.config.get("env_id", TASK_IDS[self.name]))

    def supports_continuous_actions(self) -> bool:
        return True

    def supports_discrete_actions(self) -> bool:
        return False

    def has_render(self, env: EnvBase) -> bool:
        return False  # the batched env does not render; the single env (swarm_envs.make) does

    def max_steps(self, env: EnvBase) -> int:
        return int(self._env_settings()["max_cycles"])

    def group_map(self, env: EnvBase) -> dict[str, list[str]]:
        return dict(_base(env).group_map)

    def observation_spec(self, env: EnvBase) -> Composite:
        spec = env.full_observation_spec_unbatched.clone()
        for key in ((GROUP, "info"), "info", "state"):
            del spec[key]
        return spec

    def info_spec(self, env: EnvBase) -> Composite | None:
        spec = env.full_observation_spec_unbatched.clone()
        del spec[GROUP, "observation"]
        del spec["state"]
        return spec

    def state_spec(self, env: EnvBase) -> Composite | None:
        return Composite({"state": env.full_observation_spec_unbatched["state"].clone()})

    def action_spec(self, env: EnvBase) -> Composite:
        return env.full_action_spec_unbatched

    def action_mask_spec(self, env: EnvBase) -> Composite | None:
        return None

    def get_env_transforms(self, env: EnvBase) -> list[Transform]:
        """Each Dict observation part with more than one feature dimension flattened to a vector."""
        spec = env.full_observation_spec_unbatched[GROUP, "observation"]
        if not isinstance(spec, Composite):
            return []
        # a part of shape (N, a, b): its last two dimensions become one
        return [
            FlattenObservation(first_dim=1 - len(part.shape), last_dim=-1, in_keys=[(GROUP, "observation", key)])
            for key, part in spec.items()
            if len(part.shape) > 2
        ]

    @staticmethod
    def env_name() -> str:
        return "swarm_envs"


def _base(env: EnvBase) -> SwarmTorchRLEnv:
    """The :class:`SwarmTorchRLEnv` under BenchMARL's transforms."""
    while not isinstance(env, SwarmTorchRLEnv):
        env = env.base_env
    return env


class SwarmTask(Task):
    """The suite's tasks as a BenchMARL task enum (module docstring)."""

    AGGREGATION = None
    FLOCKING = None
    CENTROID_SEEKING = None
    SORTED_FOLLOWING = None
    PARITY_CLUSTERING = None
    MID_ANGLE_NAVIGATION = None

    @staticmethod
    def associated_class() -> type[SwarmTaskClass]:
        return SwarmTaskClass

    def get_from_yaml(self, path: str | None = None) -> SwarmTaskClass:
        """The task with its config from the yaml file ``path`` (keys as in :data:`TASK_DEFAULTS`, missing keys
        from there); without ``path``, the defaults (the suite ships no files in BenchMARL's config folder)."""
        config = dict(TASK_DEFAULTS[self.name])
        if path is not None:
            from benchmarl.utils import _read_yaml_config

            config.update(_read_yaml_config(path))
        return self.get_task(config=config)
