"""The generated C observation builder (swarm_envs.export.observation_c) against the simulator.

For an e-puck, an r-one and a Droplet config (``sensing="full"``) the env is stepped with random actions
(with a reset in between); for every agent and step the firmware-side tables are filled from the sensing
state (:func:`firmware_tables`), passed to the compiled ``obs_build`` through ``ctypes`` and its vector
compared with the env's flattened observation. A change of the simulator's row ranking, scaling or
encoding that the C does not follow fails here.
"""

from __future__ import annotations

import ctypes
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
import yaml
from gymnasium import spaces

from swarm_envs.export.observation_c import builder_constants, firmware_tables, write_observation_builder
from swarm_envs.sensing.observation import nearest_slots, range_bearing_rows, ranked_slots
from swarm_envs.registry import make

CONFIGS = Path(__file__).resolve().parents[2] / "configs"
CC = shutil.which("cc")


def _config_env(name: str, **override) -> dict:
    env = dict(yaml.safe_load((CONFIGS / name).read_text())["env"])
    env.update(override)
    return env


CASES = {
    "epuck": ("swarm_envs/Aggregation-v0", _config_env("aggregation.yaml")),
    "rone": ("swarm_envs/SortedFollowing-v0", _config_env("sorted_following.yaml")),
    # the Droplet with messages and ids, so those parts carry data on a range & bearing platform, and few rows,
    # so tables often hold more entries than rows (truncation)
    "droplet": (
        "swarm_envs/Aggregation-v0",
        _config_env("aggregation.yaml", platform="droplet", message_bits=2, observe_ids=True, n_neighbours=3, n_messages=2),
    ),
}


def _compile(paths: list[Path], out: Path) -> ctypes.CDLL:
    lib = out / "libobservation.so"
    cmd = [CC, "-std=c99", "-Wall", "-Wextra", "-pedantic", "-Werror", "-O2", "-shared", "-fPIC", "-o", str(lib), str(paths[1]), "-lm"]
    done = subprocess.run(cmd, capture_output=True, text=True)
    assert done.returncode == 0, f"{' '.join(cmd)} failed:\n{done.stderr}"
    return ctypes.CDLL(str(lib))


def _ctypes_tables(c: dict) -> type[ctypes.Structure]:
    """The ctypes mirror of observation.h's obs_tables_t for constants ``c``."""

    class Neighbour(ctypes.Structure):
        _fields_ = [("id", ctypes.c_uint16), ("range_m", ctypes.c_float), ("bearing_rad", ctypes.c_float),
                    ("heading_rad", ctypes.c_float), ("age_steps", ctypes.c_uint16)]  # fmt: skip

    class NeighbourTable(ctypes.Structure):
        _fields_ = [("count", ctypes.c_uint16), ("entry", Neighbour * c["neighbour_capacity"])]

    class Message(ctypes.Structure):
        _fields_ = [("sender_id", ctypes.c_uint16), ("detector", ctypes.c_uint8), ("n_bits", ctypes.c_uint8),
                    ("payload", ctypes.c_uint8 * max(c["message_bits"], 1))]  # fmt: skip

    class MessageBuffer(ctypes.Structure):
        _fields_ = [("count", ctypes.c_uint16), ("entry", Message * c["message_capacity"])]

    class ScaleFreeEntry(ctypes.Structure):
        _fields_ = [("id", ctypes.c_uint16), ("x", ctypes.c_float), ("y", ctypes.c_float)]

    class ScaleFreeTable(ctypes.Structure):
        _fields_ = [("rigid", ctypes.c_uint8), ("count", ctypes.c_uint16), ("entry", ScaleFreeEntry * c["scale_free_capacity"])]

    class Tables(ctypes.Structure):
        _fields_ = [("own_id", ctypes.c_uint16), ("bump", ctypes.c_uint8 * 8), ("last_action", ctypes.c_float * c["action_size"]),
                    ("neighbours", NeighbourTable), ("messages", MessageBuffer), ("scale_free", ScaleFreeTable)]  # fmt: skip

    return Tables


def _fill(Tables: type[ctypes.Structure], tab: dict) -> ctypes.Structure:
    t = Tables()
    t.own_id = tab["own_id"]
    t.bump[:] = tab["bump"]
    t.last_action[:] = [float(v) for v in tab["last_action"]]
    assert len(tab["neighbours"]) <= len(t.neighbours.entry)
    t.neighbours.count = len(tab["neighbours"])
    for e, r in zip(t.neighbours.entry, tab["neighbours"]):
        e.id, e.range_m, e.bearing_rad, e.heading_rad, e.age_steps = r["id"], r["range"], r["bearing"], r["heading"], r["age"]
    t.messages.count = len(tab["messages"])
    for e, m in zip(t.messages.entry, tab["messages"]):
        e.sender_id, e.detector, e.n_bits = m["sender"], m["detector"], m["n_bits"]
        for i, bit in enumerate(m["payload"]):
            e.payload[i] = bit
    sf = tab["scale_free"]
    assert len(sf["entries"]) <= len(t.scale_free.entry)
    t.scale_free.rigid, t.scale_free.count = int(sf["rigid"]), len(sf["entries"])
    for e, s in zip(t.scale_free.entry, sf["entries"]):
        e.id, e.x, e.y = s["id"], s["x"], s["y"]
    return t


@pytest.fixture(scope="module", params=sorted(CASES))
def built(request, tmp_path_factory):
    if CC is None:
        pytest.skip("no C compiler (`cc`) on PATH to build the generated observation.c")
    env_id, kwargs = CASES[request.param]
    out = tmp_path_factory.mktemp(f"obs_{request.param}")
    paths = write_observation_builder(env_id, kwargs, out)
    lib = _compile(paths, out)
    lib.obs_build.restype = None
    lib.obs_rank_rows.restype = ctypes.c_int
    return request.param, env_id, kwargs, lib


def test_generated_files_are_c99_and_documented(built, tmp_path):
    """The header names every struct field with a comment, and the files compile as strict C99 (in the fixture)."""
    name, env_id, kwargs, _ = built
    paths = write_observation_builder(env_id, kwargs, tmp_path)
    assert [p.name for p in paths] == ["observation.h", "observation.c"]
    header = paths[0].read_text()
    for field in ("range_m", "bearing_rad", "heading_rad", "age_steps", "sender_id", "detector", "n_bits", "payload", "rigid",
                  "last_action", "bump", "own_id"):  # fmt: skip
        line = next(line for line in header.splitlines() if f" {field}" in line and ";" in line)
        assert "/*" in line, f"{field} is not documented: {line}"
    source = paths[1].read_text()
    assert "malloc" not in source and "#include <stdlib.h>" not in source


def test_c_vector_equals_env_observation(built):
    """For every agent over two episodes of random actions, obs_build on the firmware tables equals the env's
    flattened observation to 1e-5 per component; every part carries data, empty rows occur and (Droplet
    case) neighbour tables hold more entries than rows. (In these runs a scale-free table holds at most one
    entry and a robot decodes at most one message per step: the synthetic test below covers full tables.)"""
    name, env_id, kwargs, lib = built
    env = make(env_id, **kwargs)
    c = builder_constants(env)
    Tables = _ctypes_tables(c)
    space = env.layout.dict_space()
    rng = np.random.default_rng(7)
    out = (ctypes.c_float * c["size"])()
    seen = np.zeros(c["size"], bool)  # components that were non-zero at least once
    empty_rows = {"range_bearing": 0, "scale_free": 0}
    truncated = 0
    compared = 0
    steps = {"epuck": 30, "rone": 60, "droplet": 30}[name]  # the r-one's readings change once per 24-step round
    for seed in (3, 11):
        obs, _ = env.reset(seed=seed)
        for step in range(steps):
            if step:
                actions = {a: rng.uniform(-1, 1, env.action_space(a).shape).astype(np.float32) for a in env.agents}
                obs, *_ = env.step(actions)
            for agent in env.agents:
                want = spaces.flatten(space, obs[agent]).astype(np.float32)
                tab = firmware_tables(env, agent)
                lib.obs_build(ctypes.byref(_fill(Tables, tab)), out)
                got = np.frombuffer(out, np.float32).copy()
                assert got.shape == want.shape
                bad = ~np.isclose(got, want, rtol=0.0, atol=1e-5, equal_nan=True)
                if bad.any():
                    parts = env.layout.unflatten(np.arange(c["size"]))
                    where = [p for p, idx in parts.items() if bad[np.asarray(idx).reshape(-1)].any()]
                    pytest.fail(f"{name} seed {seed} step {step} {agent}: C differs in {where}: "
                                f"C {got[bad][:6]} vs env {want[bad][:6]}")  # fmt: skip
                seen |= want != 0
                parts = env.layout.unflatten(want)
                for part in empty_rows:
                    empty_rows[part] += int((parts[part][:, 0] == 0).sum())
                truncated += len(tab["neighbours"]) > c["K"]
                compared += 1
    env.close()
    assert compared >= 2 * steps * env.n_agents
    by_part = env.layout.unflatten(seen)
    for part, mask in by_part.items():
        if part == "messages" and c["message_bits"] == 0:
            assert not mask.any()  # no payload bits: the part is all zero
            continue
        assert mask.any(), f"{name}: part {part} was zero throughout, so the comparison does not cover it"
    assert all(v > 0 for v in empty_rows.values()), empty_rows
    if name != "droplet":  # (Droplets at 2 cm/s seldom touch in these few steps)
        assert by_part["proprio"][:8].any(), "no bump flag was set: the comparison does not cover them"
    if name == "droplet":  # K = 3 rows: the range & bearing ranking's truncation is exercised
        assert truncated > 0


def test_rank_rows_matches_the_simulators_selection(built):
    """obs_rank_rows (the C's one ranking function) picks the same rows in the same order as
    swarm_envs.sensing.observation.nearest_slots, with ties and NaN keys."""
    _, _, _, lib = built
    rng = np.random.default_rng(0)
    for n in (0, 1, 5, 8, 13, 30):
        for k in (1, 3, 8):
            key = rng.integers(0, 6, n).astype(np.float64)  # many ties
            key[rng.random(n) < 0.2] = np.nan
            order = (ctypes.c_int * k)()
            filled = lib.obs_rank_rows(key.ctypes.data_as(ctypes.POINTER(ctypes.c_double)), n, k, order)
            want = nearest_slots(1, np.zeros(n, np.int64), key, k)[0]
            assert list(order) == want.tolist()
            assert filled == int((want >= 0).sum())


def test_full_synthetic_tables_match_the_simulators_packing(built):
    """Tables fuller than the rows (more neighbours and scale-free entries than K, M messages, ties, values
    outside the Box, stale readings and malformed messages): the C vector equals what the simulator's own packing gives for the same readings
    (the observation builder of swarm_envs.core on a sensor frame holding them, and FullSensing's
    scale-free ranking), so truncation and clipping are covered whatever the random runs reached."""
    from swarm_envs.sensing.observation import pack_nearest
    from swarm_envs.sensing.base import MessageReadings, NeighbourReadings, ScaleFreeReadings, SensorFrame

    name, env_id, kwargs, lib = built
    env = make(env_id, **kwargs)
    env.reset(seed=0)
    c = builder_constants(env)
    Tables = _ctypes_tables(c)
    space = env.layout.dict_space()
    rng = np.random.default_rng(5)
    n_world, N, K, b = env.n_world, env.core.n_total, c["K"], c["message_bits"]
    out = (ctypes.c_float * c["size"])()
    for trial in range(20):
        agent = env.possible_agents[trial % len(env.possible_agents)]
        row = int(env.agent_robots[env.possible_agents.index(agent)])
        others = np.setdiff1d(np.arange(n_world), [row])
        ids = np.sort(rng.choice(others, size=rng.integers(0, len(others) + 1), replace=False))
        # ranges beyond the Box on both sides and equal ranges (ties); 0 on the r-one (no range)
        rng_range = rng.uniform(-0.01, 1.2 * env.platform.ir_range, ids.size) if c["has_range"] else np.zeros(ids.size)
        rng_range[1::3] = rng_range[0] if ids.size else 0.0
        bearing, heading = rng.uniform(-np.pi, np.pi, (2, ids.size))
        age = rng.integers(0, c["max_age"] + 1, ids.size)
        n_msg = int(rng.integers(0, c["M"] + 1)) if b else 0  # (the firmware's buffer keeps the first M)
        sender = rng.integers(0, n_world, n_msg)
        detector = rng.integers(0, len(c["detector_bearing"]), n_msg)
        payload = rng.integers(0, 2, (n_msg, b))
        n_sf = int(rng.integers(0, min(c["scale_free_capacity"], n_world + 4) + 1))
        sf_ids = rng.integers(0, n_world, n_sf)
        sf_xy = rng.normal(0.0, 4.0, (n_sf, 2))
        sf_xy[: n_sf // 3] = sf_xy[0] if n_sf else sf_xy[: n_sf // 3]  # equal distances: ties
        rigid = bool(rng.integers(0, 2))
        bumps = rng.integers(0, 2, 8)
        action = rng.uniform(-1, 1, c["action_size"])

        # the simulator's packing of these readings
        neighbours = NeighbourReadings(np.full(ids.size, row), ids.astype(np.int64), rng_range, bearing, heading, age.astype(float))
        if not c["has_range"]:  # ranked by age, equal ages by the tie draw: here the table order, as the C breaks ties
            neighbours.slots = ranked_slots(N, neighbours.rx, neighbours.age, np.arange(ids.size, dtype=float), K)
            neighbours.rows = range_bearing_rows(neighbours.slots, rng_range, bearing, heading, neighbours.age)
        messages = MessageReadings(np.full(n_msg, row), sender.astype(np.int64), c["detector_bearing"][detector], payload.astype(float))
        packed, order = pack_nearest(N, np.full(n_sf, row), np.hypot(sf_xy[:, 0], sf_xy[:, 1]), sf_xy, K)
        sf_row_ids = np.where(order >= 0, np.r_[sf_ids, -1][np.where(order >= 0, order, n_sf)], -1)
        valid = order >= 0
        rigid_all = np.zeros(N, bool)
        rigid_all[row] = rigid
        env.core.frame = SensorFrame(neighbours, messages, ScaleFreeReadings(packed, valid, rigid_all, sf_row_ids), {})
        env.core.bumps = np.zeros((N, 8), bool)
        env.core.bumps[row] = bumps.astype(bool)
        env.core.last_actions[row] = action
        want = spaces.flatten(space, {k: v[row] for k, v in env.core.observations().items()}).astype(np.float32)

        tab = {
            "own_id": row % n_world, "bump": bumps.tolist(), "last_action": action.astype(np.float32),
            "neighbours": [{"id": int(i), "range": float(r), "bearing": float(br), "heading": float(h), "age": int(a)}
                           for i, r, br, h, a in zip(ids, rng_range, bearing, heading, age)],
            "messages": [{"sender": int(s_), "detector": int(d), "n_bits": b, "payload": p.tolist()} for s_, d, p in zip(sender, detector, payload)],
            "scale_free": {"rigid": rigid, "entries": [{"id": int(i), "x": float(x), "y": float(y)} for i, (x, y) in zip(sf_ids, sf_xy)]},
        }  # fmt: skip
        # entries the simulator never holds, which the C leaves out: a reading older than max_age (the
        # simulator drops it), a message whose length or sender is not this swarm's (dropped on receipt)
        spare = np.setdiff1d(others, ids)
        if spare.size and len(tab["neighbours"]) < c["neighbour_capacity"]:
            tab["neighbours"].insert(int(rng.integers(0, len(tab["neighbours"]) + 1)),
                                     {"id": int(spare[0]), "range": 0.0, "bearing": 0.0, "heading": 0.0, "age": c["max_age"] + 1})  # fmt: skip
        if b and len(tab["messages"]) < c["message_capacity"]:
            bad = {"sender": n_world, "detector": 0, "n_bits": b, "payload": [1] * b} if trial % 2 else {"sender": 0, "detector": 0, "n_bits": b + 1, "payload": [1] * b}
            tab["messages"].insert(int(rng.integers(0, len(tab["messages"]) + 1)), bad)
        lib.obs_build(ctypes.byref(_fill(Tables, tab)), out)
        got = np.frombuffer(out, np.float32)
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-5, err_msg=f"{name} trial {trial}")
    env.close()


def test_only_full_sensing_is_exported(tmp_path):
    """The builder reproduces the modelled stack; the ideal ablation (true values) has no firmware tables."""
    with pytest.raises(ValueError, match="sensing='full'"):
        write_observation_builder("swarm_envs/Aggregation-v0", {"n_robots": 3, "sensing": "ideal"}, tmp_path)
    assert not (tmp_path / "observation.c").exists()
