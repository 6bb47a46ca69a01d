"""Export a trained run to a folder of C sources for the robot: policy, action decoder, observation
builder (for runs with the modelled sensing) and a README describing them."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from swarm_envs.export.actions_c import native_factor, write_actions
from swarm_envs.export.network import Actor, actor_network, write_onnx
from swarm_envs.export.observation_c import write_observation_builder
from swarm_envs.export.policy_c import write_policy
from swarm_envs.export.quantize import FixedNet, quantize
from swarm_envs.export.run import ExportError, LoadedRun, load_run
from swarm_envs.registry import task_class
from swarm_envs.adapters.views import resolve_config

__all__ = ["export_run", "observation_bound", "fixed_network", "layout_table"]


def observation_bound(run: LoadedRun) -> float:
    """The largest magnitude the observation space allows (the fixed-point input range)."""
    from gymnasium import spaces

    box = spaces.flatten_space(run.layout.dict_space())
    return float(max(np.abs(box.low).max(), np.abs(box.high).max()))


class _Recorder:
    """A model whose ``predict`` records the network inputs it is given, then asks the real model."""

    def __init__(self, model: Any) -> None:
        self.model, self.rows = model, []

    def predict(self, observation: np.ndarray, **kwargs: Any):
        self.rows.append(np.array(observation, np.float32))
        return self.model.predict(observation, **kwargs)


def calibration_observations(run: LoadedRun, seeds: tuple[int, ...] = (0, 1), steps: int = 100) -> np.ndarray:
    """The network inputs (N, input size) of the torch policy driving the env, ``steps`` steps of each seed,
    through the policy's own pipeline (after odometry, at decisions, stacked): the ReLU layers' fixed-point
    ranges come from them."""
    from swarm_envs.agents.evaluation import make_env
    from swarm_envs.agents.policies import TrainedPolicy

    env = make_env(run.cfg["task"], **run.env_kwargs)
    recorder = _Recorder(run.model)
    try:
        for seed in seeds:
            env.reset(seed=seed)
            policy = TrainedPolicy(recorder, env.platform, env.layout, run.spec)
            policy.reset(env.n_agents)
            for _ in range(min(steps, run.max_cycles)):
                parts = {k: v[env.agent_robots] for k, v in env.batched_observations().items()}
                a = policy.act_batch(parts)
                env.step({agent: a[i] for i, agent in enumerate(env.possible_agents)})
    finally:
        env.close()
    return np.concatenate(recorder.rows)


def fixed_network(run: LoadedRun, actor: Actor, mode: str) -> FixedNet:
    """The ``mode`` (``q15`` / ``int8``) integer form of ``actor`` (no LSTM): the input format from the
    observation bound, ReLU formats from :func:`calibration_observations`, the set encoder's feature format
    from the bound of the values it passes through (``proprio``, ``rigid``, ``own_id``)."""
    relu = any(layer.activation == "relu" for layer in actor.layers[:-1])
    rest_bound = 1.0
    if actor.features is not None:
        from gymnasium import spaces

        box = spaces.flatten_space(run.layout.dict_space())
        rest = actor.features.rest
        rest_bound = float(max(np.abs(box.low[rest]).max(initial=0.0), np.abs(box.high[rest]).max(initial=0.0)))
    return quantize(actor.layers, observation_bound(run), mode, calibration_observations(run) if relu else None,
                    features=actor.features, rest_bound=rest_bound)


def layout_table(run: LoadedRun) -> str:
    """Markdown rows: part, flat offset, shape, columns (the flat order of ``gymnasium.spaces.flatten``)."""
    from swarm_envs.sensing.observation import ID_FIELDS, RB_FIELDS

    columns = {
        "range_bearing": ", ".join(RB_FIELDS) + " (range m, age control steps)",
        "messages": "valid, sender bearing / pi, payload bit 0 .. b-1",
        "scale_free": "valid, x, y (scale-free, clipped to +-10)",
        "rigid": "1 when the scale-free coordinates are determined",
        "proprio": "bump sector 0..7, last action (linear, angular, message bits)",
        "own_id": "own id / (n_world - 1), own id parity",
    }
    rows, offset = ["| part | offset | shape | columns |", "|---|---|---|---|"], 0
    for name, box in run.layout.dict_space().spaces.items():
        size = int(np.prod(box.shape))
        cols = columns.get(name, ", ".join(ID_FIELDS))
        rows.append(f"| `{name}` | {offset} | {'x'.join(map(str, box.shape))} | {cols} |")
        offset += size
    return "\n".join(rows)


def _architecture(run: LoadedRun, actor: Actor) -> str:
    """``D -> ... -> A`` of the actor, with its set encoder and LSTM."""
    steps = [str(actor.input_size) + (f" ({run.spec.frame_stack} stacked observations of {run.obs_size})" if run.spec.frame_stack > 1 else "")]
    if actor.features is not None:
        f = actor.features
        blocks = ", ".join(f"{b.index.shape[0]}x{b.index.shape[1]} rows -> phi {'-'.join(str(layer.weight.shape[0]) for layer in b.phi)}"
                           for b in f.blocks)
        steps.append(f"DeepSets per frame [{blocks}; masked mean + valid share; {len(f.rest)} other values] = {f.n_stack * f.frame_out}")
    if actor.lstm:
        steps.append(f"LSTM {actor.lstm[0].hidden}" + (f" x {len(actor.lstm)} layers" if len(actor.lstm) > 1 else ""))
    steps += [f"{layer.weight.shape[0]} {layer.activation}" for layer in actor.layers[:-1]] + [f"{run.action_size}"]
    return " -> ".join(steps)


def _parameters(actor: Actor) -> int:
    layers = list(actor.layers) + ([layer for b in actor.features.blocks for layer in b.phi] if actor.features else [])
    return (sum(layer.weight.size + layer.bias.size for layer in layers)
            + sum(layer.w_ih.size + layer.w_hh.size + layer.bias.size for layer in actor.lstm))


def _state_text(run: LoadedRun, actor: Actor) -> str:
    spec, parts = run.spec, []
    if spec.odometry:
        parts.append("odometry (it turns stale bearings back by the robot's own rotation since they were measured, from the last "
                     "action in `proprio`)")
    if spec.action_repeat > 1:
        parts.append(f"the held action (the policy decides every {spec.action_repeat} control steps: the first `policy_step` "
                     f"after `policy_reset` decides, the next {spec.action_repeat - 1} return that action)")
    if spec.frame_stack > 1:
        parts.append(f"the last {spec.frame_stack} decision observations (the network sees them oldest first, zeros in place of "
                     "those before the episode's first decision)")
    if actor.lstm:
        parts.append("the actor LSTM's hidden and cell states (zero at the episode start, as sb3-contrib's `episode_start`)")
    if not parts:
        return "The policy keeps no state between steps (`policy_reset` is still the call to make at the start)."
    return ("`policy_state_t` holds " + "; ".join(parts) + ". `policy_reset` clears it: call it when the robot starts and at "
            "every episode start, and call `policy_step` every control step.")


def _readme(run: LoadedRun, actor: Actor, fixed: FixedNet | None, files: list[Path], observation: bool) -> str:
    p, spec = run.platform, run.spec
    unit, factor, what = native_factor(p)
    arch = _architecture(run, actor)
    params = _parameters(actor)
    if fixed is None:
        weight_bytes = 4 * params
    else:
        per_weight = 2 if fixed.mode == "q15" else 1
        fixed_layers = list(fixed.layers) + ([layer for _, phi in fixed.features.blocks for layer in phi] if fixed.features else [])
        weight_bytes = sum(per_weight * layer.weight.size + 8 * layer.bias.size for layer in fixed_layers) + 2 * 513
    width = max([layer.weight.shape[0] for layer in actor.layers] + ([4 * actor.lstm[0].hidden] if actor.lstm else []))
    state_bytes = ((8 * (run.layout.max_age + 1) + 8 + 4 * 3 * run.layout.n_neighbours) if spec.odometry else 0)
    state_bytes += (4 + 4 * run.action_size if spec.action_repeat > 1 else 0) + (4 * actor.input_size if spec.frame_stack > 1 else 0)
    state_bytes += sum(8 * layer.hidden for layer in actor.lstm)
    state_bytes = max(state_bytes, 4)
    stack_bytes = 4 * run.obs_size + 8 * width + (4 * spec.frame_stack * actor.features.frame_out if actor.features else 0)
    kind = "float32" if fixed is None else (f"fixed point ({fixed.mode}: {'int16' if fixed.mode == 'q15' else 'int8'} weights, "
                                            f"int16 activations, int64 sums; observation input Q{fixed.in_frac}"
                                            + (f", set features Q{fixed.features.feat_frac}" if fixed.features else "") + ")")
    settings = ", ".join(f"{k}={v!r}" for k, v in sorted(run.env_kwargs.items())) or "defaults"
    obs_line = ("`observation.h` / `observation.c` build the flat observation from the robot's sensing."
                if observation else "The observation builder is not part of this folder (it rebuilds sensing='full' with the two-hop "
                                    "scale-free method only): the firmware fills the flat observation below itself.")
    return f"""# Exported policy: {run.env_id} on the {p.name}

Made by `swarm-export` from the run `{run.run_dir}` (task `{run.cfg['task']}`, env `{run.env_id}`, settings
{settings}; swarm_envs observation layout with {run.layout.n_neighbours} neighbour rows, {run.layout.n_messages}
message rows, {run.layout.message_bits} message bits, max age {run.layout.max_age} steps).

- Policy: {spec.name}, actor {arch} ({params} parameters), {kind}.
- Sizes: {weight_bytes} bytes of constant weights and tables; {state_bytes} bytes of `policy_state_t` per robot
  (about; `sizeof` is exact); stack of one `policy_step` about {stack_bytes} bytes.
- Control step: 0.1 s; an episode of the env is {run.max_cycles} steps.
- Files: {', '.join(f'`{f.name}`' for f in files)}.

## Control loop

```c
#include "policy.h"
#include "actions.h"

static policy_state_t state;            /* one per robot; no dynamic memory */
float obs[POLICY_OBS_SIZE], action[POLICY_ACTION_SIZE];
actions_command_t cmd;

policy_reset(&state);                   /* at the start of every run (episode) */
every 0.1 s:
    fill obs (layout below) from this step's sensing, with proprio's last action = the previous `action`
    policy_step(&state, obs, action);
    actions_decode(action, &cmd);       /* cmd.left_native, cmd.right_native: {unit}; cmd.message: bits */
    set the wheels and the outgoing message
```

{obs_line}
{_state_text(run, actor)}

## Observation ({run.obs_size} floats)

{layout_table(run)}

## Actions ({run.action_size} floats in [-1, 1])

`action[0]` linear speed as a fraction of {p.max_speed} m/s, `action[1]` angular speed as a fraction of
{p.max_angular_speed:.4g} rad/s (counter-clockwise), then {run.layout.message_bits} message bits (1 where > 0).
`actions_decode` gives the wheel speeds (left = v - w b/2, right = v + w b/2, b = {p.wheel_base} m, each
limited to +-{p.max_speed} m/s) in m/s and in {unit} ({factor:g} per m/s: {what}).
{"The motors do not turn below " + str(p.min_wheel_speed) + " m/s; the env models that dead zone, the decoder leaves it to the motors." if p.min_wheel_speed > 0 else ""}
"""


def export_run(run_dir: str | Path, out_dir: str | Path, fixed: str | None = None, onnx: bool = True) -> list[Path]:
    """Write the export folder of the run in ``run_dir`` into ``out_dir``; ``fixed``: ``None`` (float32),
    ``"q15"`` or ``"int8"``. Returns the files written; :class:`ExportError` for a run it cannot export."""
    run = load_run(run_dir, fixed)
    out = Path(out_dir)
    if out.exists() and not out.is_dir():
        raise ExportError(f"output '{out}' exists and is not a folder")
    try:
        actor = actor_network(run.model)
    except ValueError as err:
        raise ExportError(f"run '{run.run_dir}': {err}") from None
    out.mkdir(parents=True, exist_ok=True)
    net = None
    if fixed is not None:
        net = fixed_network(run, actor, fixed)
    summary = f"{run.env_id} on the {run.platform.name}, {run.spec.name}, {'float32' if net is None else net.mode}"
    files = write_policy(actor, run.layout, run.platform, out, odometry=run.spec.odometry, action_repeat=run.spec.action_repeat,
                         fixed=net, summary=summary)
    files += write_actions(run.platform, run.action_size, out, summary=summary)
    if onnx:
        try:
            import onnx as _onnx  # noqa: F401  (the exporter needs the package)
        except ImportError:
            pass
        else:
            files.append(write_onnx(run.model, out / "policy.onnx"))
    # the builder rebuilds the modelled stack's observation; an ideal-sensing run (exact values) has no
    # firmware-side tables to build from
    env_cfg = resolve_config(task_class(run.env_id), run.env_kwargs)
    observation = env_cfg["sensing"] == "full" and env_cfg["scale_free_method"] == "two_hop"
    if observation:
        files += write_observation_builder(run.env_id, run.env_kwargs, out)
    readme = out / "README.md"
    readme.write_text(_readme(run, actor, net, files, observation), encoding="utf-8")
    return files + [readme]
