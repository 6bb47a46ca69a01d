"""Write ``policy.h`` / ``policy.c``: the actor's deterministic forward pass as dependency-free C99.

The C is generated here from the layers' arrays (:mod:`swarm_envs.export.network`). An ONNX-to-C compiler
(emx-onnx-cgen 1.4 compiles the exported ``policy.onnx`` of these actors) covers the network alone: the
policy's own pre-processing (:class:`swarm_envs.agents.policies.Odometry`, a per-robot state) is no ONNX
graph, and the integer build (:mod:`swarm_envs.export.quantize`) must follow one arithmetic that a numpy
model reproduces bit for bit. One generator writes both builds with the same structure: a chain of dense
layers (tanh / ReLU), weights as ``const`` arrays, no dynamic memory, the per-robot state a caller-owned
``policy_state_t``. Both builds take the DeepSets encoder, the float build also the LSTM of the recurrent
policy; both take the pipeline :class:`swarm_envs.agents.policies.TrainedPolicy` runs around the network:
odometry every control step, a decision every ``action_repeat`` steps (the action held in between) and the
last ``frame_stack`` decision observations, oldest first, zeros before the first.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from swarm_envs.adapters.env import DT
from swarm_envs.export.network import Actor, Layer, LstmLayer, SetFeatures
from swarm_envs.export.quantize import TANH_IN_FRAC, TANH_TABLE, FixedNet
from swarm_envs.sensing.observation import ObservationLayout
from swarm_envs.sim.platforms import Platform

__all__ = ["write_policy", "odometry_indices"]


def _f32(values: np.ndarray) -> str:
    return ",".join(f"{float(v):.9e}f" for v in np.asarray(values, np.float32).ravel())


def _ints(values: np.ndarray) -> str:
    return ",".join(str(int(v)) for v in np.asarray(values).ravel())


def _wrap(text: str, width: int = 110) -> str:
    out, line = [], "    "
    for item in text.split(","):
        if len(line) + len(item) + 1 > width:
            out.append(line.rstrip())
            line = "    "
        line += item + ","
    out.append(line.rstrip())
    return "\n".join(out)


def _rows(index: np.ndarray) -> str:
    return ",\n".join("    {" + _ints(row) + "}" for row in np.asarray(index))


def _d(value: float) -> str:
    return f"{float(value):.17e}"


def odometry_indices(layout: ObservationLayout) -> dict[str, np.ndarray]:
    """Flat indices the odometry reads and turns: ``range_bearing`` (K, 7), ``scale_free`` (K, 3), last action (2,)."""
    from swarm_envs.agents.policies import part_indices
    from swarm_envs.sim.world import N_BUMP_SECTORS

    index = part_indices(layout)
    return {"rb": index["range_bearing"], "sf": index["scale_free"], "action": index["proprio"][N_BUMP_SECTORS : N_BUMP_SECTORS + 2]}


def _odometry_c(layout: ObservationLayout, platform: Platform) -> str:
    idx = odometry_indices(layout)
    k = idx["rb"].shape[0]
    return f"""
/* Odometry: every stale body-frame reading turned back by the robot's own rotation since it was measured
 * (swarm_envs.agents.policies.Odometry), from the last (linear, angular) command in proprio, wheel-limited
 * as the motors take it. Double precision, as the Python pipeline. */
static const POLICY_ROM int16_t RB_INDEX[{k}][7] = {{
{_rows(idx["rb"])}
}};
static const POLICY_ROM int16_t SF_INDEX[{k}][3] = {{
{_rows(idx["sf"])}
}};
#define ACTION_LINEAR {int(idx["action"][0])}
#define ACTION_ANGULAR {int(idx["action"][1])}
#define MAX_SPEED {_d(platform.max_speed)}
#define MAX_ANGULAR_SPEED {_d(platform.max_angular_speed)}
#define HALF_BASE {_d(0.5 * platform.wheel_base)}
#define DT {_d(DT)}

static double clampd(double v, double lo, double hi) {{ return v < lo ? lo : (v > hi ? hi : v); }}

static void rotate(float *x, float *y, double angle)
{{
    double c = cos(angle), s = sin(angle), xd = (double)*x, yd = (double)*y;
    *x = (float)(xd * c + yd * s);
    *y = (float)(yd * c - xd * s);
}}

static void odometry(policy_state_t *state, float *obs)
{{
    double linear = (double)obs[ACTION_LINEAR] * MAX_SPEED, angular = (double)obs[ACTION_ANGULAR] * MAX_ANGULAR_SPEED;
    double left = clampd(linear - angular * HALF_BASE, -MAX_SPEED, MAX_SPEED);
    double right = clampd(linear + angular * HALF_BASE, -MAX_SPEED, MAX_SPEED);
    double since[POLICY_ODOMETRY_HISTORY + 1];
    int i, a, changed = 0;
    for (i = POLICY_ODOMETRY_HISTORY - 1; i > 0; --i) state->turned[i] = state->turned[i - 1];
    state->turned[0] = (right - left) / (2.0 * HALF_BASE) * DT;
    since[0] = 0.0;
    for (a = 0; a < POLICY_ODOMETRY_HISTORY; ++a) since[a + 1] = since[a] + state->turned[a];
    for (i = 0; i < {k}; ++i) {{
        const POLICY_ROM int16_t *r = RB_INDEX[i];
        int age = (int)lrint(clampd((double)obs[r[6]], 0.0, POLICY_ODOMETRY_HISTORY)); /* ties to even, as numpy's rint */
        double angle = obs[r[0]] > 0.5f ? since[age] : 0.0;
        rotate(&obs[r[2]], &obs[r[3]], angle);
        rotate(&obs[r[4]], &obs[r[5]], angle);
    }}
    for (i = 0; i < {k}; ++i)
        for (a = 0; a < 3; ++a) changed |= state->sf_last[i][a] != obs[SF_INDEX[i][a]];
    if (state->has_sf_last) state->sf_since = changed ? 0 : (state->sf_since + 1 < POLICY_ODOMETRY_HISTORY ? state->sf_since + 1 : POLICY_ODOMETRY_HISTORY);
    state->has_sf_last = 1;
    for (i = 0; i < {k}; ++i) {{
        const POLICY_ROM int16_t *r = SF_INDEX[i];
        for (a = 0; a < 3; ++a) state->sf_last[i][a] = obs[r[a]];
        rotate(&obs[r[1]], &obs[r[2]], obs[r[0]] > 0.5f ? since[state->sf_since] : 0.0);
    }}
}}
"""


def _state_struct(odometry: bool, k: int, action_repeat: int, frame_stack: int, lstm: list[LstmLayer]) -> str:
    fields = []
    if odometry:
        fields += ["    double turned[POLICY_ODOMETRY_HISTORY]; /* own rotation (rad) per control step, newest first */",
                   "    int sf_since;                          /* steps since the scale_free block changed */",
                   "    int has_sf_last;",
                   f"    float sf_last[{k}][3];                  /* the scale_free block of the previous step */"]
    if action_repeat > 1:
        fields += ["    int held_steps;                        /* calls left that return the held action */",
                   "    float held[POLICY_ACTION_SIZE];        /* the action of the last decision */"]
    if frame_stack > 1:
        fields += ["    float frames[POLICY_FRAME_STACK][POLICY_OBS_SIZE]; /* the last decision observations, oldest first */"]
    if lstm:
        fields += ["    float lstm_h[POLICY_LSTM_LAYERS][POLICY_LSTM_HIDDEN]; /* the actor LSTM's hidden state */",
                   "    float lstm_c[POLICY_LSTM_LAYERS][POLICY_LSTM_HIDDEN]; /* and cell state */"]
    if not fields:
        fields = ["    int unused; /* this policy keeps no state between steps */"]
    return "typedef struct {\n" + "\n".join(fields) + "\n} policy_state_t;"


def _header(obs_size: int, action_size: int, odometry: bool, k: int, history: int, fixed: FixedNet | None, summary: str,
            action_repeat: int = 1, frame_stack: int = 1, lstm: list[LstmLayer] | None = None) -> str:
    lstm = lstm or []
    state = _state_struct(odometry, k, action_repeat, frame_stack, lstm)
    stateless = not odometry and action_repeat == 1 and frame_stack == 1 and not lstm
    fixed_api = ""
    if fixed is not None and stateless:
        fixed_api = f"""
/* Integer-only step: obs_q[i] = observation * 2^POLICY_INPUT_FRAC (int16, round to nearest, saturated);
 * action_q15[i] = action * 32768 (in [-32767, 32767]). */
#define POLICY_INPUT_FRAC {fixed.in_frac}
void policy_step_q(policy_state_t *state, const int16_t obs_q[POLICY_OBS_SIZE], int16_t action_q15[POLICY_ACTION_SIZE]);
"""
    defines = [f"#define POLICY_OBS_SIZE {obs_size}", f"#define POLICY_ACTION_SIZE {action_size}",
               f"#define POLICY_ODOMETRY {int(odometry)}",
               f"#define POLICY_FIXED_POINT {0 if fixed is None else (15 if fixed.mode == 'q15' else 8)}",
               f"#define POLICY_ACTION_REPEAT {action_repeat} /* control steps per decision */",
               f"#define POLICY_FRAME_STACK {frame_stack} /* decision observations the network sees */",
               f"#define POLICY_INPUT_SIZE {obs_size * frame_stack} /* the network's input */",
               f"#define POLICY_LSTM_LAYERS {len(lstm)}"]
    if lstm:
        defines.append(f"#define POLICY_LSTM_HIDDEN {lstm[0].hidden}")
    if odometry:
        defines.append(f"#define POLICY_ODOMETRY_HISTORY {history}")
    return f"""/* Generated by swarm-export: {summary}. */
#ifndef SWARM_POLICY_H
#define SWARM_POLICY_H

#include <stddef.h>
#include <stdint.h>

{chr(10).join(defines)}

/* Per-robot state, owned by the caller; policy_reset() at the start of every episode. */
{state}

/* Start an episode: clears the state (odometry, held action, stacked frames, LSTM state). */
void policy_reset(policy_state_t *state);
/* One control step: the flat observation (README.md, "Observation") -> the action in [-1, 1]
 * (linear, angular, message bits...), the deterministic policy as SB3's predict(deterministic=True).
 * Call it every control step, also between decisions (it returns the held action then). */
void policy_step(policy_state_t *state, const float obs[POLICY_OBS_SIZE], float action[POLICY_ACTION_SIZE]);
size_t policy_state_size(void);
{fixed_api}
#endif
"""


def _index_type(index: np.ndarray) -> str:
    return "int16_t" if int(np.max(index, initial=0)) < 32768 else "int32_t"


def _chain(layers: list[Layer], prefix: str, src: str, last_dst: str) -> list[str]:
    """``dense`` calls through ``layers`` from ``src``, alternating h0 / h1, the last into ``last_dst``."""
    calls = []
    for i, layer in enumerate(layers):
        out, inp = layer.weight.shape
        act = {"tanh": "ACT_TANH", "relu": "ACT_RELU", "none": "ACT_NONE"}[layer.activation]
        dst = last_dst if i == len(layers) - 1 else ("h0" if i % 2 == 0 else "h1")
        calls.append(f"dense({prefix}W{i}, {prefix}B{i}, {src}, {dst}, {out}, {inp}, {act});")
        src = dst
    return calls


def _weights(layers: list[Layer], prefix: str) -> list[str]:
    data = []
    for i, layer in enumerate(layers):
        out, inp = layer.weight.shape
        data.append(f"static const POLICY_ROM float {prefix}W{i}[{out * inp}] = {{\n{_wrap(_f32(layer.weight))}\n}};")
        data.append(f"static const POLICY_ROM float {prefix}B{i}[{out}] = {{\n{_wrap(_f32(layer.bias))}\n}};")
    return data


def _set_encoder(features: SetFeatures) -> tuple[list[str], str]:
    """Constants and ``set_encode(frame, out)``: the DeepSets features of one frame (SetEncoder.forward)."""
    data, code = [], []
    width = max(layer.weight.shape[0] for b in features.blocks for layer in b.phi)
    n_feat = max(b.index.shape[1] for b in features.blocks)
    for j, block in enumerate(features.blocks):
        k, f = block.index.shape
        e = block.phi[-1].weight.shape[0]
        data.append(f"static const POLICY_ROM {_index_type(block.index)} SET{j}_INDEX[{k}][{f}] = {{\n{_rows(block.index)}\n}};")
        data += _weights(block.phi, f"S{j}")
        calls = "\n            ".join(_chain(block.phi, f"S{j}", "row", "h"))
        code.append(f"""    /* block {j}: {k} rows of {f} features -> mean of phi ({e}) over the valid rows, share of valid rows */
    count = 0;
    for (j = 0; j < {e}; ++j) sum[j] = 0.0f;
    for (r = 0; r < {k}; ++r) {{
        const POLICY_ROM {_index_type(block.index)} *idx = SET{j}_INDEX[r];
        if (frame[idx[0]] > 0.5f) {{
            for (j = 0; j < {f}; ++j) row[j] = frame[idx[j]];
            {calls}
            for (j = 0; j < {e}; ++j) sum[j] += h[j];
            ++count;
        }}
    }}
    for (j = 0; j < {e}; ++j) out[o + j] = sum[j] / (float)(count > 0 ? count : 1);
    out[o + {e}] = (float)count / {float(k):.1f}f;
    o += {e + 1};""")
    rest = features.rest
    if len(rest):
        data.append(f"static const POLICY_ROM {_index_type(rest)} SET_REST[{len(rest)}] = {{\n{_wrap(_ints(rest))}\n}};")
        code.append(f"    for (j = 0; j < {len(rest)}; ++j) out[o + j] = frame[SET_REST[j]];")
    body = f"""
/* DeepSets features of one observation frame (swarm_envs.agents.policies.SetEncoder): per row block, phi on
 * every valid row (column 0 > 0.5), the mean over them (zeros when none) and their share; then the rest. */
static void set_encode(const float *frame, float *out)
{{
    float row[{n_feat}], h0[{width}], h1[{width}], h[{width}], sum[{width}];
    int r, j, count, o = 0;
    (void)h0; (void)h1;
{chr(10).join(code)}
}}
"""
    return data, body


def _lstm(lstm: list[LstmLayer]) -> tuple[list[str], str]:
    data = []
    for i, layer in enumerate(lstm):
        four, inp = layer.w_ih.shape
        data.append(f"static const POLICY_ROM float L{i}_WIH[{four * inp}] = {{\n{_wrap(_f32(layer.w_ih))}\n}};")
        data.append(f"static const POLICY_ROM float L{i}_WHH[{four * layer.hidden}] = {{\n{_wrap(_f32(layer.w_hh))}\n}};")
        data.append(f"static const POLICY_ROM float L{i}_B[{four}] = {{\n{_wrap(_f32(layer.bias))}\n}};")
    body = """
static float sigmoid(float v) { return 1.0f / (1.0f + expf(-v)); }

/* One step of an LSTM layer (torch.nn.LSTM): gates i, f, g, o = W_ih x + W_hh h + b; c = f c + i g; h = o tanh(c) */
static void lstm_cell(const POLICY_ROM float *w_ih, const POLICY_ROM float *w_hh, const POLICY_ROM float *b, const float *x, int n_in,
                      float *h, float *c)
{
    float gates[4 * POLICY_LSTM_HIDDEN];
    int i, j;
    for (i = 0; i < 4 * POLICY_LSTM_HIDDEN; ++i) {
        float acc = b[i];
        const POLICY_ROM float *row = w_ih + (size_t)i * n_in;
        for (j = 0; j < n_in; ++j) acc += row[j] * x[j];
        row = w_hh + (size_t)i * POLICY_LSTM_HIDDEN;
        for (j = 0; j < POLICY_LSTM_HIDDEN; ++j) acc += row[j] * h[j];
        gates[i] = acc;
    }
    for (j = 0; j < POLICY_LSTM_HIDDEN; ++j) {
        float in = sigmoid(gates[j]), forget = sigmoid(gates[POLICY_LSTM_HIDDEN + j]);
        float cell = tanhf(gates[2 * POLICY_LSTM_HIDDEN + j]), out = sigmoid(gates[3 * POLICY_LSTM_HIDDEN + j]);
        c[j] = forget * c[j] + in * cell;
        h[j] = out * tanhf(c[j]);
    }
}
"""
    return data, body


def _float_net(actor: Actor) -> tuple[str, str]:
    layers = actor.layers
    data = []
    parts = []
    width = max(layer.weight.shape[0] for layer in layers)
    lines = ["    const float *in = x;"]
    if actor.features is not None:
        f = actor.features
        set_data, set_body = _set_encoder(f)
        data += set_data
        parts.append(set_body)
        lines = [f"    float features[{f.n_stack * f.frame_out}];", "    const float *in = features;",
                 f"    for (i = 0; i < {f.n_stack}; ++i) set_encode(x + (size_t)i * {f.frame_size}, features + (size_t)i * {f.frame_out});"]
    else:
        lines.append("    (void)i;")
    if actor.lstm:
        lstm_data, lstm_body = _lstm(actor.lstm)
        data += lstm_data
        parts.append(lstm_body)
        for i, layer in enumerate(actor.lstm):
            lines.append(f"    lstm_cell(L{i}_WIH, L{i}_WHH, L{i}_B, in, {layer.w_ih.shape[1]}, state->lstm_h[{i}], state->lstm_c[{i}]);")
            lines.append(f"    in = state->lstm_h[{i}];")
    else:
        lines.append("    (void)state;")
    data += _weights(layers, "")
    calls = "\n".join("    " + c for c in _chain(layers, "", "in", "action"))
    body = f"""
enum {{ ACT_NONE, ACT_TANH, ACT_RELU }};

/* y = act(W x + b), W row-major (n_out, n_in) */
static void dense(const POLICY_ROM float *w, const POLICY_ROM float *b, const float *x, float *y, int n_out, int n_in, int act)
{{
    int i, j;
    for (i = 0; i < n_out; ++i) {{
        float acc = b[i];
        const POLICY_ROM float *row = w + (size_t)i * n_in;
        for (j = 0; j < n_in; ++j) acc += row[j] * x[j];
        y[i] = act == ACT_TANH ? tanhf(acc) : (act == ACT_RELU ? (acc > 0.0f ? acc : 0.0f) : acc);
    }}
}}
{"".join(parts)}
/* the network: input (POLICY_INPUT_SIZE) -> action in [-1, 1] */
static void forward(policy_state_t *state, const float *x, float *action)
{{
    float h0[{width}], h1[{width}];
    int i;
{chr(10).join(lines)}
    (void)h0; (void)h1;
{calls}
    for (i = 0; i < POLICY_ACTION_SIZE; ++i) action[i] = action[i] < -1.0f ? -1.0f : (action[i] > 1.0f ? 1.0f : action[i]);
}}
"""
    return "\n".join(data), body


def _fixed_weights(layers: list, prefix: str, wtype: str) -> list[str]:
    data = []
    for i, layer in enumerate(layers):
        out, inp = layer.weight.shape
        data.append(f"/* {prefix or 'mlp '}layer {i}: input Q{layer.in_frac}, weights Q{layer.w_frac}, output Q{layer.out_frac}, {layer.activation} */")
        data.append(f"static const POLICY_ROM {wtype} {prefix}W{i}[{out * inp}] = {{\n{_wrap(_ints(layer.weight))}\n}};")
        data.append(f"static const POLICY_ROM int64_t {prefix}B{i}[{out}] = {{\n{_wrap(','.join(f'INT64_C({int(v)})' for v in layer.bias))}\n}};")
    return data


def _fixed_chain(layers: list, prefix: str, src: str, last_dst: str, head: bool) -> list[str]:
    calls = []
    for i, layer in enumerate(layers):
        out, inp = layer.weight.shape
        last = i == len(layers) - 1
        kind = "OUT_ACTION" if (head and last) else {"tanh": "OUT_TANH", "relu": "OUT_RELU"}[layer.activation]
        dst = last_dst if last else ("h0" if i % 2 == 0 else "h1")
        calls.append(f"dense_q({prefix}W{i}, {prefix}B{i}, {src}, {dst}, {out}, {inp}, {layer.in_frac + layer.w_frac}, {layer.out_frac}, {kind});")
        src = dst
    return calls


def _fixed_set(fs, wtype: str) -> tuple[list[str], str]:
    """Constants and ``set_encode_q(frame, out)``: the integer DeepSets features of one frame (quantize._set_q)."""
    data, code = [], []
    width = max(layer.weight.shape[0] for _, phi in fs.blocks for layer in phi)
    n_feat = max(index.shape[1] for index, _ in fs.blocks)
    for j, (index, phi) in enumerate(fs.blocks):
        k, f = index.shape
        e = phi[-1].weight.shape[0]
        data.append(f"static const POLICY_ROM {_index_type(index)} SET{j}_INDEX[{k}][{f}] = {{\n{_rows(index)}\n}};")
        data += _fixed_weights(phi, f"S{j}", wtype)
        calls = "\n            ".join(_fixed_chain(phi, f"S{j}", "row", "h", head=False))
        code.append(f"""    /* block {j}: {k} rows of {f} features -> mean of phi ({e}, Q15) over the valid rows, share of valid rows */
    count = 0;
    for (j = 0; j < {e}; ++j) sum[j] = 0;
    for (r = 0; r < {k}; ++r) {{
        const POLICY_ROM {_index_type(index)} *idx = SET{j}_INDEX[r];
        if (frame[idx[0]] > VALID_Q) {{
            for (j = 0; j < {f}; ++j) row[j] = frame[idx[j]];
            {calls}
            for (j = 0; j < {e}; ++j) sum[j] += h[j];
            ++count;
        }}
    }}
    for (j = 0; j < {e}; ++j) out[o + j] = to_feature(div_round(sum[j], count > 0 ? count : 1), 15);
    share = ((int64_t)count * 32768 + {k // 2}) / {k};
    out[o + {e}] = to_feature(share < 32767 ? share : 32767, 15);
    o += {e + 1};""")
    if len(fs.rest):
        data.append(f"static const POLICY_ROM {_index_type(fs.rest)} SET_REST[{len(fs.rest)}] = {{\n{_wrap(_ints(fs.rest))}\n}};")
        code.append(f"    for (j = 0; j < {len(fs.rest)}; ++j) out[o + j] = to_feature(frame[SET_REST[j]], {fs.in_frac});")
    body = f"""
#define VALID_Q {1 << (fs.in_frac - 1)} /* 0.5 at the input's Q{fs.in_frac} */
#define FEATURE_FRAC {fs.feat_frac}

/* v / count (count > 0) rounded to nearest, ties away from zero */
static int64_t div_round(int64_t v, int64_t count)
{{
    return v >= 0 ? (v + count / 2) / count : -((-v + count / 2) / count);
}}

/* v at Q(frac) -> the features' Q(FEATURE_FRAC), saturated to int16 */
static int16_t to_feature(int64_t v, int frac) {{ return sat16(shift_round(v, frac - FEATURE_FRAC), -32768, 32767); }}

/* integer DeepSets features of one quantised frame (quantize._set_q) */
static void set_encode_q(const int16_t *frame, int16_t *out)
{{
    int16_t row[{n_feat}], h0[{width}], h1[{width}], h[{width}];
    int64_t sum[{width}], share;
    int r, j, count, o = 0;
    (void)h0; (void)h1;
{chr(10).join(code)}
}}
"""
    return data, body


def _fixed_net(net: FixedNet) -> tuple[str, str]:
    wtype = "int16_t" if net.mode == "q15" else "int8_t"
    data = [f"/* tanh(i / 64) in Q15, i = 0 .. 512 */\nstatic const POLICY_ROM int16_t TANH_Q15[513] = {{\n{_wrap(_ints(TANH_TABLE))}\n}};"]
    width = max(layer.weight.shape[0] for layer in net.layers)
    set_body, prelude = "", ["    const int16_t *in = x;"]
    if net.features is not None:
        fs = net.features
        set_data, set_body = _fixed_set(fs, wtype)
        data += set_data
        frame_out = sum(phi[-1].weight.shape[0] + 1 for _, phi in fs.blocks) + len(fs.rest)
        prelude = [f"    int16_t features[{fs.n_stack * frame_out}];", "    const int16_t *in = features;", "    int i;",
                   f"    for (i = 0; i < {fs.n_stack}; ++i) set_encode_q(x + (size_t)i * {fs.frame_size}, features + (size_t)i * {frame_out});"]
    data += _fixed_weights(net.layers, "", wtype)
    calls = [f"    {c}" for c in _fixed_chain(net.layers, "", "in", "action_q15", head=True)]
    body = f"""
enum {{ OUT_TANH, OUT_RELU, OUT_ACTION }};

/* v / 2^s rounded to nearest (half up); s <= 0 multiplies. Right shifts of negative values are arithmetic
 * on every compiler this targets (gcc, clang, arm-none-eabi-gcc, avr-gcc). */
static int64_t shift_round(int64_t v, int s)
{{
    return s > 0 ? (v + ((int64_t)1 << (s - 1))) >> s : v * ((int64_t)1 << -s);
}}

static int16_t sat16(int64_t v, int64_t lo, int64_t hi) {{ return (int16_t)(v < lo ? lo : (v > hi ? hi : v)); }}

/* tanh of z in Q{TANH_IN_FRAC}, in Q15 */
static int16_t tanh_q15(int64_t z)
{{
    int64_t a = z < 0 ? -z : z, y;
    if (a >= ((int64_t)8 << {TANH_IN_FRAC})) {{
        y = 32767;
    }} else {{
        int idx = (int)(a >> 6), frac = (int)(a & 63);
        y = TANH_Q15[idx] + ((((int64_t)TANH_Q15[idx + 1] - TANH_Q15[idx]) * frac + 32) >> 6);
    }}
    return (int16_t)(z < 0 ? -y : y);
}}

/* y = out(W x + b): x at Q(in), W at Q(w), the int64 sum at Q(acc_frac = in + w), y at Q(out_frac) */
static void dense_q(const POLICY_ROM {wtype} *w, const POLICY_ROM int64_t *b, const int16_t *x, int16_t *y, int n_out, int n_in, int acc_frac, int out_frac, int kind)
{{
    int i, j;
    for (i = 0; i < n_out; ++i) {{
        int64_t acc = b[i];
        const POLICY_ROM {wtype} *row = w + (size_t)i * n_in;
        for (j = 0; j < n_in; ++j) acc += (int32_t)row[j] * (int32_t)x[j];
        if (kind == OUT_TANH) {{
            int64_t z = shift_round(acc, acc_frac - {TANH_IN_FRAC});
            y[i] = tanh_q15(z < INT32_MIN ? INT32_MIN : (z > INT32_MAX ? INT32_MAX : z));
        }} else if (kind == OUT_RELU) {{
            y[i] = sat16(shift_round(acc > 0 ? acc : 0, acc_frac - out_frac), 0, 32767);
        }} else {{
            y[i] = sat16(shift_round(acc, acc_frac - 15), -32767, 32767);
        }}
    }}
}}

{set_body}
/* the integer network: quantised input (POLICY_INPUT_SIZE, Q{net.in_frac}) -> action in Q15 */
static void forward_q(const int16_t *x, int16_t *action_q15)
{{
    int16_t h0[{width}], h1[{width}];
{chr(10).join(prelude)}
    (void)h0; (void)h1;
{chr(10).join(calls)}
}}

/* the network: input (POLICY_INPUT_SIZE) -> action in [-1, 1], quantised on the way in */
static void forward(policy_state_t *state, const float *obs, float *action)
{{
    int16_t x[POLICY_INPUT_SIZE], action_q15[POLICY_ACTION_SIZE];
    int i;
    (void)state;
    for (i = 0; i < POLICY_INPUT_SIZE; ++i) {{
        long q = lrintf(obs[i] * {float(2.0 ** net.in_frac):.1f}f);
        x[i] = (int16_t)(q < -32768 ? -32768 : (q > 32767 ? 32767 : q));
    }}
    forward_q(x, action_q15);
    for (i = 0; i < POLICY_ACTION_SIZE; ++i) action[i] = (float)action_q15[i] / 32768.0f;
}}
"""
    return "\n\n".join(data), body


def _reset(odometry: bool, k: int, action_repeat: int, frame_stack: int, lstm: list[LstmLayer]) -> str:
    lines = []
    if odometry:
        lines += ["    for (i = 0; i < POLICY_ODOMETRY_HISTORY; ++i) state->turned[i] = 0.0;", "    state->sf_since = 0;",
                  "    state->has_sf_last = 0;", f"    for (i = 0; i < {k}; ++i)", "        for (j = 0; j < 3; ++j) state->sf_last[i][j] = 0.0f;"]
    if action_repeat > 1:
        lines += ["    state->held_steps = 0;", "    for (i = 0; i < POLICY_ACTION_SIZE; ++i) state->held[i] = 0.0f;"]
    if frame_stack > 1:
        lines += ["    for (i = 0; i < POLICY_FRAME_STACK; ++i)", "        for (j = 0; j < POLICY_OBS_SIZE; ++j) state->frames[i][j] = 0.0f;"]
    if lstm:
        lines += ["    for (i = 0; i < POLICY_LSTM_LAYERS; ++i)",
                  "        for (j = 0; j < POLICY_LSTM_HIDDEN; ++j) state->lstm_h[i][j] = state->lstm_c[i][j] = 0.0f;"]
    if not lines:
        return "    state->unused = 0;\n"
    return "    int i, j;\n" + "\n".join(lines) + "\n    (void)j;\n"


def _step(odometry: bool, action_repeat: int, frame_stack: int) -> str:
    lines = ["    float x[POLICY_OBS_SIZE];", "    memcpy(x, obs, sizeof x);"]
    lines.append("    odometry(state, x);                  /* every control step */" if odometry else "")
    if action_repeat > 1:
        lines += ["    if (state->held_steps > 0) {          /* between decisions: the held action */",
                  "        --state->held_steps;", "        memcpy(action, state->held, sizeof state->held);", "        return;", "    }",
                  "    state->held_steps = POLICY_ACTION_REPEAT - 1;"]
    if frame_stack > 1:
        lines += ["    memmove(state->frames[0], state->frames[1], (POLICY_FRAME_STACK - 1) * sizeof state->frames[0]);",
                  "    memcpy(state->frames[POLICY_FRAME_STACK - 1], x, sizeof x);",
                  "    forward(state, state->frames[0], action);"]
    else:
        lines.append("    forward(state, x, action);")
    if action_repeat > 1:
        lines.append("    memcpy(state->held, action, sizeof state->held);")
    return "\n".join(line for line in lines if line)


def write_policy(actor: Actor, layout: ObservationLayout, platform: Platform, out_dir: Path, odometry: bool = False,
                 action_repeat: int = 1, fixed: FixedNet | None = None, summary: str = "") -> list[Path]:
    """Write ``policy.h`` and ``policy.c`` into ``out_dir``: the float ``actor``, or the integer one of ``fixed``
    (an actor without LSTM), with the odometry, action repeat and frame stack around it (the frame stack is the
    actor's input size over the observation's)."""
    obs_size = sum(int(np.prod(box.shape)) for box in layout.dict_space().spaces.values())
    action_size = actor.layers[-1].weight.shape[0]
    frame_stack = actor.input_size // obs_size
    if frame_stack * obs_size != actor.input_size:
        raise ValueError(f"the actor's input ({actor.input_size}) is not a whole number of observations ({obs_size})")
    if fixed is not None and (actor.lstm or (actor.features is None) != (fixed.features is None)):
        raise ValueError("the fixed-point build takes an actor without LSTM, quantised with its set encoder if it has one")
    k, history = layout.n_neighbours, int(layout.max_age) + 1
    header = _header(obs_size, action_size, odometry, k, history, fixed, summary, action_repeat, frame_stack, actor.lstm)
    data, body = _float_net(actor) if fixed is None else _fixed_net(fixed)
    odo = _odometry_c(layout, platform) if odometry else ""
    stateless = not odometry and action_repeat == 1 and frame_stack == 1 and not actor.lstm
    step_q = ""
    if fixed is not None and stateless:
        step_q = """
void policy_step_q(policy_state_t *state, const int16_t obs_q[POLICY_OBS_SIZE], int16_t action_q15[POLICY_ACTION_SIZE])
{
    (void)state;
    forward_q(obs_q, action_q15);
}
"""
    source = f"""/* Generated by swarm-export: {summary}. */
#include <math.h>
#include <string.h>
#include "policy.h"

/* The address space of the constant tables: empty (the default) for a von Neumann MCU or the host; on a
 * Harvard MCU define it so they stay in flash, e.g. -DPOLICY_ROM=__flash with avr-gcc (-std=gnu99). */
#ifndef POLICY_ROM
#define POLICY_ROM
#endif

{data}
{body}
{odo}
void policy_reset(policy_state_t *state)
{{
{_reset(odometry, k, action_repeat, frame_stack, actor.lstm)}}}

size_t policy_state_size(void) {{ return sizeof(policy_state_t); }}

void policy_step(policy_state_t *state, const float obs[POLICY_OBS_SIZE], float action[POLICY_ACTION_SIZE])
{{
{_step(odometry, action_repeat, frame_stack)}
}}
{step_q}"""
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = [out_dir / "policy.h", out_dir / "policy.c"]
    paths[0].write_text(header, encoding="utf-8")
    paths[1].write_text(source, encoding="utf-8")
    return paths
