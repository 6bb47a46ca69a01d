"""observe_ids=True: the robot's own id and, per observation row, the id its sensing stack decoded."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from gymnasium import spaces

import swarm_envs
from swarm_envs.comm.network import Network
from swarm_envs.sensing.observation import ID_FIELDS, ObservationLayout, id_rows, nearest_slots, own_id_rows, pack_nearest
from swarm_envs.sensing.range_bearing import RangeBearingSensor

ENV = "swarm_envs/Aggregation-v0"
ID_KEYS = {"own_id", "range_bearing_ids", "message_ids", "scale_free_ids"}


def _agents(env, obs, key):
    return np.stack([obs[a][key] for a in env.possible_agents])


def _decoded(index, rows, n_world):
    """Ids of slots (n, r) of readings ``rows`` (global robot rows), -1 where a slot is empty."""
    return np.where(index >= 0, rows[np.maximum(index, 0)] % n_world if len(rows) else -1, -1)


def _expected_ids(env):
    """Per robot (all rows of the copy): the decoded ids of its observation rows, read from the sensing frame."""
    frame, k, m = env.core.frame, env.layout.n_neighbours, env.layout.n_messages
    n = env.n_world
    nb, msg = frame.neighbours, frame.messages
    slots = nb.slots if nb.slots is not None and nb.slots.shape == (n, k) else nearest_slots(n, nb.rx, nb.range, k)
    key = msg.distance_hint if msg.distance_hint is not None else np.arange(len(msg.receiver), dtype=float)
    message_slots = pack_nearest(n, msg.receiver, key, np.zeros((len(msg.receiver), 1)), m)[1] if len(msg.receiver) else np.full((n, m), -1)
    sf = frame.scale_free.ids
    return _decoded(slots, nb.tx, n), _decoded(message_slots, msg.sender, n), np.where(sf >= 0, sf % n, -1)


# -- layout and spaces ------------------------------------------------------------------------------------
def test_id_rows_encoding():
    ids = np.array([[-1, 0, 3, 4]])
    rows = id_rows(ids, np.array([3]), n_world=5)
    np.testing.assert_array_equal(rows[0, 0], [0, 0, 0, 0])  # nothing decoded: an all-zero row
    np.testing.assert_array_equal(rows[0, 1], [1, 0.0, 1, 0])  # id 0 < 3, other parity
    np.testing.assert_array_equal(rows[0, 2], np.float32([1, 0.75, 0, 1]))  # the robot's own id (a wrong decode)
    np.testing.assert_array_equal(rows[0, 3], np.float32([1, 1.0, 0, 0]))
    np.testing.assert_array_equal(own_id_rows(np.array([0, 3, 4]), 5), np.float32([[0, 0], [0.75, 1], [1, 0]]))
    # a single robot: no division by zero
    assert np.isfinite(own_id_rows(np.array([0]), 1)).all()
    # the scaled id gives the id back exactly in float32 (n_world up to 2**24)
    n = 10_000
    scaled = id_rows(np.arange(n)[None], np.array([0]), n)[0, :, 1]
    np.testing.assert_array_equal(np.rint(scaled.astype(np.float64) * (n - 1)).astype(int), np.arange(n))


def test_id_parts_are_in_the_space_only_when_asked():
    plain = swarm_envs.make(ENV, n_robots=4, sensing="ideal")
    assert set(plain.observation_space("robot_0").spaces) == {"range_bearing", "messages", "scale_free", "rigid", "proprio"}
    env = swarm_envs.make(ENV, n_robots=4, sensing="ideal", observe_ids=True, n_neighbours=5, n_messages=3, message_bits=2)
    space = env.observation_space("robot_0")
    assert set(space.spaces) == set(plain.observation_space("robot_0").spaces) | ID_KEYS
    assert list(space.spaces) == sorted(space.spaces)
    assert space["own_id"].shape == (2,)
    assert space["range_bearing_ids"].shape == (5, len(ID_FIELDS)) and space["scale_free_ids"].shape == (5, 4)
    assert space["message_ids"].shape == (3, 4)
    obs, _ = env.reset(seed=0)
    for _ in range(5):
        obs, *_ = env.step({a: np.ones(4, np.float32) for a in env.agents})
    for agent in env.agents:
        assert space.contains(obs[agent])
    with pytest.raises(ValueError, match="observe_ids must be True or False"):
        swarm_envs.make(ENV, observe_ids=1)


def test_flatten_puts_the_id_parts_in_the_dicts_order():
    kwargs = dict(n_robots=5, sensing="full", observe_ids=True, message_bits=2, platform="rone")
    named, flat = swarm_envs.make(ENV, **kwargs), swarm_envs.make(ENV, flatten=True, **kwargs)
    obs_named, _ = named.reset(seed=3)
    obs_flat, _ = flat.reset(seed=3)
    actions = np.random.default_rng(0).uniform(-1, 1, (20, 5, 4))
    for t in range(20):
        obs_named, *_ = named.step({a: actions[t, i] for i, a in enumerate(named.agents)})
        obs_flat, *_ = flat.step({a: actions[t, i] for i, a in enumerate(flat.agents)})
    dict_space = named.observation_space("robot_0")
    for agent in named.agents:
        np.testing.assert_array_equal(obs_flat[agent], spaces.flatten(dict_space, obs_named[agent]))
        parts = flat.layout.unflatten(obs_flat[agent])
        for key in ID_KEYS:
            np.testing.assert_array_equal(parts[key], obs_named[agent][key])
    # the vector env flattens in the same order
    vec = swarm_envs.make_vec(ENV, 1, flatten=True, **kwargs)
    v_obs, _ = vec.reset(seed=3)
    for t in range(20):
        v_obs, *_ = vec.step(actions[t][None])
    np.testing.assert_array_equal(v_obs[0], np.stack([obs_flat[a] for a in flat.possible_agents]))


def test_layout_without_ids_is_unchanged():
    layout = ObservationLayout(n_neighbours=3, n_messages=2, message_bits=1)
    assert set(layout.dict_space().spaces) == {"range_bearing", "messages", "scale_free", "rigid", "proprio"}


# -- the ids are the decoded ones -------------------------------------------------------------------------
@pytest.mark.parametrize("platform", ["epuck", "droplet", "rone"])
@pytest.mark.parametrize("sensing", ["full", "ideal"])
def test_ids_equal_the_ids_the_sensing_frame_decoded(platform, sensing):
    env = swarm_envs.make(ENV, n_robots=10, platform=platform, sensing=sensing, observe_ids=True, message_bits=2)
    obs, _ = env.reset(seed=5)
    rng = np.random.default_rng(1)
    seen = {"range_bearing_ids": 0, "message_ids": 0, "scale_free_ids": 0}
    for t in range(40):
        obs, *_ = env.step({a: rng.uniform(-1, 1, 4) for a in env.agents})
        own = np.arange(env.n_world)
        np.testing.assert_array_equal(_agents(env, obs, "own_id"), own_id_rows(own, env.n_world))
        for key, ids in zip(("range_bearing_ids", "message_ids", "scale_free_ids"), _expected_ids(env)):
            got = _agents(env, obs, key)
            np.testing.assert_array_equal(got, id_rows(ids, own, env.n_world), err_msg=f"{key} step {t}")
            seen[key] += int((ids >= 0).sum())
        # a row has an id exactly where it is valid
        np.testing.assert_array_equal(_agents(env, obs, "range_bearing_ids")[..., 0], _agents(env, obs, "range_bearing")[..., 0])
        np.testing.assert_array_equal(_agents(env, obs, "message_ids")[..., 0], _agents(env, obs, "messages")[..., 0])
    assert seen["range_bearing_ids"] > 0 and seen["message_ids"] > 0
    if sensing == "ideal":  # the ablation: true ids
        pos = env.world.positions
        rb = _agents(env, obs, "range_bearing")
        ids = np.rint(_agents(env, obs, "range_bearing_ids")[..., 1] * (env.n_world - 1)).astype(int)
        valid = rb[..., 0] > 0.5
        rows, slots = np.nonzero(valid)
        true_range = np.linalg.norm(pos[ids[rows, slots]] - pos[rows], axis=1)
        np.testing.assert_allclose(rb[rows, slots, 1], true_range, rtol=1e-6)


def _derangement(n_world):
    """A permutation of a copy's ids without fixed points (every id maps to another robot's)."""
    return (np.arange(n_world) + 1) % n_world


def test_a_misdecoded_range_bearing_id_shows_as_decoded_never_as_the_true_one(monkeypatch):
    """Force every R&B request to decode to another robot's id: the observation names the decoded robot."""
    original = RangeBearingSensor.step
    n_world = 8
    sigma = _derangement(n_world)
    record = {}

    def misdecoding_step(self, links, *args, **kwargs):
        readings = original(self, links, *args, **kwargs)
        base = (readings.tx // n_world) * n_world
        wrong = base + sigma[readings.tx % n_world]
        keep = wrong != readings.rx  # a receiver rejects its own id
        record["true"], record["wrong"], record["rx"] = readings.tx[keep], wrong[keep], readings.rx[keep]
        return dataclasses.replace(
            readings, rx=readings.rx[keep], tx=wrong[keep], range=readings.range[keep], bearing=readings.bearing[keep],
            heading=readings.heading[keep], age=readings.age[keep],
            true_tx=None if readings.true_tx is None else readings.true_tx[keep],
            n_overlap=None if readings.n_overlap is None else readings.n_overlap[keep],
        )

    monkeypatch.setattr(RangeBearingSensor, "step", misdecoding_step)
    env = swarm_envs.make(ENV, n_robots=n_world, platform="epuck", sensing="full", observe_ids=True)
    obs, _ = env.reset(seed=2)
    shown = 0
    for _ in range(20):
        obs, *_ = env.step({a: np.array([0.2, 0.3]) for a in env.agents})
        ids = np.rint(_agents(env, obs, "range_bearing_ids")[..., 1] * (n_world - 1)).astype(int)
        valid = _agents(env, obs, "range_bearing_ids")[..., 0] > 0.5
        for r, s in zip(*np.nonzero(valid)):
            heard_as = record["wrong"][record["rx"] == r] % n_world
            truly = record["true"][record["rx"] == r] % n_world
            assert ids[r, s] in heard_as
            shown += 1
            # the robot named is never the true transmitter of that reading (sigma has no fixed point)
            assert ids[r, s] != truly[np.flatnonzero(heard_as == ids[r, s])[0]]
    assert shown > 20


@pytest.mark.parametrize("platform", ["rone", "epuck"])
def test_a_corrupted_swarmcom_header_shows_the_wrong_sender(monkeypatch, platform):
    """Force every SwarmCom header to decode to another robot's id: message ids (and, on the r-one, the
    sector readings named by the header) show the decoded id, never the transmitter's."""
    original = Network.step
    n_world = 7
    sigma = _derangement(n_world)
    record = {"rx": [], "wrong": [], "true": []}

    def corrupting_step(self, links, prepared=None, threads=1):
        d = original(self, links, prepared, threads)
        base = (d.origin // n_world) * n_world
        wrong = base + sigma[d.origin % n_world]
        app = d.kind == "app"
        record["rx"].append(d.receiver[app])
        record["wrong"].append(wrong[app] % n_world)
        record["true"].append(d.origin[app] % n_world)
        return dataclasses.replace(d, origin=wrong, sender=wrong)

    monkeypatch.setattr(Network, "step", corrupting_step)
    env = swarm_envs.make(ENV, n_robots=n_world, platform=platform, sensing="full", observe_ids=True, message_bits=2)
    obs, _ = env.reset(seed=4)
    counted = 0
    for _ in range(60):
        for key in record:
            record[key].clear()
        obs, *_ = env.step({a: np.array([0.0, 0.0, 1.0, -1.0]) for a in env.agents})
        rx, wrong, true = (np.concatenate(record[k]) if record[k] else np.zeros(0, int) for k in ("rx", "wrong", "true"))
        m_ids = _agents(env, obs, "message_ids")
        for r, s in zip(*np.nonzero(m_ids[..., 0] > 0.5)):
            shown = int(np.rint(m_ids[r, s, 1] * (n_world - 1)))
            assert shown in wrong[rx == r]
            assert shown not in true[(rx == r) & (wrong == shown)]
            counted += 1
        if platform == "rone":  # sector readings are named by the header they were measured on
            assert np.array_equal(_expected_ids(env)[0], np.where(
                _agents(env, obs, "range_bearing_ids")[..., 0] > 0.5,
                np.rint(_agents(env, obs, "range_bearing_ids")[..., 1] * (n_world - 1)).astype(int), -1))
    assert counted > 10


@pytest.mark.parametrize("sensing", ["full", "ideal"])
@pytest.mark.parametrize("platform", ["epuck", "rone"])
def test_copies_with_ids_equal_single_envs(sensing, platform):
    seeds, steps = [3, 8], 40
    kwargs = dict(n_robots=5, sensing=sensing, platform=platform, observe_ids=True, message_bits=2, max_cycles=steps)
    vec = swarm_envs.make_vec(ENV, len(seeds), **kwargs)
    actions = np.random.default_rng(0).uniform(-1, 1, (steps, len(seeds), 5, 4))
    v_obs, _ = vec.reset(seed=seeds)
    history = []
    for t in range(steps):
        v_obs, *_ = vec.step(actions[t])
        history.append({k: v.copy() for k, v in v_obs.items()})
    for b, seed in enumerate(seeds):
        env = swarm_envs.make(ENV, **kwargs)
        env.reset(seed=seed)
        for t in range(steps):
            obs, *_ = env.step({a: actions[t, b, i] for i, a in enumerate(env.possible_agents)})
            for key in ID_KEYS:
                np.testing.assert_array_equal(history[t][key][b], _agents(env, obs, key), err_msg=f"{key} copy {b} step {t}")
