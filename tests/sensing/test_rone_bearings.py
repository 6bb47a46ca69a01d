"""r-one bearings measured on decoded frames [L Sec. 3.2.1-3.2.3; docs/design.md#bearing-only-sensing] and the exchange by decoded sender."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pytest

from swarm_envs.ir.layer import compute_links
from swarm_envs.sim.platforms import get_platform
from swarm_envs.sensing.bearing_sensor import RONE_ARC_RANGE_DEG, MessageBearings, link_masks, sector_lut, sense_bearings
from swarm_envs.sensing.exchange import BearingExchange, encode_rows
from swarm_envs.sensing.full import BEACON_PERIOD, FullSensing
from swarm_envs.registry import task_class
from swarm_envs.tasks.settings import validate_settings

RONE = get_platform("rone")


@dataclass
class Frames:
    """The fields of ``Deliveries`` the bearing table and the exchange read."""

    receiver: np.ndarray
    origin: np.ndarray
    transmitter: np.ndarray
    interference: np.ndarray | None = None
    kind: np.ndarray | None = None
    length: np.ndarray | None = None
    payload: np.ndarray | None = None
    corrupt: np.ndarray | None = None


def frames(receiver, origin, transmitter, interference=None, **kw) -> Frames:
    a = lambda v: np.asarray(v, dtype=np.int64).reshape(-1)  # noqa: E731
    return Frames(a(receiver), a(origin), a(transmitter), None if interference is None else a(interference), **kw)


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
    mb = MessageBearings(RONE, 3, np.random.default_rng(0))
    nominal = sense_bearings(links, RONE)
    p = np.flatnonzero((nominal.rx == 0) & (nominal.tx == 1))[0]
    # robot 1's light started the frame but its header decoded to origin 2
    mb.step(frames([0], [2], [1]), links)
    r = mb.fresh  # this step's measurements (the readings follow at the following round start)
    assert r.rx.tolist() == [0] and r.tx.tolist() == [2]  # attributed to the decoded id, not the true sender
    assert r.bearing[0] == nominal.bearing[p] and r.heading[0] == nominal.heading[p]  # measured on robot 1's light
    assert r.age.tolist() == [0.0]
    # a frame started by noise, an origin outside the swarm, or the receiver's own id measure nothing
    mb2 = MessageBearings(RONE, 3, np.random.default_rng(0))
    mb2.step(frames([0, 0, 0], [1, 7, 0], [-1, 1, 1]), links)
    assert len(mb2.fresh.rx) == 0 and len(mb2.fill["rx"]) == 0
    assert mb2.stats["rejected"] == 2


def _rounds(period: int, phase: int) -> MessageBearings:
    mb = MessageBearings(RONE, 3, np.random.default_rng(0), period=period)
    mb.phase[:] = phase
    return mb


def test_readings_are_the_last_complete_rounds_frames():
    """[L Sec. 3.2.2]: at each round start a robot's readings become the frames of the round that just ended
    and everything older is cleared; frames of the current round wait for the next start."""
    pos, hd, links = triangle()
    period = 4
    mb = _rounds(period, 0)  # every robot's rounds start at steps 0, 4, 8, ...
    none = frames([], [], [])
    got = []
    for t in range(16):
        # robot 0 decodes robot 1 at steps 1 (round [0, 4)) and 13 (round [12, 16)), robot 2 at steps 2 and 6
        fr = {1: frames([0], [1], [1]), 2: frames([0], [2], [2]), 6: frames([0], [2], [2]), 13: frames([0], [1], [1])}.get(t, none)
        r = mb.step(fr, links)
        got.append({(int(a), int(b)): float(age) for a, b, age in zip(r.rx, r.tx, r.age)})
    assert got[0:4] == [{}] * 4  # nothing before the first round is complete (a frame waits for the round's end)
    assert got[4:8] == [{(0, 1): t - 1.0, (0, 2): t - 2.0} for t in range(4, 8)]  # round [0, 4), ageing
    assert got[8:12] == [{(0, 2): t - 6.0} for t in range(8, 12)]  # round [4, 8): robot 1 was silent, gone
    assert got[12:16] == [{}] * 4  # round [8, 12): nothing heard, nothing known
    assert mb.step(none, links).tx.tolist() == [1]  # round [12, 16) published at 16


def test_a_robots_readings_follow_its_own_rounds():
    pos, hd, links = triangle()
    mb = _rounds(4, 0)
    mb.phase[:] = [0, 2, 0]  # robot 1's rounds start at 2, 6, ...
    out = []
    for t in range(7):
        fr = frames([0, 1], [1, 0], [1, 0]) if t == 0 else frames([], [], [])
        r = mb.step(fr, links)
        out.append(sorted(zip(r.rx.tolist(), r.tx.tolist())))
    assert out == [[], [], [(1, 0)], [(1, 0)], [(0, 1), (1, 0)], [(0, 1), (1, 0)], [(0, 1)]]


def test_a_frame_whose_light_no_longer_reaches_the_receiver_measures_nothing():
    pos, hd, links = triangle()
    far = compute_links(pos * 10.0, hd, RONE)  # 3 m apart: no link
    mb = MessageBearings(RONE, 3, np.random.default_rng(0))
    assert len(far.rx) == 0
    mb.step(frames([0], [1], [1]), far)
    assert len(mb.fresh.rx) == 0


def test_ground_truth_fields_other_than_whose_light_do_not_matter():
    pos, hd, links = triangle()
    out = []
    for corrupt in (False, True):
        mb = MessageBearings(RONE, 3, np.random.default_rng(5), arc_range=RONE_ARC_RANGE_DEG)
        mb.step(frames([0, 1, 2], [1, 2, 0], [1, 2, 0], corrupt=np.full(3, corrupt)), links)
        r = mb.fresh
        out.append((r.rx.tolist(), r.tx.tolist(), r.bearing.tolist(), r.heading.tolist()))
    assert out[0] == out[1]


def test_copies_are_independent_and_reset_alone():
    pos, hd, links1 = triangle()
    pos2 = np.concatenate([pos, pos + 10.0])
    links2 = compute_links(pos2, np.r_[hd, hd], RONE, copy=np.repeat([0, 1], 3))
    one = MessageBearings(RONE, 3, np.random.default_rng(3), arc_range=RONE_ARC_RANGE_DEG)
    two = MessageBearings(RONE, 3, None, n_copies=2, arc_range=RONE_ARC_RANGE_DEG)
    two.reset(np.array([0, 1]), [np.random.default_rng(9), np.random.default_rng(3)])
    one.phase[:] = 0
    two.phase[:] = 0
    one.step(frames([0, 1, 2, 0], [1, 2, 0, 2], [1, 2, 0, 2]), links1)
    # copy 1 gets the same frames (rows + 3) interleaved with copy 0's
    two.step(frames([0, 3, 4, 1, 5, 3], [1, 4, 5, 2, 3, 5], [1, 4, 5, 2, 3, 5]), links2)
    for _ in range(one.period):  # to the following round start: the frames become the readings
        r1 = one.step(frames([], [], []), links1)
        r2 = two.step(frames([], [], []), links2)
    c1 = r2.rx >= 3
    assert c1.sum() == len(r1.rx) == 4
    np.testing.assert_array_equal(r2.rx[c1] - 3, r1.rx)
    np.testing.assert_array_equal(r2.tx[c1] - 3, r1.tx)
    np.testing.assert_array_equal(r2.bearing[c1], r1.bearing)
    two.reset(np.array([0]), [np.random.default_rng(1)])
    assert (two.readings().rx >= 3).all() and len(two.readings().rx) == c1.sum()


# ------------------------------------------------------------------ per-receiver copies [L Sec. 3.2.1]
def test_a_receiver_whose_own_copy_was_corrupted_does_not_count():
    """Only receivers whose own copy of the frame was clean give the bearing, and the orientation comes from
    the transmitters those receivers heard (the firmware keeps a receiver only if its copy passes the CRC)."""
    pos = np.array([[0.0, 0.0], [0.3, 0.0]])
    hd = np.array([0.0, np.deg2rad(150.0)])
    links = compute_links(pos, hd, RONE)
    # robot 0's receiver 0 (axis 22.5 deg) hears robot 1's transmitters 7, 0 and 1, its receiver 7 (-22.5 deg)
    # transmitters 1 and 2 (each transmitter lights its outward half-plane; the receivers' arcs pick the emitters)
    rx_mask, tx_mask = link_masks(links, RONE, np.flatnonzero((links.rx == 0) & (links.tx == 1)))
    assert rx_mask.tolist() == [0b10000001] and tx_mask.tolist() == [0b10000111]

    def measure(interference):
        mb = MessageBearings(RONE, 2, np.random.default_rng(0))
        mb.step(frames([0], [1], [1], interference=[interference]), links)
        r = mb.fresh
        return None if len(r.rx) == 0 else tuple(np.round(np.rad2deg([r.bearing[0], r.heading[0]]), 9))

    assert measure(0) == (0.0, 157.5)  # both receivers: their midpoint; transmitters 7, 0, 1, 2: 22.5 deg
    assert measure(1 << 3) == (0.0, 157.5)  # light on a receiver the frame did not reach changes nothing
    assert measure(1 << 0) == (-22.5, 90.0)  # receiver 0's copy lost: receiver 7 alone, transmitters 1 and 2
    assert measure(1 << 7) == (22.5, -157.5)  # receiver 7's copy lost: receiver 0, transmitters 7, 0 and 1
    assert measure((1 << 0) | (1 << 7)) is None  # no clean copy: nothing measured


def _hidden_terminals():
    """Robots 1 and 2 both reach robot 0 but not each other (a wall between them), so CSMA cannot keep
    their frames apart at robot 0: 1 lights receivers 7 and 0 of robot 0, 2 lights receiver 0."""
    a1, a2, r = np.deg2rad(-8.0), np.deg2rad(20.0), 0.6
    pos = np.array([[0.0, 0.0], [r * np.cos(a1), r * np.sin(a1)], [r * np.cos(a2), r * np.sin(a2)]])
    hd = np.array([0.0, a1 + np.pi, a2 + np.pi])
    w = 0.5 * (a1 + a2)
    wall = np.array([[[0.25 * np.cos(w), 0.25 * np.sin(w)], [1.5 * np.cos(w), 1.5 * np.sin(w)]]])
    links = compute_links(pos, hd, RONE, obstacles=wall)
    pairs = set(zip(links.rx.tolist(), links.tx.tolist()))
    assert (0, 1) in pairs and (0, 2) in pairs and (1, 2) not in pairs and (2, 1) not in pairs
    lit = dict(zip(zip(links.rx.tolist(), links.tx.tolist()), link_masks(links, RONE)[0].tolist()))
    assert lit[(0, 1)] == 0b10000001 and lit[(0, 2)] == 0b00000001
    return links, lit


@pytest.mark.parametrize("senders", [(1,), (1, 2)])
def test_colliding_light_over_the_real_channel_costs_the_receivers_it_reached(senders):
    """SwarmCom over hidden terminals: a frame's interference is the receivers the other robot's light
    reached; robot 1's frames then measure on receiver 7 alone (-22.5 deg), not on both (0 deg), and robot 2's
    (whose only receiver is hit) measure nothing. With robot 2 silent nothing interferes."""
    from swarm_envs.comm.network import Network

    links, lit = _hidden_terminals()
    # without the r-one's CRC: SwarmCom's one decoder (the brightest detector) would drop every frame whose
    # bits the other robot's light flipped, and the per-receiver rule under test needs frames delivered
    net = Network(RONE, 3, np.random.default_rng(0), crc_bits=0)
    mb = MessageBearings(RONE, 3, np.random.default_rng(1))
    interference, bearings = {1: [], 2: []}, {1: [], 2: []}
    for _ in range(300):
        for q in senders:  # back to back: a frame whenever the queue is empty
            if net.q_count[q] == 0:
                net.queue_system(q, np.zeros((1, 0), bool), "beacon")
        d = net.step(links)
        mb.step(d, links)
        at0 = (d.receiver == 0) & (d.origin == d.transmitter)  # frames whose header names the light's robot
        for t, i in zip(d.transmitter[at0].tolist(), d.interference[at0].tolist()):
            interference[t].append(i)
        f = mb.fresh
        for v, b in zip(f.tx[f.rx == 0].tolist(), f.bearing[f.rx == 0].tolist()):
            bearings[v].append(round(float(np.rad2deg(b)), 9))
    assert len(interference[1]) > 5
    if senders == (1,):
        assert set(interference[1]) == {0} and set(bearings[1]) == {0.0}
        return
    other = {1: lit[(0, 2)], 2: lit[(0, 1)]}
    for t in (1, 2):  # only the other robot's light interferes, and only where it reaches
        assert all(i & ~other[t] == 0 for i in interference[t])
    assert any(i == lit[(0, 2)] for i in interference[1])  # delivered, but receiver 0's copy was hit
    assert set(bearings[1]) == {-22.5}
    assert bearings[2] == [] and len(interference[2]) > 0 and mb.stats["interfered"] > 0


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
    tx_half = np.full((P, 8), np.pi / 2)  # the transmitters' half-plane (RoneIR)
    same = link_masks(links, RONE, rows, np.concatenate([np.full((P, 8), np.deg2rad(68.0) / 2), tx_half], axis=1))
    np.testing.assert_array_equal(same[0], nominal[0])  # the nominal arcs reproduce the IR layer's masks
    np.testing.assert_array_equal(same[1], nominal[1])
    half = np.concatenate([0.5 * np.deg2rad(rng.uniform(*RONE_ARC_RANGE_DEG, (P, 8))), tx_half], axis=1)
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
def _round_start(fs: FullSensing, robot: int, t: int) -> int:
    """The step at which ``robot``'s round containing step ``t`` started (copy 0, clock = steps since reset)."""
    return t - (t - int(fs.bearings.phase[robot])) % fs.bearings.period


@pytest.mark.parametrize("exchange", ["ideal", "network"])
def test_env_readings_are_frames_of_the_last_complete_round(exchange):
    """Every reading the env shows was measured on a frame decoded (from that decoded sender) during its
    receiver's last complete round [L Sec. 3.2.2], and is unchanged through the round it is shown in."""
    n = 8
    fs = full_stack(n, seed=1, exchange=exchange)
    rng = np.random.default_rng(2)
    pos = rng.uniform(0, 0.8, (n, 2))
    while np.min(np.hypot(*(pos[:, None] - pos[None]).transpose(2, 0, 1))[np.triu_indices(n, 1)]) < 0.12:
        pos = rng.uniform(0, 0.8, (n, 2))
    hd = rng.uniform(-np.pi, np.pi, n)
    seen = []
    step = fs.network.step

    def record(links, prepared=None, threads=1):
        d = step(links, prepared, threads)
        seen.append(set(zip(d.receiver.tolist(), d.origin.tolist())))
        return d

    fs.network.step = record
    prev = {}
    shown = 0
    for t in range(4 * BEACON_PERIOD):
        nb = fs.step(pos, hd, None).neighbours
        now = {(int(r), int(s)): (float(b), float(a)) for r, s, b, a in zip(nb.rx, nb.tx, nb.bearing, nb.age)}
        for (u, v), (b, a) in now.items():
            start = _round_start(fs, u, t)
            measured = t - int(a)
            assert start - BEACON_PERIOD <= measured < start  # measured during u's last complete round
            assert (u, v) in seen[measured]  # on a frame from that (decoded) sender decoded then
            if t > start:  # within a round the readings do not change, they only age
                assert prev[(u, v)] == (b, a - 1)
            shown += 1
        for u in range(n):  # and nothing of a robot's readings survives its round start but what it just heard
            if _round_start(fs, u, t) < t:
                assert {k for k in now if k[0] == u} == {k for k in prev if k[0] == u}
        prev = now
    assert shown > 4 * n  # readings were shown


def test_env_neighbour_out_of_range_disappears_at_the_second_round_start():
    """A neighbour that went out of range stays through the round after the one of its last measured frame
    and is gone at the start of the next (each robot clears all prior neighbour information every round)."""
    fs = full_stack(2, seed=0, exchange="network")
    pos = np.array([[0.0, 0.0], [0.3, 0.0]])
    hd = np.array([0.0, np.pi])
    last = {}
    t = 0
    for _ in range(2 * BEACON_PERIOD):
        nb = fs.step(pos, hd, None).neighbours
        for r, s in zip(fs.bearings.fresh.rx.tolist(), fs.bearings.fresh.tx.tolist()):
            last[(r, s)] = t
        t += 1
    assert set(zip(nb.rx.tolist(), nb.tx.tolist())) == {(0, 1), (1, 0)}
    far = np.array([[0.0, 0.0], [2.0, 0.0]])  # beyond the 1 m IR range
    shown = {(0, 1): [], (1, 0): []}
    t0 = t
    for _ in range(3 * BEACON_PERIOD):
        nb = fs.step(far, hd, None).neighbours
        assert len(fs.bearings.fresh.rx) == 0  # no frame can arrive
        now = set(zip(nb.rx.tolist(), nb.tx.tolist()))
        for key in shown:
            shown[key].append(key in now)
        t += 1
    for (u, v), h in shown.items():
        m = last[(u, v)]
        gone = _round_start(fs, u, m) + 2 * BEACON_PERIOD  # published at the next start, cleared at the one after
        assert gone > t0
        assert h == [t0 + i < gone for i in range(len(h))]


def test_env_every_frame_colliding_leaves_no_reading():
    """A neighbour heard only through frames that never decode (every frame lost) never appears."""
    fs = full_stack(3, seed=0, exchange="network")
    pos, hd, _ = triangle()
    step = fs.network.step

    def lose_robot_2(links, prepared=None, threads=1):  # the channel loses every frame from robot 2 (e.g. all collide)
        d = step(links, prepared, threads)
        keep = d.transmitter != 2
        for f in ("receiver", "origin", "sender", "seq", "detector", "kind", "length", "payload", "slot", "corrupt", "transmitter"):
            setattr(d, f, getattr(d, f)[keep])
        return d

    fs.network.step = lose_robot_2
    for _ in range(3 * BEACON_PERIOD):
        nb = fs.step(pos, hd, None).neighbours
        assert 2 not in nb.tx.tolist()
    assert {0, 1} <= set(nb.tx.tolist())


def test_env_a_list_whose_frame_measured_no_bearing_adds_no_neighbour():
    """The exchange pairs a received list with the bearing measured on that very frame: once every receiver
    copy of robot 2's frames is corrupted, its lists still arrive but it drops out of the others' knowledge
    by their second round start (an older reading of it is never reused)."""
    fs = full_stack(3, seed=0, exchange="network")
    pos, hd, _ = triangle()
    step = fs.network.step
    hit_all = {"on": False, "lists": 0}

    def corrupt_robot_2(links, prepared=None, threads=1):
        d = step(links, prepared, threads)
        if hit_all["on"]:
            from2 = d.transmitter == 2
            d.interference = np.where(from2, 0xFF, d.interference)
            hit_all["lists"] += int((from2 & (d.kind == fs.exchange.kind)).sum())
        return d

    fs.network.step = corrupt_robot_2
    for _ in range(4 * BEACON_PERIOD):
        fs.step(pos, hd, None)
    kn = fs.exchange.knowledge()
    assert all(2 in kn.ids[u].tolist() for u in (0, 1))
    hit_all["on"] = True
    for t in range(3 * BEACON_PERIOD):
        fs.step(pos, hd, None)
        kn = fs.exchange.knowledge()
        if t >= 2 * BEACON_PERIOD:
            assert all(2 not in kn.ids[u].tolist() for u in (0, 1)), t
            assert 2 not in fs.bearings.readings().tx.tolist()
    assert hit_all["lists"] >= 2  # robot 2's lists kept arriving
    assert all(1 - u in kn.ids[u].tolist() for u in (0, 1))  # the others still know each other


def test_env_rone_ages_stay_inside_the_observation_bound_and_are_not_clipped():
    import swarm_envs
    from swarm_envs.sensing.full import SECTOR_MAX_AGE

    env = swarm_envs.make("swarm_envs/Aggregation-v0", platform="rone", n_robots=6, sensing="full", max_cycles=200)
    obs, _ = env.reset(seed=3)
    space = env.observation_space(env.possible_agents[0])
    assert space["range_bearing"].high[0, 6] == SECTOR_MAX_AGE == 2 * BEACON_PERIOD - 1
    ages = []
    for _ in range(5 * BEACON_PERIOD):
        obs, *_ = env.step({a: np.zeros(2) for a in env.agents})
        for a in env.agents:
            assert space.contains(obs[a])
            rb = obs[a]["range_bearing"]
            ages += rb[rb[:, 0] > 0, 6].tolist()
    assert max(ages) > 10 and min(ages) >= 1  # older than rb_max_age's 10, and never this step's frame


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
    ex.step(readings, d)
    ex.start_rounds(np.arange(n))  # the round ends: its table is what robot 0 knows
    kn = ex.knowledge()
    slot = np.flatnonzero(kn.ids[0] == 2)
    assert slot.size == 1 and kn.bearings[0, slot[0]] == pytest.approx(np.deg2rad(45.0))
    assert 1 not in kn.ids[0].tolist()
    assert kn.row_ids[0, slot[0], 0] == 3
    # the receiver has no reading of the decoded sender: no own bearing, no entry
    ex2 = BearingExchange(n, "network", k_max=n, period=1, rng=np.random.default_rng(0))
    d3 = frames([0], [3], [1], kind=d.kind, length=d.length, payload=np.zeros((1, L), bool))
    ex2.step(readings, d3)
    ex2.start_rounds(np.arange(n))
    assert (ex2.knowledge().ids[0] < 0).all()


def test_exchange_rejects_an_origin_outside_the_receivers_copy():
    ex = BearingExchange(3, "network", k_max=3, period=1, rng=np.random.default_rng(0), n_copies=2)
    readings = type("R", (), {})()
    readings.rx, readings.tx = np.array([0, 0]), np.array([1, 4])  # 4 is a robot of the other copy
    readings.bearing, readings.valid = np.zeros(2), np.ones(2, bool)
    L = ex.bits_per_message(0)
    d = frames([0], [4], [1], kind=np.array(["bearing_exchange"], object), length=np.array([L]), payload=np.zeros((1, L), bool))
    ex.step(readings, d)
    ex.start_rounds(np.arange(ex.n))
    assert (ex.knowledge().ids < 0).all() and ex.stats["rejected"] == 1


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
