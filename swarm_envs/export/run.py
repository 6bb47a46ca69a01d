"""Load a ``train.py`` run folder (``config.yaml`` + ``model.zip``) for export, refusing what cannot be exported."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import yaml

from swarm_envs.sensing.observation import ObservationLayout
from swarm_envs.sim.platforms import Platform

__all__ = ["ExportError", "LoadedRun", "load_run", "SUPPORTED"]

#: the policy variants the C export implements
SUPPORTED = ("algorithm ppo or recurrent_ppo, encoder mlp or deepsets, odometry on or off, any action_repeat and frame_stack; "
             "the fixed-point builds (q15, int8) for algorithm ppo")


class ExportError(ValueError):
    """A run folder that cannot be exported (missing files, another policy variant, a bad model)."""


@dataclass
class LoadedRun:
    """A trained run: its resolved config, env id and settings, policy variant, model and env geometry."""

    run_dir: Path
    cfg: dict[str, Any]
    env_id: str
    env_kwargs: dict[str, Any]
    spec: Any  # swarm_envs.agents.policies.PolicySpec
    model: Any  # stable_baselines3.PPO
    layout: ObservationLayout
    platform: Platform
    obs_size: int
    action_size: int
    max_cycles: int


def load_run(run_dir: str | Path, fixed: str | None = None) -> LoadedRun:
    """The run of ``run_dir``; :class:`ExportError` with one line saying what is missing or unsupported
    (``fixed``: the fixed-point build asked for, ``q15`` or ``int8``, or None for float32)."""
    run_dir = Path(run_dir)
    if not run_dir.is_dir():
        raise ExportError(f"run folder '{run_dir}' not found (give the output folder of train.py, holding config.yaml and model.zip)")
    config, model_path = run_dir / "config.yaml", run_dir / "model.zip"
    missing = [p.name for p in (config, model_path) if not p.is_file()]
    if missing:
        raise ExportError(f"run folder '{run_dir}' has no {' and no '.join(missing)} (train.py writes both into its output folder)")
    from swarm_envs.agents.config import DEFAULTS, ConfigError, merge_settings, validate
    from swarm_envs.agents.policies import PolicySpec
    from swarm_envs.agents.tasks import env_id, import_modules
    from swarm_envs.agents.config import env_kwargs_of
    from swarm_envs.agents.checkpoints import load_checkpoint
    from swarm_envs.agents.staging import TrainError

    try:
        raw = yaml.safe_load(config.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as err:
        raise ExportError(f"'{config}' cannot be read as YAML: {' '.join(str(err).split())[:200]}") from None
    if not isinstance(raw, dict):
        raise ExportError(f"'{config}' does not hold a train.py config (a mapping at the top level)")
    try:
        import_modules(raw.get("imports") or [])
        cfg = validate(merge_settings(DEFAULTS, raw))
    except (ConfigError, ImportError) as err:
        raise ExportError(f"'{config}': {err}") from None
    spec = PolicySpec.from_agent(cfg["agent"])
    if fixed is not None and spec.algorithm != "ppo":
        raise ExportError(f"run '{run_dir}' trained the policy variant {spec.name}: --fixed {fixed} is not available for algorithm "
                          f"{spec.algorithm} (its LSTM is exported in float32 only); the C export supports {SUPPORTED}")
    kwargs = {k: v for k, v in env_kwargs_of(cfg).items() if k != "render_mode"}
    try:
        model = load_checkpoint(model_path, cfg, kwargs)
    except TrainError as err:
        raise ExportError(str(err)) from None
    from swarm_envs.agents.evaluation import make_env

    env = make_env(cfg["task"], **kwargs, flatten=True)
    try:
        layout, platform = env.layout, env.platform
        obs_size = int(env.observation_space(env.possible_agents[0]).shape[0])
        action_size = int(env.action_space(env.possible_agents[0]).shape[0])
        max_cycles = int(env.max_cycles)
    finally:
        env.close()
    return LoadedRun(run_dir, cfg, env_id(cfg["task"]), kwargs, spec, model, layout, platform, obs_size, action_size, max_cycles)
