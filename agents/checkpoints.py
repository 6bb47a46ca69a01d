"""Trained runs read back: finding a run's model, loading it for the run's env, and checking that an evaluation's
env matches the one the model was trained on (observation and action spaces)."""

from __future__ import annotations
import zipfile
from pathlib import Path
from typing import Any
import yaml
from swarm_envs.agents.config import DEFAULTS
from swarm_envs.agents.tasks import env_id
from swarm_envs.agents.evaluation import make_env
from swarm_envs.agents.staging import TrainError

from swarm_envs.agents.config import env_kwargs_of

__all__ = ["resolve_checkpoint", "load_checkpoint", "check_run_config"]


def resolve_checkpoint(path: str) -> Path:
    """The checkpoint file (SB3 accepts the name without ``.zip``); :class:`TrainError` if missing."""
    p = Path(path)
    try:
        if not p.exists() and p.suffix != ".zip" and p.with_name(p.name + ".zip").is_file():
            p = p.with_name(p.name + ".zip")
        if not p.exists():
            raise TrainError(f"checkpoint '{path}' not found")
        if p.is_dir():
            raise TrainError(f"checkpoint '{p}' is a directory, not a model .zip")
        if not p.is_file():
            raise TrainError(f"checkpoint '{p}' is not a regular file (a device or a pipe), not a model .zip")
    except OSError as err:  # e.g. a name too long for the file system
        raise TrainError(f"checkpoint '{path}' cannot be read: {err.strerror or err}") from None
    return p


def load_checkpoint(path: Path, cfg: dict[str, Any], env_kwargs: dict[str, Any]):
    """Load a PPO ``.zip`` and check it fits the config's env; :class:`TrainError` with one line otherwise."""
    from swarm_envs.agents.policies import PolicySpec, algorithm_class

    spec = PolicySpec.from_agent(cfg["agent"])
    if not zipfile.is_zipfile(path):
        raise TrainError(f"checkpoint '{path}' is not a zip archive (truncated, or not a stable-baselines3 model)")
    try:
        model = algorithm_class(spec).load(path, device="cpu")
    except Exception as err:  # SB3 raises many kinds (KeyError, BadZipFile, ValueError, pickle errors)
        detail = str(err).strip().splitlines()[0] if str(err).strip() else ""
        raise TrainError(f"checkpoint '{path}' cannot be loaded as a {'RecurrentPPO' if spec.algorithm == 'recurrent_ppo' else 'PPO'} model ({type(err).__name__}{': ' + detail if detail else ''})") from None
    env = make_env(cfg["task"], **{**env_kwargs, "flatten": True})
    agent = env.possible_agents[0]
    obs_shape, act_shape = env.observation_space(agent).shape, env.action_space(agent).shape
    obs_shape = (obs_shape[0] * spec.frame_stack,)
    env.close()
    settings = ", ".join(f"{k}={v}" for k, v in env_kwargs.items())
    if model.observation_space.shape != obs_shape:
        raise TrainError(f"checkpoint '{path}' expects observations of size {_size(model.observation_space.shape)} but the "
                         f"config's {cfg['task']} env ({settings or 'defaults'}) gives {_size(obs_shape)}; "
                         "evaluate it with the config it was trained with (its config.yaml)")
    if model.action_space.shape != act_shape:
        raise TrainError(f"checkpoint '{path}' gives actions of size {_size(model.action_space.shape)} but the "
                         f"config's {cfg['task']} env expects {_size(act_shape)}")
    return model


def check_run_config(checkpoint: Path, cfg: dict[str, Any], env_kwargs: dict[str, Any], config: str) -> None:
    """:class:`TrainError` (one line naming both) if the run that saved ``checkpoint`` (its ``config.yaml``:
    :func:`swarm_envs.agents.config.run_config_path`) trained another task, on another platform, with other
    observation or action spaces or another policy variant than the config ``config`` (resolved: ``cfg``,
    env settings ``env_kwargs``) evaluates. A model without a run config (or with one train.py did not
    write) is checked by :func:`load_checkpoint`'s observation and action sizes only."""
    from swarm_envs.agents.config import run_config_path
    from swarm_envs.agents.policies import PolicySpec
    from swarm_envs.agents.tasks import SHORT_NAMES

    path = run_config_path(checkpoint)
    if path is None:
        return
    try:
        run = yaml.safe_load(path.read_text())
    except (OSError, UnicodeDecodeError, yaml.YAMLError):
        return
    if not isinstance(run, dict) or not isinstance(run.get("task"), str) or not isinstance(run.get("env") or {}, dict):
        return
    trained = f"checkpoint '{checkpoint}' was trained"
    hint = f"evaluate it with its run's config ({path})"
    run_id, ours = SHORT_NAMES.get(run["task"], run["task"]), env_id(cfg["task"])
    if run_id != ours:
        raise TrainError(f"{trained} on {run_id} (its run config {path}) but {config} evaluates {ours}; {hint}")
    try:
        run_kwargs = {k: v for k, v in env_kwargs_of({"env": run.get("env") or {}}).items() if k != "render_mode"}
        run_env = make_env(run_id, **run_kwargs, flatten=True)
    except Exception:  # settings this version does not take: the sizes were checked
        return
    env = make_env(ours, **{**env_kwargs, "flatten": True})
    try:
        if run_env.platform.name != env.platform.name:
            raise TrainError(f"{trained} on the {run_env.platform.name} platform (its run config {path}) but {config} "
                             f"uses the {env.platform.name}; {hint}")
        spaces = [(e.layout.dict_space(), e.action_space(e.possible_agents[0])) for e in (run_env, env)]
        if spaces[0] != spaces[1]:
            raise TrainError(f"{trained} with {_spaces_text(*spaces[0])} (its run config {path}) but {config} gives "
                             f"{_spaces_text(*spaces[1])}; {hint}")
    finally:
        run_env.close()
        env.close()
    agent = run.get("agent") if isinstance(run.get("agent"), dict) else {}
    try:
        run_spec = PolicySpec.from_agent({**DEFAULTS["agent"], **agent})
    except TypeError:
        return
    spec = PolicySpec.from_agent(cfg["agent"])
    differ = [k for k in spec.__dataclass_fields__ if getattr(run_spec, k) != getattr(spec, k)]
    if differ:
        raise TrainError(f"{trained} as the policy variant {run_spec.name}, {_fields(run_spec, differ)} (its run config "
                         f"{path}) but {config} evaluates {spec.name}, {_fields(spec, differ)}; {hint}")


def _spaces_text(observations: Any, actions: Any) -> str:
    """``observations range_bearing 8x7, proprio 10; actions 2`` (each part's shape)."""
    parts = ", ".join(f"{name} {_size(space.shape)}" for name, space in observations.spaces.items())
    return f"observations {parts}; actions {_size(actions.shape)}"


def _fields(spec: Any, names: list[str]) -> str:
    """``agent.frame_stack=4, agent.odometry=True``: the named fields of a policy variant."""
    return ", ".join(f"agent.{k}={getattr(spec, k)}" for k in names)


def _size(shape: tuple[int, ...] | None) -> str:
    return "x".join(str(s) for s in shape) if shape else "?"
