"""Training configuration: YAML files validated against a schema of defaults, with dotted overrides.

A config names its ``task`` by a registered env id (``swarm_envs/Flocking-v0``, or a task of your own,
``my_lab/Spread-v0``, whose registering module is listed in ``imports``) or by a short name of the suite's
tasks (``flocking``), and has five sections besides ``task``, ``imports``, ``seed`` and ``output_dir`` (see
``configs/*.yaml``):

- ``imports``: modules (``my_lab.tasks``) or Python files (``path/to/tasks.py``) imported before the task
  is looked up, e.g. the module that calls ``swarm_envs.register``;
- ``env``: keyword arguments of the task's env (any common setting, see
  ``swarm_envs.settings.COMMON_SETTINGS``, or the task's own ``SETTINGS``; values are checked by the env's
  own validator, ``swarm_envs.settings.validate_settings``, for the env train.py would build, whatever its
  ``sensing``);
- ``agent``: PPO hyper-parameters (stable-baselines3 names) and the scripted baseline;
- ``train``: budget (``total_timesteps`` counts robot-steps: one per robot per env step), env copies,
  torch threads, checkpoints;
- ``eval``: seeds and episode settings for the final comparison.

Unknown keys, wrong types and bad values raise :class:`ConfigError` naming the dotted key.
"""

from __future__ import annotations

import copy
import numbers
from pathlib import Path
from typing import Any

import yaml

__all__ = ["ConfigError", "DEFAULTS", "load_config", "apply_overrides", "validate", "resolve"]


class ConfigError(ValueError):
    """A bad training configuration (unknown key, wrong type or value)."""


#: schema and defaults; ``None`` under ``env`` means "free-form, validated by the env"
DEFAULTS: dict[str, Any] = {
    "task": "aggregation",
    "imports": [],
    "seed": 0,
    "output_dir": "runs/default",
    "env": {},
    "agent": {
        "scripted": None,  # None = the task's scripted baseline (its Task.SCRIPTED_POLICY; none if it has none)
        "scripted_kwargs": {},
        "learning_rate": 3.0e-4,
        "n_steps": 128,  # rollout length per row (robot); rollout size = n_steps * n_envs * n_robots
        "batch_size": 512,
        "n_epochs": 5,
        "gamma": 0.99,
        "gae_lambda": 0.95,
        "clip_range": 0.2,
        "ent_coef": 0.0,
        "vf_coef": 0.5,
        "max_grad_norm": 0.5,
        "net_arch": [64, 64],
        "activation": "tanh",
        "log_std_init": 0.0,
        "reward_scale": 1.0,  # multiplies env rewards seen by PPO (not the reported metrics)
    },
    "train": {
        "total_timesteps": 100_000,
        "n_envs": 2,  # env copies in the VecEnv
        "n_workers": 1,  # worker processes the copies are split over (one batched core each); <= n_envs
        "torch_threads": 1,  # benchmarks/bench_torch_threads.py: 2 is <=5 % faster idle, 4-8x slower with a busy core
        "checkpoint_freq": 50_000,  # robot-steps between checkpoints (0 = only the final model)
        "progress_bar": True,
    },
    "eval": {
        "n_seeds": 20,
        "seed_start": 10_000,  # evaluation seeds are seed_start .. seed_start + n_seeds - 1
        "deterministic": True,
        "max_cycles": None,  # None = env.max_cycles
    },
}

_CHOICES = {"agent.activation": ("tanh", "relu")}
_POSITIVE_INT = {"agent.n_steps", "agent.batch_size", "agent.n_epochs", "train.total_timesteps", "train.n_envs", "train.n_workers",
                 "train.torch_threads", "eval.n_seeds"}
_NON_NEGATIVE_INT = {"train.checkpoint_freq", "seed", "eval.seed_start"}
_POSITIVE_FLOAT = {"agent.learning_rate", "agent.clip_range", "agent.max_grad_norm", "agent.reward_scale"}
_UNIT_FLOAT = {"agent.gamma", "agent.gae_lambda"}
_NON_NEGATIVE_FLOAT = {"agent.ent_coef", "agent.vf_coef"}


def _type_ok(value: Any, default: Any) -> bool:
    if default is None:
        return True
    if isinstance(default, bool):
        return isinstance(value, bool)
    if isinstance(default, int):
        return isinstance(value, numbers.Integral) and not isinstance(value, bool)
    if isinstance(default, float):
        return isinstance(value, numbers.Real) and not isinstance(value, bool)
    return isinstance(value, type(default))


def _merge(base: dict, update: dict, path: str = "") -> dict:
    out = copy.deepcopy(base)
    for key, value in (update or {}).items():
        dotted = f"{path}{key}"
        if path == "env." or dotted in ("agent.scripted_kwargs",):
            out[key] = value
            continue
        if key not in base:
            raise ConfigError(f"unknown config key {dotted!r}; allowed keys here: {sorted(base)}")
        if isinstance(base[key], dict) and value is None:
            value = {}  # an empty section in YAML (``env:``) means "all defaults"
        if isinstance(base[key], dict) and dotted not in ("agent.scripted_kwargs",):
            if not isinstance(value, dict):
                raise ConfigError(f"config key {dotted!r} must be a mapping, got {value!r}")
            out[key] = _merge(base[key], value, dotted + ".")
        else:
            out[key] = value
    return out


def _env_allowed(task: str) -> dict[str, Any]:
    """Every env setting of ``task`` with its default (the id's registered settings included)."""
    from swarm_envs.agents.tasks import env_id
    from swarm_envs.registry import spec, task_class
    from swarm_envs.settings import COMMON_DEFAULTS

    name = env_id(task)
    return {**COMMON_DEFAULTS, **task_class(name).TASK_DEFAULTS, **spec(name).kwargs}


def validate(cfg: dict[str, Any]) -> dict[str, Any]:
    """Check every key and value; returns ``cfg`` (raises :class:`ConfigError`)."""
    from swarm_envs.agents.scripted import check_scripted_kwargs
    from swarm_envs.agents.tasks import env_id, import_modules

    imports = cfg["imports"]
    if not isinstance(imports, list) or not all(isinstance(m, str) and m for m in imports):
        raise ConfigError(f"config key 'imports' must be a list of module names or .py paths, got {imports!r:.80}")
    try:
        import_modules(imports)
    except ImportError as err:
        raise ConfigError(f"config key 'imports': {err}") from None
    try:
        env_id(cfg["task"])
    except ValueError as err:
        raise ConfigError(f"config key 'task': {err}") from None

    def walk(node: dict, schema: dict, path: str) -> None:
        for key, value in node.items():
            dotted = f"{path}{key}"
            if dotted in ("env", "agent.scripted_kwargs"):
                if not isinstance(value, dict):
                    raise ConfigError(f"config key {dotted!r} must be a mapping, got {value!r}")
                continue
            if key not in schema:
                raise ConfigError(f"unknown config key {dotted!r}; allowed keys here: {sorted(schema)}")
            default = schema[key]
            if isinstance(default, dict):
                walk(value, default, dotted + ".")
                continue
            if not _type_ok(value, default):
                raise ConfigError(f"config key {dotted!r} must be of type {type(default).__name__}, got {value!r}")
            if dotted in _CHOICES and value not in _CHOICES[dotted]:
                raise ConfigError(f"config key {dotted!r}={value!r} not allowed; allowed values: {list(_CHOICES[dotted])}")
            if dotted in _POSITIVE_INT and value < 1:
                raise ConfigError(f"config key {dotted!r} must be an integer >= 1, got {value!r}")
            if dotted in _NON_NEGATIVE_INT and value < 0:
                raise ConfigError(f"config key {dotted!r} must be an integer >= 0, got {value!r}")
            if dotted in _POSITIVE_FLOAT and not value > 0:
                raise ConfigError(f"config key {dotted!r} must be > 0, got {value!r}")
            if dotted in _UNIT_FLOAT and not 0 <= value <= 1:
                raise ConfigError(f"config key {dotted!r} must be in [0, 1], got {value!r}")
            if dotted in _NON_NEGATIVE_FLOAT and value < 0:
                raise ConfigError(f"config key {dotted!r} must be >= 0, got {value!r}")

    walk(cfg, DEFAULTS, "")
    net = cfg["agent"]["net_arch"]
    if not net or not all(isinstance(h, int) and not isinstance(h, bool) and h > 0 for h in net):
        raise ConfigError(f"config key 'agent.net_arch' must be a non-empty list of positive layer sizes, got {net!r}")
    scripted = cfg["agent"]["scripted"]
    if scripted is None:
        from swarm_envs.agents.tasks import scripted_policy

        scripted = scripted_policy(cfg["task"])
    if scripted is not None:
        try:
            check_scripted_kwargs(scripted, cfg["agent"]["scripted_kwargs"])
        except ValueError as err:
            raise ConfigError(f"config key 'agent.scripted' / 'agent.scripted_kwargs': {err}") from None
    elif cfg["agent"]["scripted_kwargs"]:
        raise ConfigError(f"config key 'agent.scripted_kwargs' is set but task {cfg['task']!r} has no scripted baseline")
    mc = cfg["eval"]["max_cycles"]
    if mc is not None and (isinstance(mc, bool) or not isinstance(mc, int) or mc < 1):
        raise ConfigError(f"config key 'eval.max_cycles' must be null or an integer >= 1, got {mc!r}")
    allowed = _env_allowed(cfg["task"])
    unknown = sorted(set(cfg["env"]) - set(allowed) - {"flatten", "render_mode"})
    if unknown:
        raise ConfigError(f"unknown env key(s) {['env.' + k for k in unknown]} for task {cfg['task']!r}; allowed: {sorted(allowed)}")
    if "flatten" in cfg["env"] or "render_mode" in cfg["env"]:
        raise ConfigError("env.flatten and env.render_mode are set by train.py; remove them from the config")
    _check_env_settings(cfg["task"], cfg["env"])
    if cfg["train"]["n_workers"] > cfg["train"]["n_envs"]:
        raise ConfigError(f"train.n_workers ({cfg['train']['n_workers']}) must not exceed train.n_envs ({cfg['train']['n_envs']})")
    if cfg["agent"]["batch_size"] > cfg["agent"]["n_steps"] * cfg["train"]["n_envs"] * _n_agents(cfg):
        raise ConfigError(
            "agent.batch_size must not exceed the rollout size n_steps * n_envs * n_robots "
            f"({cfg['agent']['n_steps']} * {cfg['train']['n_envs']} * {_n_agents(cfg)})"
        )
    return cfg


def _check_env_settings(task: str, env: dict[str, Any]) -> None:
    """Run the env's own validator (:func:`swarm_envs.settings.validate_settings`) on the settings train.py
    would build the env with (YAML lists as tuples, ``flatten=True``), then build that env once (cheap: no
    reset) for the checks that need its arena (robots and anchors fit). Raises :class:`ConfigError`."""
    import swarm_envs
    from swarm_envs.agents.tasks import env_id
    from swarm_envs.settings import SettingsError

    kwargs = {**env, "flatten": True}
    if isinstance(kwargs.get("code"), list):
        kwargs["code"] = tuple(kwargs["code"])
    try:
        swarm_envs.make(env_id(task), **kwargs).close()
    except SettingsError as err:
        raise ConfigError(f"bad env settings: {err} (config key 'env.{err.key}')") from None
    except (ValueError, TypeError) as err:
        raise ConfigError(f"bad env settings: {err}") from None


def _n_agents(cfg: dict[str, Any]) -> int:
    return int(cfg["env"].get("n_robots", _env_allowed(cfg["task"])["n_robots"]))


def _parse_value(text: str) -> Any:
    try:
        return yaml.safe_load(text)
    except yaml.YAMLError:
        return text


def apply_overrides(cfg: dict[str, Any], overrides: list[str]) -> dict[str, Any]:
    """Apply ``key=value`` overrides (dotted keys, YAML-parsed values), e.g. ``train.total_timesteps=2000``."""
    cfg = copy.deepcopy(cfg)
    for item in overrides or []:
        if "=" not in item:
            raise ConfigError(f"--set expects key=value (e.g. train.total_timesteps=2000), got {item!r}")
        key, text = item.split("=", 1)
        parts = key.strip().split(".")
        node, schema = cfg, DEFAULTS
        for i, part in enumerate(parts[:-1]):
            dotted = ".".join(parts[: i + 1])
            if not isinstance(node.get(part), dict):
                raise ConfigError(f"unknown config key {key!r}: {dotted!r} is not a section")
            node = node[part]
            schema = schema.get(part, {}) if isinstance(schema, dict) else {}
        last = parts[-1]
        free = parts[0] == "env" or parts[:2] == ["agent", "scripted_kwargs"]
        if not free and last not in schema:
            raise ConfigError(f"unknown config key {key!r}; allowed keys here: {sorted(schema)}")
        node[last] = _parse_value(text)
    return cfg


def load_config(path: str | Path | None, overrides: list[str] | None = None) -> dict[str, Any]:
    """Read a YAML config (missing keys take :data:`DEFAULTS`), apply overrides and validate."""
    raw: dict[str, Any] = {}
    if path is not None:
        try:
            with open(path) as fh:
                raw = yaml.safe_load(fh) or {}
        except FileNotFoundError:
            raise ConfigError(f"config file {str(path)!r} not found") from None
        except yaml.YAMLError as err:
            raise ConfigError(f"config file {str(path)!r} is not valid YAML: {err}") from None
        if not isinstance(raw, dict):
            raise ConfigError(f"config file {str(path)!r} must hold a mapping at the top level")
    cfg = _merge(DEFAULTS, raw)
    cfg = apply_overrides(cfg, overrides or [])
    return validate(cfg)


def resolve(cfg: dict[str, Any]) -> dict[str, Any]:
    """The config with task defaults filled in (scripted baseline name), for saving beside results."""
    from swarm_envs.agents.tasks import scripted_policy

    out = copy.deepcopy(cfg)
    if out["agent"]["scripted"] is None:
        out["agent"]["scripted"] = scripted_policy(out["task"])
    return out
