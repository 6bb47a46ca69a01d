"""Write ``policy.h`` / ``policy.c``: the actor's deterministic forward pass as dependency-free C99.

The C is generated here from the layers' arrays (:mod:`swarm_envs.export.network`). An ONNX-to-C compiler
(emx-onnx-cgen 1.4 compiles the exported ``policy.onnx`` of these actors) covers the network alone: the
policy's own pre-processing (:class:`swarm_envs.agents.policies.Odometry`, a per-robot state) is no ONNX
graph, and the integer build (:mod:`swarm_envs.export.quantize`) must follow one arithmetic that a numpy
model reproduces bit for bit. One generator writes both builds with the same structure: a chain of dense
layers (tanh / ReLU), weights as ``const`` arrays, no dynamic memory, the per-robot state a caller-owned
``policy_state_t``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from swarm_envs.env import DT
from swarm_envs.export.network import Layer
from swarm_envs.export.quantize import TANH_IN_FRAC, TANH_TABLE, FixedNet
from swarm_envs.observation import ObservationLayout
from swarm_envs.platforms import Platform

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
    from swarm_envs.agents.policies import _part_indices
    from swarm_envs.world import N_BUMP_SECTORS

    index = _part_indices(layout)
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


def _header(obs_size: int, action_size: int, odometry: bool, k: int, history: int, fixed: FixedNet | None, summary: str) -> str:
    state = (f"""typedef struct {{
    double turned[POLICY_ODOMETRY_HISTORY]; /* own rotation (rad) per control step, newest first */
    int sf_since;                          /* steps since the scale_free block changed */
    int has_sf_last;
    float sf_last[{k}][3];                  /* the scale_free block of the previous step */
}} policy_state_t;""" if odometry else """typedef struct {
    int unused; /* this policy keeps no state between steps */
} policy_state_t;""")
    fixed_api = ""
    if fixed is not None and not odometry:
        fixed_api = f"""
/* Integer-only step: obs_q[i] = observation * 2^POLICY_INPUT_FRAC (int16, round to nearest, saturated);
 * action_q15[i] = action * 32768 (in [-32767, 32767]). */
#define POLICY_INPUT_FRAC {fixed.in_frac}
void policy_step_q(policy_state_t *state, const int16_t obs_q[POLICY_OBS_SIZE], int16_t action_q15[POLICY_ACTION_SIZE]);
"""
    return f"""/* Generated by swarm-export: {summary}. */
#ifndef SWARM_POLICY_H
#define SWARM_POLICY_H

#include <stddef.h>
#include <stdint.h>

#define POLICY_OBS_SIZE {obs_size}
#define POLICY_ACTION_SIZE {action_size}
#define POLICY_ODOMETRY {int(odometry)}
#define POLICY_FIXED_POINT {0 if fixed is None else (15 if fixed.mode == "q15" else 8)}
{f"#define POLICY_ODOMETRY_HISTORY {history}" if odometry else ""}

/* Per-robot state, owned by the caller; policy_reset() at the start of every episode. */
{state}

void policy_reset(policy_state_t *state);
/* One control step: the flat observation (README.md, "Observation") -> the action in [-1, 1]
 * (linear, angular, message bits...), the deterministic policy as SB3's predict(deterministic=True). */
void policy_step(policy_state_t *state, const float obs[POLICY_OBS_SIZE], float action[POLICY_ACTION_SIZE]);
size_t policy_state_size(void);
{fixed_api}
#endif
"""


def _float_net(layers: list[Layer]) -> tuple[str, str]:
    data, calls = [], []
    width = max(layer.weight.shape[0] for layer in layers)
    for i, layer in enumerate(layers):
        out, inp = layer.weight.shape
        data.append(f"static const POLICY_ROM float W{i}[{out * inp}] = {{\n{_wrap(_f32(layer.weight))}\n}};")
        data.append(f"static const POLICY_ROM float B{i}[{out}] = {{\n{_wrap(_f32(layer.bias))}\n}};")
        act = {"tanh": "ACT_TANH", "relu": "ACT_RELU", "none": "ACT_NONE"}[layer.activation]
        src = "x" if i == 0 else ("h0" if i % 2 == 1 else "h1")
        dst = "action" if i == len(layers) - 1 else ("h0" if i % 2 == 0 else "h1")
        calls.append(f"    dense(W{i}, B{i}, {src}, {dst}, {out}, {inp}, {act});")
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

static void forward(const float *x, float *action)
{{
    float h0[{width}], h1[{width}];
    int i;
    (void)h0; (void)h1;
{chr(10).join(calls)}
    for (i = 0; i < POLICY_ACTION_SIZE; ++i) action[i] = action[i] < -1.0f ? -1.0f : (action[i] > 1.0f ? 1.0f : action[i]);
}}
"""
    return "\n".join(data), body


def _fixed_net(net: FixedNet) -> tuple[str, str]:
    wtype = "int16_t" if net.mode == "q15" else "int8_t"
    data = [f"/* tanh(i / 64) in Q15, i = 0 .. 512 */\nstatic const POLICY_ROM int16_t TANH_Q15[513] = {{\n{_wrap(_ints(TANH_TABLE))}\n}};"]
    calls = []
    width = max(layer.weight.shape[0] for layer in net.layers)
    for i, layer in enumerate(net.layers):
        out, inp = layer.weight.shape
        data.append(f"/* layer {i}: input Q{layer.in_frac}, weights Q{layer.w_frac}, output Q{layer.out_frac}, {layer.activation} */")
        data.append(f"static const POLICY_ROM {wtype} W{i}[{out * inp}] = {{\n{_wrap(_ints(layer.weight))}\n}};")
        data.append(f"static const POLICY_ROM int64_t B{i}[{out}] = {{\n{_wrap(','.join(f'INT64_C({int(v)})' for v in layer.bias))}\n}};")
        last = i == len(net.layers) - 1
        kind = "OUT_ACTION" if last else {"tanh": "OUT_TANH", "relu": "OUT_RELU"}[layer.activation]
        src = "x" if i == 0 else ("h0" if i % 2 == 1 else "h1")
        dst = "action_q15" if last else ("h0" if i % 2 == 0 else "h1")
        calls.append(f"    dense_q(W{i}, B{i}, {src}, {dst}, {out}, {inp}, {layer.in_frac + layer.w_frac}, {layer.out_frac}, {kind});")
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

static void forward_q(const int16_t *x, int16_t *action_q15)
{{
    int16_t h0[{width}], h1[{width}];
    (void)h0; (void)h1;
{chr(10).join(calls)}
}}

static void forward(const float *obs, float *action)
{{
    int16_t x[POLICY_OBS_SIZE], action_q15[POLICY_ACTION_SIZE];
    int i;
    for (i = 0; i < POLICY_OBS_SIZE; ++i) {{
        long q = lrintf(obs[i] * {float(2.0 ** net.in_frac):.1f}f);
        x[i] = (int16_t)(q < -32768 ? -32768 : (q > 32767 ? 32767 : q));
    }}
    forward_q(x, action_q15);
    for (i = 0; i < POLICY_ACTION_SIZE; ++i) action[i] = (float)action_q15[i] / 32768.0f;
}}
"""
    return "\n\n".join(data), body


def write_policy(layers: list[Layer], layout: ObservationLayout, platform: Platform, odometry: bool, out_dir: Path,
                 fixed: FixedNet | None = None, summary: str = "") -> list[Path]:
    """Write ``policy.h`` and ``policy.c`` into ``out_dir``: the float actor, or the integer one of ``fixed``."""
    obs_size, action_size = layers[0].weight.shape[1], layers[-1].weight.shape[0]
    k, history = layout.n_neighbours, int(layout.max_age) + 1
    header = _header(obs_size, action_size, odometry, k, history, fixed, summary)
    data, body = _float_net(layers) if fixed is None else _fixed_net(fixed)
    odo = _odometry_c(layout, platform) if odometry else ""
    reset = ("    int i, a;\n    for (i = 0; i < POLICY_ODOMETRY_HISTORY; ++i) state->turned[i] = 0.0;\n"
             "    state->sf_since = 0;\n    state->has_sf_last = 0;\n"
             f"    for (i = 0; i < {k}; ++i)\n        for (a = 0; a < 3; ++a) state->sf_last[i][a] = 0.0f;\n") if odometry else "    state->unused = 0;\n"
    step_q = ""
    if fixed is not None and not odometry:
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
{reset}}}

size_t policy_state_size(void) {{ return sizeof(policy_state_t); }}

void policy_step(policy_state_t *state, const float obs[POLICY_OBS_SIZE], float action[POLICY_ACTION_SIZE])
{{
    float x[POLICY_OBS_SIZE];
    memcpy(x, obs, sizeof x);
{"    odometry(state, x);" if odometry else "    (void)state;"}
    forward(x, action);
}}
{step_q}"""
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = [out_dir / "policy.h", out_dir / "policy.c"]
    paths[0].write_text(header, encoding="utf-8")
    paths[1].write_text(source, encoding="utf-8")
    return paths
