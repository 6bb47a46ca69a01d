"""r-one bearings measured on decoded frames [L Sec. 3.2.1-3.2.3; docs/design.md#bearing-only-sensing] and the exchange by decoded sender."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from swarm_envs.ir.layer import compute_links
from swarm_envs.platforms import get_platform
from swarm_envs.sensing.bearing_sensor import RONE_ARC_RANGE_DEG, MessageBearings, link_masks, sector_lut, sense_bearings
from swarm_envs.sensing.exchange import BearingExchange, encode_rows
from swarm_envs.sensing.full import BEACON_PERIOD, FullSensing
from swarm_envs.registry import task_class
from swarm_envs.settings import validate_settings

RONE = get_platform("rone")


@dataclass
class Frames:
    """The fields of ``Deliveries`` the bearing table and the exchange read."""

    receiver: np.ndarray
    origin: np.ndarray
    transmitter: np.ndarray
    kind: np.ndarray | None = None
    length: np.ndarray | None = None
    payload: np.ndarray | None = None
    corrupt: np.ndarray | None = None


def frames(receiver, origin, transmitter, **kw) -> Frames:
    a = lambda v: np.asarray(v, dtype=np.int64).reshape(-1)  # noqa: E731
    return Frames(a(receiver), a(origin), a(transmitter), **kw)


def triangle():
    """Three r-one robots 30 cm apart, facing the centre: every pair hears each other."""
    ang = np.deg2rad([90.0, 210.0, 330.0])
    pos = 0.3 / np.sqrt(3) * np.stack([np.cos(ang), np.sin(ang)], -1)
    hd = ang + np.pi
    return pos, hd, compute_links(pos, hd, RONE)


def full_stack(n: int, seed: int = 0, **settings) -> FullSensing:
    cfg = validate_settings(task_class("swarm_envs/Aggregation-v0"), {"platform": "rone", "n_robots": n, **settings})
    fs = FullSensing(RONE, n, cfg)
    fs.reset(np.array([0]), [np.random.default_rng(seed)])
    return fs


# ------------------------------------------------------------------ the table, with constructed frames
def test_reading_is_measured_on_the_frame_and_named_by_its_decoded_origin():
    pos, hd, links = triangle()
    mb = MessageBearings(RONE, 3, np.random.default_rng(0), max_age=5)
    nominal = sense_bearings(links, RONE)
    p = np.flatnonzero((nominal.rx == 0) & (nominal.tx == 1))[0]
    # robot 1's light started the frame but its header decoded to origin 2
    r = mb.step(frames([0], [2], [1]), links)
    assert r.rx.tolist() == [0] and r.tx.tolist() == [2]  # attributed to the decoded id, not the true sender
    assert r.bearing[0] == nominal.bearing[p] and r.heading[0] == nominal.heading[p]  # measured on robot 1's light
    assert r.age.tolist() == [0.0]
    # a frame started by noise, an origin outside the swarm, or the receiver's own id measure nothing
    mb2 = MessageBearings(RONE, 3, np.random.default_rng(0))
    assert len(mb2.step(frames([0, 0, 0], [1, 7, 0], [-1, 1, 1]), links).rx) == 0
    assert mb2.stats["rejected"] == 2


def test_readings_refresh_only_when_frames_arrive_and_vanish_after_max_age():
    pos, hd, links = triangle()
    max_age = 4
    mb = MessageBearings(RONE, 3, np.random.default_rng(0), max_age=max_age)
    none = frames([], [], [])
    r = mb.step(frames([0], [1], [1]), links)
    first = r.bearing.copy()
    ages = []
    for _ in range(max_age):  # no decoded frame: the reading keeps its value and ages
        r = mb.step(none, links)
        assert r.tx.tolist() == [1] and r.bearing.tolist() == first.tolist()
        ages.append(r.age[0])
    assert ages == [1.0, 2.0, 3.0, 4.0]
    assert len(mb.step(none, links).rx) == 0  # older than max_age: gone
    # a new frame brings it back with age 0
    assert mb.step(frames([0], [1], [1]), links).age.tolist() == [0.0]


def test_a_frame_whose_light_no_longer_reaches_the_receiver_measures_nothing():
    pos, hd, links = triangle()
    far = compute_links(pos * 10.0, hd, RONE)  # 3 m apart: no link
    mb = MessageBearings(RONE, 3, np.random.default_rng(0))
    assert len(far.rx) == 0
    assert len(mb.step(frames([0], [1], [1]), far).rx) == 0


def test_ground_truth_fields_other_than_whose_light_do_not_matter():
    pos, hd, links = triangle()
    out = []
    for corrupt in (False, True):
        mb = MessageBearings(RONE, 3, np.random.default_rng(5), arc_range=RONE_ARC_RANGE_DEG)
        r = mb.step(frames([0, 1, 2], [1, 2, 0], [1, 2, 0], corrupt=np.full(3, corrupt)), links)
        out.append((r.rx.tolist(), r.tx.tolist(), r.bearing.tolist(), r.heading.tolist()))
    assert out[0] == out[1]


def test_copies_are_independent_and_reset_alone():
    pos, hd, links1 = triangle()
    pos2 = np.concatenate([pos, pos + 10.0])
    links2 = compute_links(pos2, np.r_[hd, hd], RONE, copy=np.repeat([0, 1], 3))
    one = MessageBearings(RONE, 3, np.random.default_rng(3), arc_range=RONE_ARC_RANGE_DEG)
    two = MessageBearings(RONE, 3, None, n_copies=2, arc_range=RONE_ARC_RANGE_DEG)
    two.reset(np.array([0, 1]), [np.random.default_rng(9), np.random.default_rng(3)])
    r1 = one.step(frames([0, 1, 2, 0], [1, 2, 0, 2], [1, 2, 0, 2]), links1)
    # copy 1 gets the same frames (rows + 3) interleaved with copy 0's
    r2 = two.step(frames([0, 3, 4, 1, 5, 3], [1, 4, 5, 2, 3, 5], [1, 4, 5, 2, 3, 5]), links2)
    c1 = r2.rx >= 3
    np.testing.assert_array_equal(r2.rx[c1] - 3, r1.rx)
    np.testing.assert_array_equal(r2.tx[c1] - 3, r1.tx)
    np.testing.assert_array_equal(r2.bearing[c1], r1.bearing)
    two.reset(np.array([0]), [np.random.default_rng(1)])
    assert (two.readings().rx >= 3).all() and len(two.readings().rx) == c1.sum()


# ------------------------------------------------------------------ hardware noise
def test_arc_noise_keeps_the_firmware_sectors_and_only_moves_boundary_cases():
    rng = np.random.default_rng(0)
    n = 120
    pos = rng.uniform(0, 3.0, (n, 2))
    hd = rng.uniform(-np.pi, np.pi, n)
    links = compute_links(pos, hd, RONE, occlusion="none")
    P = len(links.rx)
    rows = np.arange(P)
    nominal = link_masks(links, RONE, rows)
    same = link_masks(links, RONE, rows, np.full((P, 16), np.deg2rad(68.0) / 2))
    np.testing.assert_array_equal(same[0], nominal[0])  # the nominal arcs reproduce the IR layer's masks
    np.testing.assert_array_equal(same[1], nominal[1])
    half = 0.5 * np.deg2rad(rng.uniform(*RONE_ARC_RANGE_DEG, (P, 16)))
    noisy_rx, _ = link_masks(links, RONE, rows, half)
    lut = sector_lut()
    b0, b1 = lut[nominal[0]], lut[noisy_rx]
    ok = np.isfinite(b0) & np.isfinite(b1)
    err_nominal = np.abs(np.angle(np.exp(1j * (b0[ok] - links.bearing[ok]))))
    err_noisy = np.abs(np.angle(np.exp(1j * (b1[ok] - links.bearing[ok]))))
    changed = b0[ok] != b1[ok]
    assert 0.02 < changed.mean() < 0.5  # some readings move to a neighbouring sector, most do not
    assert err_noisy.mean() > err_nominal.mean()
    # a changed reading moves by one sector step (22.5 deg) at most
    step = np.abs(np.angle(np.exp(1j * (b1[ok][changed] - b0[ok][changed]))))
    assert np.all(step <= np.deg2rad(22.5) + 1e-9)


# ------------------------------------------------------------------ over the real channel
def test_env_readings_refresh_no_faster_than_decoded_frames():
    n = 8
    fs = full_stack(n, seed=1, exchange="ideal")
    rng = np.random.default_rng(2)
    pos = rng.uniform(0, 0.8, (n, 2))
    while np.min(np.hypot(*(pos[:, None] - pos[None]).transpose(2, 0, 1))[np.triu_indices(n, 1)]) < 0.12:
        pos = rng.uniform(0, 0.8, (n, 2))
    hd = rng.uniform(-np.pi, np.pi, n)
    seen = []
    step = fs.network.step

    def record(links, prepared=None):
        d = step(links, prepared)
        seen.append(set(zip(d.receiver.tolist(), d.origin.tolist())))
        return d

    fs.network.step = record
    prev = {}
    fresh_total = 0
    for t in range(3 * BEACON_PERIOD):
        nb = fs.step(pos, hd, None).neighbours
        now = {(int(r), int(s)): (float(b), float(a)) for r, s, b, a in zip(nb.rx, nb.tx, nb.bearing, nb.age)}
        for key, (b, a) in now.items():
            if a == 0:
                assert key in seen[-1]  # fresh only where a frame from that (decoded) sender was decoded now
                fresh_total += 1
            else:
                assert key in prev and prev[key][0] == b and prev[key][1] == a - 1  # unchanged, one step older
        prev = now
    assert fresh_total > n  # frames did arrive
    # decoded frames are far fewer than per-step links: about one per neighbour and beacon period
    assert fresh_total < 3 * len(compute_links(pos, hd, RONE).rx)


def test_env_neighbour_out_of_range_disappears_after_max_age():
    fs = full_stack(2, seed=0, exchange="network")
    pos = np.array([[0.0, 0.0], [0.3, 0.0]])
    hd = np.array([0.0, np.pi])
    for _ in range(2 * BEACON_PERIOD):
        nb = fs.step(pos, hd, None).neighbours
    assert set(zip(nb.rx.tolist(), nb.tx.tolist())) == {(0, 1), (1, 0)}
    far = np.array([[0.0, 0.0], [2.0, 0.0]])  # beyond the 1 m IR range
    history = {(0, 1): [], (1, 0): []}
    for _ in range(fs.bearings.max_age + 2):
        nb = fs.step(far, hd, None).neighbours
        now = {(int(r), int(s)): a for r, s, a in zip(nb.rx, nb.tx, nb.age)}
        for key, h in history.items():
            h.append(now.get(key))
    for key, h in history.items():
        gone = h.index(None)
        assert all(a is None for a in h[gone:])  # once gone, it stays gone (no frame can arrive)
        assert h[gone - 1] == fs.bearings.max_age  # aged one step at a time up to the documented age
        assert np.all(np.diff(h[:gone]) == 1)


def test_env_every_frame_colliding_leaves_no_reading():
    """A neighbour heard only through frames that never decode (every frame lost) never appears."""
    fs = full_stack(3, seed=0, exchange="network")
    pos, hd, _ = triangle()
    step = fs.network.step

    def lose_robot_2(links, prepared=None):  # the channel loses every frame from robot 2 (e.g. all collide)
        d = step(links, prepared)
        keep = d.transmitter != 2
        for f in ("receiver", "origin", "sender", "seq", "detector", "kind", "length", "payload", "slot", "corrupt", "transmitter"):
            setattr(d, f, getattr(d, f)[keep])
        return d

    fs.network.step = lose_robot_2
    for _ in range(3 * BEACON_PERIOD):
        nb = fs.step(pos, hd, None).neighbours
        assert 2 not in nb.tx.tolist()
    assert {0, 1} <= set(nb.tx.tolist())


# ------------------------------------------------------------------ exchange by decoded sender
def test_exchange_matches_the_list_to_the_bearing_of_the_decoded_sender():
    n = 4
    ex = BearingExchange(n, "network", k_max=n, period=1, rng=np.random.default_rng(0))
    # the receiver 0 believes: robot 2 at 45 deg, robot 1 at -90 deg
    readings = type("R", (), {})()
    readings.rx, readings.tx = np.array([0, 0]), np.array([1, 2])
    readings.bearing = np.deg2rad([-90.0, 45.0])
    readings.valid = np.ones(2, bool)
    bits = encode_rows(np.array([[3]]), np.array([[0.0]]), ex.id_bits, ex.count_bits, ex.bearing_bits)
    L = ex.bits_per_message(1)
    # robot 1's light, header decoded as robot 2
    d = frames([0], [2], [1], kind=np.array(["bearing_exchange"], object), length=np.array([L]), payload=bits[:, :L].astype(bool))
    kn = ex.step(readings, d)
    slot = np.flatnonzero(kn.ids[0] == 2)
    assert slot.size == 1 and kn.bearings[0, slot[0]] == pytest.approx(np.deg2rad(45.0))
    assert 1 not in kn.ids[0].tolist()
    assert kn.row_ids[0, slot[0], 0] == 3
    # the receiver has no reading of the decoded sender: no own bearing, no entry
    ex2 = BearingExchange(n, "network", k_max=n, period=1, rng=np.random.default_rng(0))
    d3 = frames([0], [3], [1], kind=d.kind, length=d.length, payload=np.zeros((1, L), bool))
    assert (ex2.step(readings, d3).ids[0] < 0).all()


def test_exchange_rejects_an_origin_outside_the_receivers_copy():
    ex = BearingExchange(3, "network", k_max=3, period=1, rng=np.random.default_rng(0), n_copies=2)
    readings = type("R", (), {})()
    readings.rx, readings.tx = np.array([0, 0]), np.array([1, 4])  # 4 is a robot of the other copy
    readings.bearing, readings.valid = np.zeros(2), np.ones(2, bool)
    L = ex.bits_per_message(0)
    d = frames([0], [4], [1], kind=np.array(["bearing_exchange"], object), length=np.array([L]), payload=np.zeros((1, L), bool))
    kn = ex.step(readings, d)
    assert (kn.ids < 0).all() and ex.stats["rejected"] == 1


@pytest.mark.parametrize("exchange", ["ideal", "network"])
def test_vector_copies_equal_single_envs_with_beacons_and_noise(exchange):
    """Each copy's message-borne readings (beacons or exchange lists, arc noise on) equal a single env's."""
    import swarm_envs

    seeds, steps = [3, 8], 2 * BEACON_PERIOD
    kw = dict(n_robots=5, platform="rone", sensing="full", exchange=exchange, message_bits=2, max_cycles=steps)
    vec = swarm_envs.make_vec("swarm_envs/Aggregation-v0", len(seeds), **kw)
    actions = np.random.default_rng(0).uniform(-1, 1, (steps, len(seeds), vec.n_agents, vec.layout.action_size))
    vec.reset(seed=seeds)
    singles = [swarm_envs.make("swarm_envs/Aggregation-v0", **kw) for _ in seeds]
    for env, s in zip(singles, seeds):
        env.reset(seed=s)
    valid = 0
    for t in range(steps):
        obs, *_ = vec.step(actions[t])
        for b, env in enumerate(singles):
            o, *_ = env.step({a: actions[t, b, i] for i, a in enumerate(env.possible_agents)})
            for i, a in enumerate(env.possible_agents):
                np.testing.assert_array_equal(obs["range_bearing"][b, i], o[a]["range_bearing"])
                np.testing.assert_array_equal(obs["scale_free"][b, i], o[a]["scale_free"])
                valid += int(o[a]["range_bearing"][:, 0].sum())
    assert valid > 0
