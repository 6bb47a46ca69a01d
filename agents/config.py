"""Training configuration: YAML files validated against a schema of defaults, with dotted overrides.

A config names its ``task`` by a registered env id (``swarm_envs/Flocking-v0``, or a task of your own,
``my_lab/Spread-v0``, whose registering module is listed in ``imports``) or by a short name of the suite's
tasks (``flocking``), and has five sections besides ``task``, ``imports``, ``seed`` and ``output_dir`` (see
``configs/*.yaml``):

- ``imports``: modules (``my_lab.tasks``) or Python files (``path/to/tasks.py``) imported before the task
  is looked up, e.g. the module that calls ``swarm_envs.register``;
- ``env``: keyword arguments of the task's env (any common setting, see
  ``swarm_envs.tasks.settings.COMMON_SETTINGS``, or the task's own ``SETTINGS``; values are checked by the env's
  own validator, ``swarm_envs.tasks.settings.validate_settings``, for the env train.py would build, whatever its
  ``sensing``);
- ``agent``: PPO hyper-parameters (stable-baselines3 names), the policy variant (``algorithm``, ``encoder``,
  ``odometry``, ``action_repeat``, ``frame_stack``: :mod:`swarm_envs.agents.policies`) and the scripted baseline;
- ``train``: budget (``total_timesteps`` counts robot-steps: one per robot per env step), env copies,
  torch threads, checkpoints;
- ``eval``: seeds and episode settings for the final comparison.

Unknown keys, wrong types and bad values raise :class:`ConfigError` naming the dotted key: every number is
finite and within bounds whose reasons :data:`BOUNDS` states (e.g. ``seed`` < 2**32, the seeds numpy and
SB3 take), every section is a mapping with string keys, and the env settings pass the env's own validator
and build. Nothing is written while checking, and a run only starts once the whole config has passed.
"""

from __future__ import annotations

import copy
import math
import numbers
import sys
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from swarm_envs._text import shown

__all__ = ["ConfigError", "DEFAULTS", "BOUNDS", "load_config", "apply_overrides", "validate", "resolve", "bounds_table", "run_config_path", "progress_bar_on", "merge_settings", "env_kwargs_of"]


class ConfigError(ValueError):
    """A bad training configuration (unknown key, wrong type or value)."""


class _DuplicateKey(yaml.YAMLError):
    """A mapping of a YAML document names a key twice (``key``; ``line`` of the repeat, ``first`` of the first, 1-based)."""

    def __init__(self, key: Any, line: int, first: int) -> None:
        super().__init__(f"the key {shown(key)} is given twice (lines {first} and {line})")
        self.key, self.line, self.first = key, line, first


class _StrictLoader(yaml.SafeLoader):
    """``yaml.SafeLoader`` that refuses a key given twice in one mapping (PyYAML keeps the last one silently).

    Keys merged in with ``<<: *anchor`` may still be overridden: only the mapping's own keys are compared."""

    def construct_mapping(self, node: yaml.MappingNode, deep: bool = False) -> dict:
        if isinstance(node, yaml.MappingNode):
            first: dict[Any, int] = {}
            for key_node, _ in node.value:
                if key_node.tag == "tag:yaml.org,2002:merge":
                    continue
                key = self.construct_object(key_node, deep=deep)
                line = key_node.start_mark.line + 1
                try:
                    if key in first:
                        raise _DuplicateKey(key, line, first[key])
                    first[key] = line
                except TypeError:  # an unhashable key: SafeLoader's own error names it
                    continue
        return super().construct_mapping(node, deep=deep)


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
        # the policy variant (swarm_envs.agents.policies): algorithm, encoder, odometry, decisions, memory
        "algorithm": "ppo",  # "ppo" (SB3) or "recurrent_ppo" (sb3-contrib, LSTM)
        "encoder": "mlp",  # "mlp" (flat observation) or "deepsets" (masked mean over the neighbour/message rows)
        "odometry": False,  # turn stale readings back by the robot's own rotation since they were measured
        "action_repeat": 1,  # control steps each decision is held for (gamma discounts per decision)
        "frame_stack": 1,  # decision observations the policy sees at once
        "set_embedding": 64,  # deepsets: width of the per-row embedding
        "lstm_hidden": 64,  # recurrent_ppo: LSTM units
    },
    "train": {
        "total_timesteps": 100_000,
        "n_envs": 2,  # env copies in the VecEnv
        "n_workers": 1,  # worker processes the copies are split over (one batched core each); <= n_envs
        "torch_threads": 1,  # benchmarks/bench_torch_threads.py: 2 is <=5 % faster idle, 4-8x slower with a busy core
        "checkpoint_freq": 50_000,  # robot-steps between checkpoints (0 = only the final model)
        "progress_bar": "auto",  # tqdm bars: "auto" only when stderr is a terminal, or true / false
    },
    "eval": {
        "n_seeds": 20,
        "seed_start": 10_000,  # evaluation seeds are seed_start .. seed_start + n_seeds - 1
        "deterministic": True,
        "max_cycles": None,  # None = env.max_cycles
        "baselines": True,  # also evaluate the scripted baseline and random actions (the suite does that once per task)
    },
}

_CHOICES = {"agent.activation": ("tanh", "relu"), "agent.algorithm": ("ppo", "recurrent_ppo"), "agent.encoder": ("mlp", "deepsets")}
#: every numeric key: (low, high, reason for the bounds); floats must also be finite. ``low`` is exclusive
#: for the keys of :data:`_OPEN_LOW`.
BOUNDS: dict[str, tuple[float, float, str]] = {
    "seed": (0, 2**32 - 1, "numpy's and SB3's global seeding takes 32-bit seeds"),
    "agent.learning_rate": (0.0, 1.0, "Adam steps beyond 1 diverge"),
    "agent.n_steps": (1, 1_000_000, "rollout steps per robot; the rollout buffer is also bounded in bytes"),
    "agent.batch_size": (1, 10_000_000, "at most the rollout size"),
    "agent.n_epochs": (1, 1000, "passes over each rollout"),
    "agent.gamma": (0.0, 1.0, "a discount factor"),
    "agent.gae_lambda": (0.0, 1.0, "a GAE weight"),
    "agent.clip_range": (0.0, 10.0, "PPO's ratio clip; beyond 10 it clips nothing"),
    "agent.ent_coef": (0.0, 1000.0, "a loss weight"),
    "agent.vf_coef": (0.0, 1000.0, "a loss weight"),
    "agent.max_grad_norm": (0.0, 1e6, "a gradient-norm clip"),
    "agent.log_std_init": (-20.0, 5.0, "exp(5) = 148 is already far wider than the action range [-1, 1]"),
    "agent.reward_scale": (0.0, 1e6, "a factor on the rewards PPO sees"),
    "agent.action_repeat": (1, 10_000, "control steps per decision; at most an episode's worth"),
    "agent.frame_stack": (1, 64, "stacked observations multiply the network's input and the rollout buffer"),
    "agent.set_embedding": (1, 4096, "units of a layer, like net_arch"),
    "agent.lstm_hidden": (1, 4096, "units of a layer, like net_arch"),
    "train.total_timesteps": (1, 10**12, "robot-steps; 10^12 take decades at this simulator's speed"),
    "train.n_envs": (1, 100_000, "env copies of one batched core (make_vec's bound; their estimated memory must also fit the machine's available memory)"),
    "train.n_workers": (1, 64, "worker processes, each with its own batched core"),
    "train.torch_threads": (1, 256, "more threads than cores only add overhead"),
    "train.checkpoint_freq": (0, 10**12, "robot-steps between checkpoints (0: only the final model)"),
    "eval.n_seeds": (1, 100_000, "evaluation episodes per policy"),
    "eval.seed_start": (0, 2**63 - 1, "env seeds are non-negative integers"),
    "eval.max_cycles": (1, 10**9, "the env's max_cycles rule"),
}
_OPEN_LOW = {"agent.learning_rate", "agent.clip_range", "agent.max_grad_norm", "agent.reward_scale"}
#: keys whose default is null and otherwise take a value of this type
#: keys that are true, false or "auto" (decided when used, e.g. :func:`progress_bar_on`)
_BOOL_OR_AUTO = {"train.progress_bar"}
_NULLABLE = {"eval.max_cycles": 1, "agent.scripted": ""}
#: agent.net_arch: layers and units per layer at most (memory of the policy and value networks)
MAX_LAYERS, MAX_UNITS = 16, 4096
#: bytes of the PPO rollout buffer at most (n_steps x n_envs x robots x (observation + action + 6) float32)
MAX_ROLLOUT_BYTES = 4 << 30


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


def merge_settings(base: dict, update: dict, path: str = "") -> dict:
    """A deep copy of the nested settings ``base`` with ``update`` merged in, key by key (``path``: the
    dotted prefix of ``base``, for error messages)."""
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
                raise ConfigError(f"config key {dotted!r} must be a mapping, got {shown(value)}")
            out[key] = merge_settings(base[key], value, dotted + ".")
        else:
            out[key] = value
    return out


def _env_allowed(task: str) -> dict[str, Any]:
    """Every env setting of ``task`` with its default (the id's registered settings included)."""
    from swarm_envs.agents.tasks import env_id
    from swarm_envs.registry import spec, task_class
    from swarm_envs.tasks.settings import COMMON_DEFAULTS

    name = env_id(task)
    return {**COMMON_DEFAULTS, **task_class(name).TASK_DEFAULTS, **spec(name).kwargs}


def validate(cfg: dict[str, Any]) -> dict[str, Any]:
    """Check every key and value; returns ``cfg`` (raises :class:`ConfigError`)."""
    from swarm_envs.agents.scripted import check_scripted_kwargs
    from swarm_envs.agents.tasks import env_id, import_modules

    imports = cfg["imports"]
    if not isinstance(imports, list) or not all(isinstance(m, str) and m for m in imports):
        raise ConfigError(f"config key 'imports' must be a list of module names or .py paths, got {shown(imports)}")
    try:
        import_modules(imports)
    except ImportError as err:
        raise ConfigError(f"config key 'imports': {err}") from None
    try:
        env_id(cfg["task"])
    except ValueError as err:
        raise ConfigError(f"config key 'task': {err}") from None

    def walk(node: Any, schema: dict, path: str) -> None:
        if not isinstance(node, dict):
            raise ConfigError(f"config key {path.rstrip('.')!r} must be a mapping (a section), got {shown(node)}")
        for key, value in node.items():
            if not isinstance(key, str):
                raise ConfigError(f"config section {path.rstrip('.') or 'top level'!r} has a key {key!r:.80} that is not a string")
            dotted = f"{path}{key}"
            if dotted in ("env", "agent.scripted_kwargs"):
                if not isinstance(value, dict):
                    raise ConfigError(f"config key {dotted!r} must be a mapping, got {shown(value)}")
                bad = [k for k in value if not isinstance(k, str)]
                if bad:
                    raise ConfigError(f"config key {dotted!r} has a key {bad[0]!r:.80} that is not a string")
                continue
            if key not in schema:
                raise ConfigError(f"unknown config key {dotted!r}; allowed keys here: {sorted(schema)}")
            default = schema[key]
            if isinstance(default, dict):
                walk(value, default, dotted + ".")
                continue
            if dotted in _NULLABLE and value is None:
                continue
            if dotted in _BOOL_OR_AUTO:
                if not (value is True or value is False or value == "auto"):
                    raise ConfigError(f"config key {dotted!r}={shown(value)} not allowed; allowed values: [true, false, 'auto']")
                continue
            example = _NULLABLE.get(dotted, default)
            if not _type_ok(value, example):
                raise ConfigError(f"config key {dotted!r} must be of type {type(example).__name__}, got {shown(value)}")
            if isinstance(example, float) and isinstance(value, numbers.Integral):
                try:  # an integer where a float is meant (learning_rate: 1) is that float
                    node[key] = float(value)
                except OverflowError:
                    pass  # too large for a float: the bounds refuse it
            if dotted in _CHOICES and value not in _CHOICES[dotted]:
                raise ConfigError(f"config key {dotted!r}={shown(value)} not allowed; allowed values: {list(_CHOICES[dotted])}")
            if dotted in BOUNDS:
                _check_bounds(dotted, value, integer=isinstance(example, int))

    walk(cfg, DEFAULTS, "")
    net = cfg["agent"]["net_arch"]
    if not net or len(net) > MAX_LAYERS or not all(isinstance(h, int) and not isinstance(h, bool) and 0 < h <= MAX_UNITS for h in net):
        raise ConfigError(
            f"config key 'agent.net_arch' must be a list of 1 to {MAX_LAYERS} layer sizes in [1, {MAX_UNITS}] "
            f"(memory of the networks), got {net!r:.80}"
        )
    if not isinstance(cfg["output_dir"], str) or not cfg["output_dir"].strip():
        raise ConfigError(f"config key 'output_dir' must be a non-empty path, got {cfg['output_dir']!r:.80}")
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
    allowed = _env_allowed(cfg["task"])
    unknown = sorted(set(cfg["env"]) - set(allowed) - {"flatten", "render_mode"})
    if unknown:
        raise ConfigError(f"unknown env key(s) {['env.' + k for k in unknown]} for task {cfg['task']!r}; allowed: {sorted(allowed)}")
    if "flatten" in cfg["env"] or "render_mode" in cfg["env"]:
        raise ConfigError("env.flatten and env.render_mode are set by train.py; remove them from the config")
    env = _check_env_settings(cfg["task"], cfg["env"], (scripted, cfg["agent"]["scripted_kwargs"]) if scripted is not None else None)
    if cfg["train"]["n_workers"] > cfg["train"]["n_envs"]:
        raise ConfigError(f"train.n_workers ({cfg['train']['n_workers']}) must not exceed train.n_envs ({cfg['train']['n_envs']})")
    _check_batch(cfg, env)
    return cfg


def _check_bounds(dotted: str, value: Any, integer: bool | None = None) -> None:
    """:class:`ConfigError` unless ``value`` is finite and within :data:`BOUNDS` of ``dotted``; ``integer``: the
    key takes integers (the message says "an integer"; default: whether ``value`` is one)."""
    low, high, why = BOUNDS[dotted]
    if isinstance(value, numbers.Integral) and not isinstance(value, bool):
        number = int(value)  # integers compared exactly (a float rounds 2**63 - 1 up)
        ok = (number > low if dotted in _OPEN_LOW else number >= low) and number <= high
    else:
        try:
            number = float(value)
        except (OverflowError, TypeError, ValueError):  # an int too large for a float, or not a number
            number = math.inf
        above = number > low if dotted in _OPEN_LOW else number >= low
        ok = math.isfinite(number) and above and number <= high
    if not ok:
        if integer is None:
            integer = isinstance(value, numbers.Integral)
        kind = "an integer" if integer else "a finite number"
        raise ConfigError(f"config key {dotted!r} must be {kind} in {_span(dotted)} ({why}), got {shown(value)}")


def _span(dotted: str) -> str:
    """The range of :data:`BOUNDS` ``dotted`` as text, ``[low, high]`` or ``(low, high]``."""
    low, high, _ = BOUNDS[dotted]
    low_s, high_s = (str(b) if isinstance(b, int) else f"{b:g}" for b in (low, high))
    return f"({low_s}, {high_s}]" if dotted in _OPEN_LOW else f"[{low_s}, {high_s}]"


def _check_batch(cfg: dict[str, Any], env: dict[str, int]) -> None:
    """The rollout fits make_vec's bounds and memory, and the batch fits the rollout."""
    from swarm_envs.adapters.memory import MAX_TOTAL_ROBOTS, available_memory

    a, t = cfg["agent"], cfg["train"]
    if t["n_envs"] * env["n_world"] > MAX_TOTAL_ROBOTS:
        raise ConfigError(
            f"config key 'train.n_envs': {t['n_envs']} copies of {env['n_world']} robots exceed the {MAX_TOTAL_ROBOTS} robots "
            "one batched core takes; use fewer copies"
        )
    available = available_memory()  # make_vec's memory check, over all workers' copies together
    if available is not None and t["n_envs"] * env["copy_bytes"] > available:
        raise ConfigError(
            f"config key 'train.n_envs': {t['n_envs']} env copies of {env['n_world']} robot(s) would need "
            f"~{t['n_envs'] * env['copy_bytes'] / 2**30:.2f} GiB of memory (~{env['copy_bytes'] / 1e3:,.0f} KB per copy over an "
            f"episode), but the machine has {available / 2**30:.2f} GiB available; use at most {available // env['copy_bytes']:,} copies"
        )
    rollout = a["n_steps"] * t["n_envs"] * env["n_agents"]
    obs_size = env["obs_size"] * a["frame_stack"]
    size = rollout * (obs_size + env["act_size"] + 6) * 4
    if size > MAX_ROLLOUT_BYTES:
        raise ConfigError(
            f"config key 'agent.n_steps': the PPO rollout of n_steps x n_envs x n_robots = {rollout} robot-steps would take "
            f"{size / 2**30:.1f} GiB of memory ({obs_size} observation entries each), at most {MAX_ROLLOUT_BYTES / 2**30:.0f} GiB"
        )
    if a["batch_size"] > rollout:
        raise ConfigError(
            "config key 'agent.batch_size' must not exceed the rollout size n_steps * n_envs * n_robots "
            f"({a['n_steps']} * {t['n_envs']} * {env['n_agents']})"
        )


def _check_env_settings(task: str, env: dict[str, Any], scripted: tuple[str, dict[str, Any]] | None = None) -> dict[str, int]:
    """Run the env's own validator (:func:`swarm_envs.tasks.settings.validate_settings`) on the settings train.py
    would build the env with (YAML lists as tuples, ``flatten=True``), then build that env once (cheap: no
    reset) for the checks that need its arena (robots and anchors fit; the build's fit test is exact, so
    every seed resets), and the ``scripted`` (name, keyword arguments) baseline once on it. Returns its
    sizes (``n_agents``, ``n_world``, ``obs_size``, ``act_size``) and ``copy_bytes``, the estimated memory of one env
    copy (:func:`swarm_envs.adapters.memory.copy_memory`); raises :class:`ConfigError`."""
    import swarm_envs
    from swarm_envs.agents.tasks import env_id
    from swarm_envs.tasks.settings import SettingsError
    from swarm_envs.adapters.memory import copy_memory

    kwargs = {**env, "flatten": True}
    if isinstance(kwargs.get("code"), list):
        kwargs["code"] = tuple(kwargs["code"])
    try:
        env = swarm_envs.make(env_id(task), **kwargs)
    except SettingsError as err:
        raise ConfigError(f"bad env settings: {err} (config key 'env.{err.key}')") from None
    except (ValueError, TypeError) as err:
        raise ConfigError(f"bad env settings: {err}") from None
    if scripted is not None:
        from swarm_envs.agents.scripted import make_scripted

        name, kwargs = scripted
        try:
            make_scripted(name, env, **kwargs)
        except Exception as err:  # a controller of your own may raise anything for a bad value
            env.close()
            raise ConfigError(f"config key 'agent.scripted_kwargs': scripted policy {name!r} refuses {kwargs!r:.120}: {type(err).__name__}: {err}"[:400]) from None
    agent = env.possible_agents[0]
    sizes = {
        "n_agents": env.n_agents,
        "n_world": env.n_world,
        "obs_size": int(np.prod(env.observation_space(agent).shape)),
        "act_size": int(np.prod(env.action_space(agent).shape)),
        "copy_bytes": copy_memory(env.task),
    }
    env.close()
    return sizes


def _parse_value(key: str, text: str) -> Any:
    """``text`` as YAML (a string when it is not YAML); :class:`ConfigError` naming ``key`` for a number
    too long to read (Python reads integers of at most 4300 digits)."""
    try:
        return yaml.load(text, Loader=_StrictLoader)  # safe_load that refuses a key given twice
    except _DuplicateKey as err:
        raise ConfigError(f"config key {key!r}: the value names the key {shown(err.key)} twice; keep one") from None
    except yaml.YAMLError:
        return text
    except ValueError as err:
        raise ConfigError(f"config key {key!r}: the value cannot be read ({err})"[:300]) from None


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
        value = _parse_value(key.strip(), text)
        if not free and isinstance(node.get(last), dict) and isinstance(value, dict):
            # a section given as a mapping updates it, as a section of a config file does: its other keys keep their values
            value = merge_settings(node[last], value, key.strip() + ".")
        node[last] = value
    return cfg


def progress_bar_on(setting: bool | str) -> bool:
    """Whether to draw tqdm progress bars for ``train.progress_bar``: ``true`` / ``false`` as given, ``"auto"``
    only when stderr (where tqdm draws) is a terminal, so logs and CI output carry no bar redraws."""
    if setting == "auto":
        try:
            return sys.stderr.isatty()
        except (AttributeError, ValueError):  # a replaced or closed stderr
            return False
    return bool(setting)


def load_config(path: str | Path | None, overrides: list[str] | None = None) -> dict[str, Any]:
    """Read a YAML config (missing keys take :data:`DEFAULTS`), apply overrides and validate."""
    raw: dict[str, Any] = {}
    if path is not None:
        try:
            with open(path, encoding="utf-8") as fh:
                raw = yaml.load(fh, Loader=_StrictLoader)  # safe_load that refuses a key given twice
        except FileNotFoundError:
            raise ConfigError(f"config file {str(path)!r} not found") from None
        except UnicodeDecodeError:
            raise ConfigError(f"config file {str(path)!r} is not a text (UTF-8 YAML) file") from None
        except OSError as err:
            raise ConfigError(f"config file {str(path)!r} cannot be read: {err.strerror or err}") from None
        except _DuplicateKey as err:  # PyYAML would keep the last value silently
            raise ConfigError(f"config file {str(path)!r}: {err}; keep one") from None
        except yaml.YAMLError as err:
            first = " ".join(str(err).split())
            raise ConfigError(f"config file {str(path)!r} is not valid YAML: {first:.200}") from None
        except ValueError as err:  # e.g. an integer of more than 4300 digits
            raise ConfigError(f"config file {str(path)!r}: a value cannot be read ({err})"[:300]) from None
        if raw is None or raw == {}:  # an empty file, or only comments: it would silently train the default task
            raise ConfigError(
                f"config file {str(path)!r} names no task (it is empty or only comments); give at least 'task: <env id or short name>'"
            )
        if not isinstance(raw, dict):
            raise ConfigError(f"config file {str(path)!r} must hold a mapping at the top level")
    cfg = merge_settings(DEFAULTS, raw)
    cfg = apply_overrides(cfg, overrides or [])
    return validate(cfg)


def resolve(cfg: dict[str, Any]) -> dict[str, Any]:
    """The config with task defaults filled in (scripted baseline name), for saving beside results."""
    from swarm_envs.agents.tasks import scripted_policy

    out = copy.deepcopy(cfg)
    if out["agent"]["scripted"] is None:
        out["agent"]["scripted"] = scripted_policy(out["task"])
    return out


def bounds_table() -> str:
    """A Markdown table of :data:`BOUNDS`: config key, range and the reason for it."""
    rows = ["| config key | range | why |", "|---|---|---|"]
    for key, (_, _, why) in BOUNDS.items():
        rows.append(f"| `{key}` | {_span(key)} | {why} |")
    return "\n".join(rows) + "\n"


def run_config_path(model: str | Path) -> Path | None:
    """The ``config.yaml`` of the run that saved ``model`` (train.py's ``model.zip`` or a
    ``checkpoints/*.zip``): beside the model, or beside its ``checkpoints/`` folder; None if there is none."""
    model = Path(model)
    run = model.parent.parent if model.parent.name == "checkpoints" else model.parent
    path = run / "config.yaml"
    return path if path.is_file() else None


def env_kwargs_of(cfg: dict[str, Any]) -> dict[str, Any]:
    """The env keyword arguments of a config (YAML lists -> tuples where the env wants tuples)."""
    kwargs = dict(cfg["env"])
    if isinstance(kwargs.get("code"), list):
        kwargs["code"] = tuple(kwargs["code"])
    return kwargs
