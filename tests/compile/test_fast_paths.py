"""The fast per-step paths (ideal sensing, observations, task rewards and metrics) equal straightforward
numpy formulas, bit for bit: the ``_plain_*`` functions below (KD-tree pairs + argsort, ``np.add.at``,
``np.mod`` wrapping, packing of every link, ``np.clip``) and :mod:`swarm_envs._compile.reference`.
"""

from __future__ import annotations

import numpy as np
import pytest

import swarm_envs
from swarm_envs.sensing import observation
from swarm_envs._compile import reference
from swarm_envs.sim.geometry import wrap_angle
from swarm_envs.sensing.observation import nearest_slots, wrapped_difference
from swarm_envs.sensing import ideal
from swarm_envs.tasks.task import MESSAGE_RANGE
from swarm_envs.sensing.ideal import candidate_pairs, copy_pairs, directed_links, directed_pairs
from swarm_envs.tasks.task import bump_any


def _equal(a, b, what=""):
    """Same values (NaN where NaN) and the same dtype and shape."""
    a, b = np.asarray(a), np.asarray(b)
    assert a.dtype == b.dtype and a.shape == b.shape, what
    np.testing.assert_array_equal(a, b, err_msg=what)


# -- the plain reference implementations -----------------------------------------------------------------
def _plain_relative_pose(positions, headings, rx, tx):
    delta = positions[tx] - positions[rx]
    distance = np.hypot(delta[:, 0], delta[:, 1])
    bearing = np.arctan2(delta[:, 1], delta[:, 0]) - headings[rx]
    heading = headings[tx] - headings[rx]
    return distance, wrap_angle(bearing), wrap_angle(heading)


def _plain_ideal_step(sensing, positions, headings):
    """IdealSensing.step without messages, plain reference: KD-tree pairs, every link packed."""
    copy = sensing.copy if sensing.n_copies > 1 else None
    rx, tx = directed_pairs(candidate_pairs(positions, sensing.platform.ir_range, copy))
    distance, bearing, heading = _plain_relative_pose(positions, headings, rx, tx)
    n = sensing.n
    mean_distance = np.bincount(rx, distance, n) / np.maximum(np.bincount(rx, minlength=n), 1)
    scale = np.where(mean_distance > 0, mean_distance, 1.0)[rx]
    local = np.stack([distance * np.cos(bearing), distance * np.sin(bearing)], -1) / scale[:, None]
    packed, order = reference.pack_nearest(n, rx, distance, local, sensing.k)
    valid = order >= 0
    return (rx, tx, distance, bearing, heading), (packed, valid, valid.any(axis=1))


def _plain_observations(core):
    """SwarmCore.observations, plain reference: every link's values stacked and packed, then np.clip."""
    frame = core.frame
    n, k, m, b = core.n_total, core.layout.n_neighbours, core.layout.n_messages, core.layout.message_bits
    nb = frame.neighbours
    rb_values = (
        np.stack(
            [np.ones(len(nb.rx)), nb.range, np.cos(nb.bearing), np.sin(nb.bearing), np.cos(nb.heading), np.sin(nb.heading), nb.age],
            axis=-1,
        )
        if len(nb.rx)
        else np.zeros((0, 7))
    )
    range_bearing, _ = reference.pack_nearest(n, nb.rx, nb.range, rb_values, k)
    msg = frame.messages
    if len(msg.receiver):
        key = msg.distance_hint if msg.distance_hint is not None else np.arange(len(msg.receiver), dtype=float)
        msg_values = np.concatenate(
            [np.ones((len(msg.receiver), 1)), msg.bearing[:, None] / np.pi, msg.payload.reshape(len(msg.receiver), b)], axis=1
        )
        messages, _ = reference.pack_nearest(n, msg.receiver, key, msg_values, m)
    else:
        messages = np.zeros((n, m, 2 + b))
    sf = frame.scale_free
    scale_free = np.concatenate([sf.valid[..., None].astype(float), np.where(sf.valid[..., None], sf.xy, 0.0)], axis=-1)
    proprio = np.concatenate([core.bumps.astype(float), core.last_actions], axis=1)
    parts = {"range_bearing": range_bearing, "messages": messages, "scale_free": scale_free, "rigid": sf.rigid.astype(float).reshape(-1, 1), "proprio": proprio}
    return {name: np.clip(np.asarray(parts[name], np.float32), box.low, box.high) for name, box in core.layout.dict_space().spaces.items()}


def _plain_flocking_rewards(task, state):
    """The flocking rewards written plainly (per copy, a KD-tree's pairs, ``np.add.at``)."""
    B, A = task.n_copies, task.n_agents
    pos, head = task.agents_of(state.positions), task.agents_of(state.headings)
    speed = np.linalg.norm(task.agents_of(state.velocities), axis=2)
    vmax, link = task.platform.max_speed, MESSAGE_RANGE[task.platform.name]
    pairs = candidate_pairs(pos.reshape(B * A, 2), link, np.repeat(np.arange(B), A))
    # cohesion: the mean share of the other robots within the message range (a KD-tree's pairs, counted per copy)
    cohesion = np.array([2.0 * np.sum(pairs[:, 0] // A == b) / (A * (A - 1)) for b in range(B)]) if A > 1 else np.ones(B)
    weight = np.clip(speed / vmax, 0.0, 1.0)
    vec = np.stack([np.cos(head), np.sin(head)], -1) * weight[..., None]
    pol = np.linalg.norm(vec.mean(axis=1), axis=1)
    bumped = bump_any(task.agents_of(state.bumps)).astype(float)
    rx, tx = np.concatenate([pairs[:, 0], pairs[:, 1]]), np.concatenate([pairs[:, 1], pairs[:, 0]])
    order = np.argsort(rx * (B * A) + tx)
    rx, tx = rx[order], tx[order]
    flat = vec.reshape(B * A, 2)
    sums = flat.copy()
    np.add.at(sums, rx, flat[tx])
    counts = 1 + np.bincount(rx, minlength=B * A)
    local_pol = np.linalg.norm(sums / counts[:, None], axis=1).reshape(B, A)
    global_reward = pol * cohesion - task.penalty * bumped.mean(axis=1)
    local_reward = local_pol * cohesion[:, None] - task.penalty * bumped
    rewards = np.repeat(global_reward[:, None], A, axis=1) if task.reward_mode == "global" else local_reward
    terms = {
        "polarisation": np.repeat(pol[:, None], A, axis=1),
        "local_polarisation": local_pol,
        "cohesion": np.repeat(cohesion[:, None], A, axis=1),
        "collision": bumped,
    }
    metrics = {"polarisation": pol, "cohesion": cohesion, "collision_fraction": bumped.mean(axis=1)}
    return rewards, terms, metrics


# -- building blocks -------------------------------------------------------------------------------------
@pytest.mark.parametrize("copies,size,spread,r", [(7, 10, 1.0, 0.5), (1, 300, 4.0, 0.6), (3, 40, 0.3, 1.0), (1, 1500, 8.0, 0.7), (4, 1, 1.0, 1.0), (2, 100, 100.0, 0.05)])
def test_copy_pairs_equal_kd_tree_pairs(copies, size, spread, r):
    rng = np.random.default_rng(size)
    pos = rng.uniform(0, spread, (copies * size, 2))
    if len(pos) > 4:  # exact coincidences and pairs at exactly the range (a binary fraction: exact squares)
        pos[1] = pos[0]
        pos[3] = pos[2] + [0.5, 0.0]
    got = copy_pairs(pos, r, size)
    ref = candidate_pairs(pos, r, np.repeat(np.arange(copies), size) if copies > 1 else None)
    _equal(got, ref)
    rx, tx, link = directed_links(got, len(pos))
    ref_rx, ref_tx = directed_pairs(ref)
    _equal(rx, ref_rx)
    _equal(tx, ref_tx)
    np.testing.assert_array_equal(np.sort(got[link], axis=1), np.sort(np.c_[rx, tx], axis=1))
    with pytest.raises(ValueError, match="whole copies"):
        copy_pairs(np.zeros((7, 2)), r, 2)


@pytest.mark.parametrize("spread,r", [(1.0, 0.3), (1.0, 5.0), (100.0, 0.05), (3.0, 0.2)])
def test_copy_pairs_grid_branch(monkeypatch, spread, r):
    """The cell grid (copies above BRUTE_FORCE_MAX; one cell, capped cells)."""
    rng = np.random.default_rng(3)
    pos = rng.uniform(0, spread, (240, 2))
    pos[40:60] = pos[40] + rng.normal(0, r / 3, (20, 2))  # a dense clump in every case
    ref = candidate_pairs(pos, r, np.repeat(np.arange(3), 80))
    assert len(ref) > 0
    monkeypatch.setattr(ideal, "BRUTE_FORCE_MAX", 5)
    _equal(copy_pairs(pos, r, 80), ref)


def test_directed_links_equal_the_reference():
    rng = np.random.default_rng(4)
    pairs = candidate_pairs(rng.uniform(0, 1, (80, 2)), 0.3)
    got = directed_links(pairs, 80)
    ref = reference.directed_links(pairs, 80)
    for a, b in zip(got, ref):
        _equal(a, b)


def test_wrapped_difference_equals_wrap_angle_bit_for_bit():
    rng = np.random.default_rng(5)
    special = np.array([0.0, -0.0, np.pi, -np.pi, 2 * np.pi, -2 * np.pi, 3 * np.pi, -3 * np.pi, np.nan, np.inf, -np.inf, 1e300, 5e-324])
    a = np.concatenate([rng.uniform(-np.pi, np.pi, 50_000), rng.uniform(-40, 40, 50_000), special, np.nextafter(special[:8], 1)])
    b = np.concatenate([rng.uniform(-np.pi, np.pi, 100_000), np.zeros(len(special)), np.zeros(8)])
    b[::5] = 0.0
    got = wrapped_difference(a, b)
    with np.errstate(invalid="ignore"):
        ref = wrap_angle(a - b)
    _equal(got, ref)
    np.testing.assert_array_equal(np.signbit(got), np.signbit(ref))


def test_clip_to_box_equals_numpy_clip():
    rng = np.random.default_rng(6)
    v = rng.normal(0, 2, (3000, 4, 3))
    for value, share in [(0.0, 0.1), (-0.0, 0.1), (np.nan, 0.05), (1.0, 0.05), (-1.0, 0.05), (np.inf, 0.02), (-np.inf, 0.02)]:
        v[rng.uniform(size=v.shape) < share] = value
    low = np.tile(np.array([0, -1, -0.5], np.float32), (4, 1))
    high = np.tile(np.array([1, 1, 0.0], np.float32), (4, 1))
    got, ref = observation._clip_to_box(v, low, high), np.clip(v.astype(np.float32), low, high)
    _equal(got, ref)
    np.testing.assert_array_equal(np.signbit(got), np.signbit(ref))


def test_nearest_slots_equal_pack_nearest_order():
    rng = np.random.default_rng(7)
    row, key = rng.integers(0, 300, 4000), rng.uniform(0, 1, 4000)
    key[::7] = 0.5
    key[::31] = np.nan
    _equal(nearest_slots(300, row, key, 6), reference.pack_nearest(300, row, key, np.zeros((4000, 1)), 6)[1])


# -- whole steps -------------------------------------------------------------------------------------------
def _rollout(env_id, B, steps=4, **kwargs):
    vec = swarm_envs.make_vec(env_id, B, max_cycles=1000, **kwargs)
    vec.reset(seed=1)
    rng = np.random.default_rng(2)
    for _ in range(steps):
        vec.step(rng.uniform(-1, 1, (B, vec.n_agents, vec.layout.action_size)))
    return vec


@pytest.mark.parametrize(
    "B,kwargs",
    [(5, dict(n_robots=10)), (1, dict(n_robots=200, platform="droplet")), (3, dict(n_robots=12, message_bits=2, n_neighbours=5))],
)
def test_ideal_sensing_and_observations_equal_the_plain_formulas(B, kwargs):
    vec = _rollout("swarm_envs/Flocking-v0", B, sensing="ideal", **kwargs)
    core = vec.core
    frame = core.sensing.step(core.positions, core.headings, None)
    (rx, tx, distance, bearing, heading), (xy, valid, rigid) = _plain_ideal_step(core.sensing, core.positions, core.headings)
    nb = frame.neighbours
    assert len(rx) > 0
    for got, ref in [(nb.rx, rx), (nb.tx, tx), (nb.range, distance), (nb.bearing, bearing), (nb.heading, heading)]:
        _equal(got, ref)
    _equal(frame.scale_free.xy, xy)
    _equal(frame.scale_free.valid, valid)
    _equal(frame.scale_free.rigid, rigid)
    got, ref = core.observations(), _plain_observations(core)  # with the last step's frame (messages if any)
    assert got.keys() == ref.keys()
    for name in ref:
        _equal(got[name], ref[name], name)


def test_full_sensing_observations_equal_the_plain_formulas():
    vec = _rollout("swarm_envs/Flocking-v0", 2, steps=6, sensing="full", n_robots=8, message_bits=2)
    got, ref = vec.core.observations(), _plain_observations(vec.core)
    assert (ref["range_bearing"][..., 0] > 0).any()
    for name in ref:
        _equal(got[name], ref[name], name)


@pytest.mark.parametrize("B,n,mode", [(6, 10, "global"), (2, 9, "local"), (1, 1100, "local"), (3, 10, "local")])
def test_flocking_rewards_equal_the_plain_formulas(B, n, mode):
    vec = _rollout("swarm_envs/Flocking-v0", B, steps=3, sensing="ideal", n_robots=n, reward_mode=mode)
    task, state = vec.core.task, vec.core.state()
    got, ref = task.rewards(state, np.zeros(B, bool)), _plain_flocking_rewards(task, state)
    _equal(got[0], ref[0], "rewards")
    for d_got, d_ref in zip(got[1:], ref[1:]):
        assert d_got.keys() == d_ref.keys()
        for name in d_ref:
            _equal(d_got[name], d_ref[name], name)
    assert (ref[1]["local_polarisation"] != ref[1]["polarisation"]).any()


def test_cluster_metrics_equal_the_reference():
    from swarm_envs.tasks import metrics

    rng = np.random.default_rng(8)
    for B, N, link in [(9, 10, 0.3), (1, 1200, 0.25), (3, 30, 0.1), (2, 5, 2.0), (4, 6, 1e-3)]:
        pos = rng.uniform(0, 1 if N < 100 else 8, (B, N, 2))
        got, ref = metrics.largest_component_fraction(pos, link), reference.largest_component_fraction(pos, link)
        _equal(got[0], ref[0])
        _equal(got[1], ref[1])


def test_neighbourhood_sums_equal_add_at_over_sorted_links():
    from swarm_envs.tasks import metrics

    rng = np.random.default_rng(9)
    pos = rng.uniform(0, 2, (400, 2))
    pairs = copy_pairs(pos, 0.3, 100)
    values = rng.normal(size=(400, 2))
    values[::17] = 0.0
    sums, counts = metrics.neighbourhood_sums(values, pairs)
    rx, tx = directed_pairs(pairs)
    ref = values.copy()
    np.add.at(ref, rx, values[tx])
    _equal(sums, ref)
    _equal(counts, 1 + np.bincount(rx, minlength=400))
