"""C99 observation builder for robot firmware (docs/export.md, "The observation builder").

:func:`write_observation_builder` writes ``observation.h`` / ``observation.c`` for one env config: from the
tables a robot's firmware keeps (its range & bearing or sector-bearing neighbour table, the SwarmCom
messages decoded since the last control step, its scale-free neighbour table and rigid flag, its bump
flags and last action) ``obs_build`` writes the float32 vector the simulator's observation layout
(:class:`swarm_envs.sensing.observation.ObservationLayout`, flattened in Gymnasium's sorted key order) gives for
that config: the same row ranking, truncation, scaling, id encoding and clipping to the observation Box.
The C uses no dynamic memory and only ``<math.h>`` and ``<stdint.h>``.

:func:`firmware_tables` fills the same tables from the simulator's sensing state (``sensing="full"``),
never from ground truth, so the C output can be compared with the env's observation.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from swarm_envs.sim.geometry import wrap_angle
from swarm_envs.sim.world import N_BUMP_SECTORS

__all__ = ["write_observation_builder", "builder_constants", "firmware_tables", "PART_MACROS"]

#: observation part -> the macro suffix of its offset in the flat vector (``OBS_OFFSET_<suffix>``)
PART_MACROS = {
    "message_ids": "MESSAGE_IDS",
    "messages": "MESSAGES",
    "own_id": "OWN_ID",
    "proprio": "PROPRIO",
    "range_bearing": "RANGE_BEARING",
    "range_bearing_ids": "RANGE_BEARING_IDS",
    "rigid": "RIGID",
    "scale_free": "SCALE_FREE",
    "scale_free_ids": "SCALE_FREE_IDS",
}


def _make_env(env_id: str, env_kwargs: dict[str, Any]) -> Any:
    from swarm_envs.registry import make

    return make(env_id, **env_kwargs)


def builder_constants(env: Any) -> dict[str, Any]:
    """The sizes, capacities, offsets and bounds the C builder is generated with, for a built ``env``
    (a :class:`swarm_envs.adapters.env.SwarmEnv` with ``sensing="full"``).

    Keys: ``K``, ``M``, ``message_bits``, ``action_size``, ``n_world``, ``observe_ids``, ``size`` (length
    of the flat vector), ``offsets`` (part -> first index), ``low`` / ``high`` (float32 bounds of the flat
    vector), ``neighbour_capacity`` (entries of the neighbour table), ``message_capacity``,
    ``scale_free_capacity``, ``detector_bearing`` (rad in (-pi, pi], body frame, per detector), ``platform``,
    ``has_range`` (the platform measures range), ``max_age`` (steps, the oldest observed reading).
    """
    if env.config["sensing"] != "full":
        raise ValueError(f"the C observation builder reproduces sensing='full' only, got sensing={env.config['sensing']!r}")
    if env.config["scale_free_method"] != "two_hop":
        raise ValueError("the C observation builder needs scale_free_method='two_hop' (the firmware's scale-free table)")
    layout = env.layout
    space = layout.dict_space()
    offsets, start = {}, 0
    for name, box in space.spaces.items():
        offsets[name] = start
        start += int(np.prod(box.shape))
    from gymnasium import spaces

    flat = spaces.flatten_space(space)
    return {
        "K": layout.n_neighbours,
        "M": layout.n_messages,
        "message_bits": layout.message_bits,
        "action_size": layout.action_size,
        "n_world": int(env.n_world),
        "observe_ids": bool(layout.observe_ids),
        "size": start,
        "offsets": offsets,
        "low": np.asarray(flat.low, np.float32),
        "high": np.asarray(flat.high, np.float32),
        "neighbour_capacity": max(int(env.n_world) - 1, 1),
        "message_capacity": layout.n_messages,
        "scale_free_capacity": int(env.sensing.exchange.k_max),
        "detector_bearing": wrap_angle(np.asarray(env.platform.detector_directions, np.float64)),
        "platform": env.platform.name,
        "has_range": bool(env.sensing.has_range),
        "max_age": int(layout.max_age),
    }


def write_observation_builder(env_id: str, env_kwargs: dict, out_dir: Path) -> list[Path]:
    """Write ``observation.h`` and ``observation.c`` for env ``env_id`` built with ``env_kwargs`` into
    ``out_dir`` (created if missing); returns their paths (header first)."""
    env = _make_env(env_id, dict(env_kwargs))
    try:
        const = builder_constants(env)
    finally:
        env.close()
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    header, source = out_dir / "observation.h", out_dir / "observation.c"
    header.write_text(_header(const, env_id))
    source.write_text(_source(const))
    return [header, source]


# ---------------------------------------------------------------------------------------------- tables
def firmware_tables(env: Any, agent: str) -> dict[str, Any]:
    """The firmware-side tables of ``agent`` after the env's last reset or step, filled from the sensing
    stack's state (``sensing="full"``): what the robot measured and decoded, never ground truth.

    Returns a dict: ``own_id`` (int); ``bump`` (8 ints, sector 0 ahead, counter-clockwise); ``last_action``
    (float32 (2 + b,), the command applied in the last step, clipped to [-1, 1], zero after a reset);
    ``neighbours``: list of ``{"id", "range" (m), "bearing" (rad), "heading" (rad), "age" (steps)}`` in
    the table's order (ascending decoded id); ``messages``: list of ``{"sender", "detector", "n_bits",
    "payload" (list of 0/1)}`` in arrival order (at most ``n_messages``); ``scale_free``: ``{"rigid": bool,
    "entries": [{"id", "x", "y"}]}``, the robot's computed neighbour coordinates (scale-free units) in the
    table's slot order.
    """
    from swarm_envs.sensing.full import FullSensing
    from swarm_envs.sensing.scale_free import coordinates_all

    sensing = env.sensing
    if not isinstance(sensing, FullSensing):
        raise ValueError("firmware_tables needs sensing='full'")
    frame = env.core.frame
    if frame is None:
        raise RuntimeError("firmware_tables needs a started episode; call reset() first")
    const = builder_constants(env)
    n_world = env.n_world
    row = int(env.agent_robots[env.possible_agents.index(agent)])  # one copy: the world robot row
    own = row % n_world

    nb = frame.neighbours
    mine = np.flatnonzero(nb.rx == row)
    neighbours = [
        {"id": int(nb.tx[p] % n_world), "range": float(nb.range[p]), "bearing": float(nb.bearing[p]),
         "heading": float(nb.heading[p]), "age": int(nb.age[p])}
        for p in _table_order(mine, nb.slots, row, const["has_range"])
    ]  # fmt: skip

    msg = frame.messages
    if msg.distance_hint is not None:
        raise ValueError("firmware_tables: the stack ranks messages by a distance hint the firmware buffer does not hold")
    directions = const["detector_bearing"]
    messages = []
    for p in np.flatnonzero(msg.receiver == row)[: const["message_capacity"]]:
        detector = np.flatnonzero(directions == msg.bearing[p])
        if detector.size != 1:
            raise ValueError(f"message bearing {msg.bearing[p]} is not a detector axis of the {env.platform.name}")
        payload = np.asarray(msg.payload[p]).reshape(-1)
        messages.append({"sender": int(msg.sender[p] % n_world), "detector": int(detector[0]), "n_bits": int(payload.size),
                         "payload": [int(v > 0.5) for v in payload]})  # fmt: skip

    result = coordinates_all(sensing.exchange.knowledge())  # the robot's scale-free localisation on what it knows
    slots = np.flatnonzero(result.valid[row])
    if not const["has_range"] and frame.scale_free.ids is not None:  # the stack's ranking order first (see _table_order)
        rank = {int(i): r for r, i in enumerate(frame.scale_free.ids[row]) if i >= 0}  # id -> observation slot
        slots = np.array(sorted(slots, key=lambda s: rank.get(int(result.ids[row, s]), len(rank))), dtype=np.int64)
    entries = [
        {"id": int(result.ids[row, s] % n_world), "x": float(result.xy[row, s, 0]), "y": float(result.xy[row, s, 1])}
        for s in slots
    ]
    return {
        "own_id": own,
        "bump": [int(b) for b in env.core.bumps[row]],
        "last_action": np.asarray(env.core.last_actions[row], np.float32),
        "neighbours": neighbours,
        "messages": messages,
        "scale_free": {"rigid": bool(result.rigid[row]), "entries": entries},
    }


def _table_order(mine: np.ndarray, slots: np.ndarray | None, row: int, has_range: bool) -> np.ndarray:
    """The order of ``agent``'s neighbour-table entries (reading indices ``mine``, ascending decoded id).

    A platform with range ranks its rows by range, so the table's order does not matter. A platform without
    range (r-one) ranks by age with equal ages in a random order the simulator draws each step
    (:func:`swarm_envs.sensing.observation.ranked_slots`); the C builder breaks equal keys by table order, so here the
    table lists the readings the simulator ranked first, in its order, then the rest: a firmware that shuffles
    its table once per control step follows the same rule in distribution."""
    if has_range or slots is None:
        return mine
    ranked = [int(p) for p in slots[row] if p >= 0]
    return np.array(ranked + [int(p) for p in mine if int(p) not in ranked], dtype=np.int64)


# ---------------------------------------------------------------------------------------------- C text
def _f32(values: np.ndarray) -> str:
    """float32 values as exact C float literals."""
    out = []
    for v in np.asarray(values, np.float32).reshape(-1):
        out.append(f"{float(v)!r}f" if np.isfinite(v) else ("INFINITY" if v > 0 else "-INFINITY"))
    return ", ".join(out)


def _header(c: dict[str, Any], env_id: str) -> str:
    offsets = "\n".join(
        f"#define OBS_OFFSET_{PART_MACROS[name]} {start}" for name, start in c["offsets"].items()
    )
    range_doc = (
        "estimated range from the range & bearing brightness matrix [F14], m"
        if c["has_range"]
        else "0 (the r-one measures no range; its rows hold sector bearings of decoded frames)"
    )
    bearing_doc = (
        "bearing [F14] estimated from the brightness matrix"
        if c["has_range"]
        else "sector bearing of the longest contiguous run of clean receivers [L Sec. 3.2.1]"
    )
    return f"""/* observation.h: observation builder for {env_id} on the {c['platform']} (generated by swarm_envs.export).
 *
 * obs_build() turns the tables the firmware keeps into the float32 observation vector the simulator gives
 * for this configuration (layout of docs/observations.md, flattened in sorted key order). C99, no dynamic
 * memory. Angles are in the robot's body frame: x forward, counter-clockwise, radians. One control step is
 * 0.1 s.
 */
#ifndef SWARM_OBSERVATION_H
#define SWARM_OBSERVATION_H

#include <stdint.h>

#define OBS_SIZE {c['size']}                  /* floats in the observation vector */
#define OBS_N_NEIGHBOURS {c['K']}          /* K: range_bearing / scale_free rows */
#define OBS_N_MESSAGES {c['M']}            /* M: messages rows */
#define OBS_MESSAGE_BITS {c['message_bits']}          /* b: payload bits per message */
#define OBS_ACTION_SIZE {c['action_size']}           /* 2 + b */
#define OBS_N_BUMP_SECTORS {N_BUMP_SECTORS}
#define OBS_N_WORLD {c['n_world']}               /* robots in the swarm (ids 0 .. OBS_N_WORLD - 1) */
#define OBS_OBSERVE_IDS {int(c['observe_ids'])}           /* 1: the id parts are in the vector */
#define OBS_MAX_AGE {c['max_age']}             /* steps: older neighbour readings are not observed */
#define OBS_N_DETECTORS {len(c['detector_bearing'])}
#define OBS_NEIGHBOUR_CAPACITY {c['neighbour_capacity']}    /* entries of obs_neighbour_table_t */
#define OBS_MESSAGE_CAPACITY {c['message_capacity']}      /* entries of obs_message_buffer_t */
#define OBS_SCALE_FREE_CAPACITY {c['scale_free_capacity']}  /* entries of obs_scale_free_table_t */
#define OBS_PAYLOAD_CAPACITY {max(c['message_bits'], 1)}

/* first index of each part in the vector (parts in sorted key order) */
{offsets}

/* One neighbour reading; the table holds one per decoded neighbour id, kept in ascending id order. */
typedef struct {{
    uint16_t id;          /* neighbour id as decoded from the frame it was measured on (0 .. OBS_N_WORLD - 1) */
    float range_m;        /* {range_doc} */
    float bearing_rad;    /* direction to the neighbour: {bearing_doc}, rad */
    float heading_rad;    /* the neighbour's forward direction seen from this robot, rad */
    uint16_t age_steps;   /* control steps since the reading was measured (0: this step) */
}} obs_neighbour_t;

typedef struct {{
    uint16_t count;                                   /* valid entries */
    obs_neighbour_t entry[OBS_NEIGHBOUR_CAPACITY];
}} obs_neighbour_table_t;

/* One SwarmCom application message decoded since the last control step. */
typedef struct {{
    uint16_t sender_id;   /* the frame header's decoded origin (0 .. OBS_N_WORLD - 1; others are skipped) */
    uint8_t detector;     /* index of the receiver's brightest detector during the frame (0 .. OBS_N_DETECTORS - 1) */
    uint8_t n_bits;       /* payload length, bits (frames with n_bits != OBS_MESSAGE_BITS are skipped) */
    uint8_t payload[OBS_PAYLOAD_CAPACITY]; /* payload bits, 0 or 1, first bit first */
}} obs_message_t;

typedef struct {{
    uint16_t count;                                   /* messages in arrival order (the first M are used) */
    obs_message_t entry[OBS_MESSAGE_CAPACITY];
}} obs_message_buffer_t;

/* One neighbour whose scale-free coordinates the robot's 2-hop localisation [L Algs. 1-4] computed. */
typedef struct {{
    uint16_t id;          /* neighbour id stored by the bearing exchange */
    float x;              /* position in the robot's frame, scale-free units (mean neighbour distance 1) */
    float y;
}} obs_scale_free_entry_t;

typedef struct {{
    uint8_t rigid;        /* 1: every neighbour's scale-free length was computable [L Sec. 5.5.1] */
    uint16_t count;       /* valid entries, in the localisation's slot order */
    obs_scale_free_entry_t entry[OBS_SCALE_FREE_CAPACITY];
}} obs_scale_free_table_t;

/* Everything obs_build() reads. */
typedef struct {{
    uint16_t own_id;                          /* this robot's id (0 .. OBS_N_WORLD - 1) */
    uint8_t bump[OBS_N_BUMP_SECTORS];         /* 1: contact in 45-degree sector i (0 ahead, counter-clockwise) during the last step */
    float last_action[OBS_ACTION_SIZE];       /* the action applied in the last step, each in [-1, 1] (0 after a reset) */
    obs_neighbour_table_t neighbours;
    obs_message_buffer_t messages;
    obs_scale_free_table_t scale_free;
}} obs_tables_t;

/* Indices (into key[0..n-1]) of the k smallest keys in increasing order, NaN keys last, equal keys in table
 * order; order[c] = -1 past the n-th. Returns the number of rows filled. The ranking rule of the
 * range_bearing rows (key: range_m, or age_steps on a platform without range) and scale_free rows (key:
 * distance from the origin). */
int obs_rank_rows(const double *key, int n, int k, int *order);

/* Write the observation vector of the tables t into out[0 .. OBS_SIZE - 1]. */
void obs_build(const obs_tables_t *t, float out[OBS_SIZE]);

#endif /* SWARM_OBSERVATION_H */
"""


def _source(c: dict[str, Any]) -> str:
    ids = c["observe_ids"]
    id_scale = float(max(c["n_world"] - 1, 1))
    det = ", ".join(repr(float(v)) for v in c["detector_bearing"])

    def if_ids(text: str) -> str:
        return text if ids else ""

    if c["has_range"]:
        key_doc, key_expr, tie_doc = "the estimated range", "(double)e->range_m", ""
    else:  # no range sensor: the most recently heard first, equal ages in a per-step random order (table order)
        key_doc, key_expr = "the reading's age: the most recently decoded first", "(double)e->age_steps"
        tie_doc = "; shuffle the neighbour table once per control step so that equal ages rank in a random order"

    return f"""/* observation.c: see observation.h (generated by swarm_envs.export). */
#include "observation.h"

#include <math.h>

#define OBS_PI 3.141592653589793
#define OBS_ID_SCALE {id_scale!r}   /* ids are scaled by max(OBS_N_WORLD - 1, 1) */

static const float OBS_LOW[OBS_SIZE] = {{{_f32(c['low'])}}};
static const float OBS_HIGH[OBS_SIZE] = {{{_f32(c['high'])}}};
/* detector axes in the body frame, rad: a message's sender bearing */
static const double OBS_DETECTOR_BEARING[OBS_N_DETECTORS] = {{{det}}};

static int obs_before(double ka, int ia, double kb, int ib)
{{
    int nan_a = ka != ka, nan_b = kb != kb;
    if (nan_a != nan_b) return nan_b;
    if (!nan_a && ka != kb) return ka < kb;
    return ia < ib;
}}

int obs_rank_rows(const double *key, int n, int k, int *order)
{{
    int count = 0, p, c;
    for (p = 0; p < n; ++p) {{
        c = count;
        if (c == k) {{
            if (k == 0 || !obs_before(key[p], p, key[order[k - 1]], order[k - 1])) continue;
            c = k - 1;
        }} else {{
            ++count;
        }}
        while (c > 0 && obs_before(key[p], p, key[order[c - 1]], order[c - 1])) {{
            order[c] = order[c - 1];
            --c;
        }}
        order[c] = p;
    }}
    for (c = count; c < k; ++c) order[c] = -1;
    return count;
}}

/* The ranking keys: range_bearing rows are the K neighbour-table entries with the smallest key ({key_doc};
 * NaN, never observed, for a reading older than OBS_MAX_AGE), scale_free rows the K entries nearest in
 * scale-free distance. Equal keys keep table order{tie_doc}. */
static double obs_neighbour_key(const obs_neighbour_t *e)
{{
    return e->age_steps > OBS_MAX_AGE ? NAN : {key_expr};
}}

static double obs_scale_free_key(const obs_scale_free_entry_t *e)
{{
    return hypot((double)e->x, (double)e->y);
}}
{if_ids('''
/* [decoded, id / (n_world - 1), id < own id, same parity as own id] */
static void obs_id_row(float *dst, int id, int own)
{
    dst[0] = 1.0f;
    dst[1] = (float)((double)id / OBS_ID_SCALE);
    dst[2] = id < own ? 1.0f : 0.0f;
    dst[3] = (id % 2) == (own % 2) ? 1.0f : 0.0f;
}
''')}
void obs_build(const obs_tables_t *t, float out[OBS_SIZE])
{{
    int order[OBS_N_NEIGHBOURS];
    double key[OBS_NEIGHBOUR_CAPACITY > OBS_SCALE_FREE_CAPACITY ? OBS_NEIGHBOUR_CAPACITY : OBS_SCALE_FREE_CAPACITY];
    int i, c, n, own = (int)t->own_id;

    (void)own;
    for (i = 0; i < OBS_SIZE; ++i) out[i] = 0.0f;

    /* range_bearing: the K neighbour readings ranked first (obs_neighbour_key) */
    n = t->neighbours.count < OBS_NEIGHBOUR_CAPACITY ? t->neighbours.count : OBS_NEIGHBOUR_CAPACITY;
    for (i = 0; i < n; ++i) key[i] = obs_neighbour_key(&t->neighbours.entry[i]);
    obs_rank_rows(key, n, OBS_N_NEIGHBOURS, order);
    for (c = 0; c < OBS_N_NEIGHBOURS; ++c) {{
        const obs_neighbour_t *e;
        float *row;
        if (order[c] < 0) break;
        e = &t->neighbours.entry[order[c]];
        if (e->age_steps > OBS_MAX_AGE) break; /* too old: not observed (NaN keys rank last) */
        row = out + OBS_OFFSET_RANGE_BEARING + 7 * c;
        row[0] = 1.0f;
        row[1] = e->range_m;
        row[2] = (float)cos((double)e->bearing_rad);
        row[3] = (float)sin((double)e->bearing_rad);
        row[4] = (float)cos((double)e->heading_rad);
        row[5] = (float)sin((double)e->heading_rad);
        row[6] = (float)e->age_steps;
{if_ids('''        obs_id_row(out + OBS_OFFSET_RANGE_BEARING_IDS + 4 * c, (int)e->id, own);
''')}    }}

    /* messages: the first M well-formed ones in arrival order */
    n = t->messages.count < OBS_MESSAGE_CAPACITY ? t->messages.count : OBS_MESSAGE_CAPACITY;
    for (i = 0, c = 0; i < n && c < OBS_N_MESSAGES; ++i) {{
        const obs_message_t *e = &t->messages.entry[i];
        float *row = out + OBS_OFFSET_MESSAGES + (2 + OBS_MESSAGE_BITS) * c;
        int b;
        if (OBS_MESSAGE_BITS == 0 || e->n_bits != OBS_MESSAGE_BITS || e->sender_id >= OBS_N_WORLD || e->detector >= OBS_N_DETECTORS) continue;
        row[0] = 1.0f;
        row[1] = (float)(OBS_DETECTOR_BEARING[e->detector] / OBS_PI);
        for (b = 0; b < OBS_MESSAGE_BITS; ++b) row[2 + b] = e->payload[b] ? 1.0f : 0.0f;
{if_ids('''        obs_id_row(out + OBS_OFFSET_MESSAGE_IDS + 4 * c, (int)e->sender_id, own);
''')}        ++c;
    }}

    /* scale_free: the K computed neighbours ranked first (obs_scale_free_key) */
    n = t->scale_free.count < OBS_SCALE_FREE_CAPACITY ? t->scale_free.count : OBS_SCALE_FREE_CAPACITY;
    for (i = 0; i < n; ++i) key[i] = obs_scale_free_key(&t->scale_free.entry[i]);
    obs_rank_rows(key, n, OBS_N_NEIGHBOURS, order);
    for (c = 0; c < OBS_N_NEIGHBOURS; ++c) {{
        const obs_scale_free_entry_t *e;
        float *row;
        if (order[c] < 0) break;
        e = &t->scale_free.entry[order[c]];
        row = out + OBS_OFFSET_SCALE_FREE + 3 * c;
        row[0] = 1.0f;
        row[1] = e->x;
        row[2] = e->y;
{if_ids('''        obs_id_row(out + OBS_OFFSET_SCALE_FREE_IDS + 4 * c, (int)e->id, own);
''')}    }}
    out[OBS_OFFSET_RIGID] = t->scale_free.rigid ? 1.0f : 0.0f;

    /* proprio: bump sectors, last action */
    for (i = 0; i < OBS_N_BUMP_SECTORS; ++i) out[OBS_OFFSET_PROPRIO + i] = t->bump[i] ? 1.0f : 0.0f;
    for (i = 0; i < OBS_ACTION_SIZE; ++i) out[OBS_OFFSET_PROPRIO + OBS_N_BUMP_SECTORS + i] = t->last_action[i];
{if_ids('''
    out[OBS_OFFSET_OWN_ID] = (float)((double)own / OBS_ID_SCALE);
    out[OBS_OFFSET_OWN_ID + 1] = (float)(own % 2);
''')}
    /* clip into the observation Box (NaN stays NaN) */
    for (i = 0; i < OBS_SIZE; ++i) {{
        float v = out[i];
        if (v == v) {{
            if (!(v > OBS_LOW[i])) v = OBS_LOW[i];
            if (!(v < OBS_HIGH[i])) v = OBS_HIGH[i];
        }}
        out[i] = v;
    }}
}}
"""
