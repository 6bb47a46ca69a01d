"""SwarmCom protocol and network simulator [T20 Sec. 4, 6]: detector, CSMA, collisions, flooding."""

import numpy as np
import pytest

from swarm_envs.comm.channel import ADCModel, detector_intensity
from swarm_envs.comm.network import Network
from swarm_envs.comm.protocol import IDLE, RECV, DetectorBank, FrameFormat
from swarm_envs.ir.layer import compute_links

NOISELESS = ADCModel(noise_var=0.0)


def _pair(d, rng, **kw):
    pos = np.array([[0.0, 0.0], [d, 0.0]])
    hd = np.array([0.0, np.pi])
    return compute_links(pos, hd, "epuck"), Network("epuck", 2, rng, **kw)


def _run(net, links, steps):
    out = []
    for _ in range(steps):
        out.append(net.step(links))
    return out


def test_frame_layout_round_trip():
    fmt = FrameFormat.for_swarm(300, (15, 11), with_sender=True)
    assert fmt.id_bits == 9
    assert fmt.header_bits == 1 + 3 + 8 + 7 + 9 + 9
    pay = np.random.default_rng(0).integers(0, 2, (3, 20)).astype(bool)
    bits, slots = fmt.build(np.array([1, 2, 1]), np.array([5, 127, 0]), np.array([7, 299, 0]), np.array([8, 1, 2]), pay, np.array([20, 3, 0]))
    assert bits[:, 0].all()  # start symbol
    assert slots.tolist() == (1 + 15 * fmt.n_blocks(np.array([20, 3, 0]))).tolist()
    info, ok = fmt.code.decode_stream(bits[0, 1:slots[0]])
    h = fmt.parse_header(info[None])
    assert ok and h["origin"][0] == 7 and h["sender"][0] == 8 and h["seq"][0] == 5 and h["length"][0] == 20
    assert np.array_equal(info[fmt.header_bits : fmt.header_bits + 20], pay[0])


def test_detector_dynamic_threshold_eq36():
    det = DetectorBank(1, relative_threshold=5)
    det.reset(np.array([4080.0]))
    listen = np.ones(1, bool)
    ev = det.sample(np.full((1, 8), 4080), listen, 4, 0)
    assert ev["started"].size == 0 and det.state[0] == IDLE
    m = np.full((1, 8), 4080)
    m[0, 3] = 3000  # start symbol, amplitude A = 3000 on detector 3
    ev = det.sample(m, listen, 4, 1)
    assert ev["started"].tolist() == [0] and det.state[0] == RECV
    assert det.thr[0] == np.floor(abs(4075 + 3000) / 2)  # 3537
    for val, bit in [(3600, False), (3500, True), (4070, False), (3536, True)]:
        m[0, 3] = val
        det.sample(m, listen, 4, 2)
        assert det.buf[0, det.nbits[0] - 1] == bit
    assert det.best_det[0] == 3 and det.best_m[0] == 3000


def test_ambient_estimate_tracks_environment(rng):
    net = Network("epuck", 3, rng, ambient=np.array([4080.0, 4000.0, 3900.0]))
    assert np.allclose(net.det.m_max_est, [4079.5, 3999.5, 3899.5], atol=0.2)


@pytest.mark.parametrize("code", [(15, 15), (15, 11), (15, 1)])
def test_noiseless_close_pair_decodes_perfectly(rng, code):
    links, net = _pair(0.15, rng, adc_model=NOISELESS, code=code, payload_bits=12)
    sent = []
    got = []
    gap = int(np.ceil(net.frame_slots() / net.slots_per_step)) + 1  # steps per frame (+1 for CSMA delay)
    for k in range(4 * gap):
        if k % gap == 0:
            p = rng.integers(0, 2, 12).astype(bool)
            sent.append(p)
            net.send(0, p)
        got.append(net.step(links))
    got += _run(net, links, 10)
    rx = [(d.receiver[i], d.origin[i], d.payload[i, : d.length[i]]) for d in got for i in range(len(d))]
    assert len(rx) == len(sent)
    for (r, o, p), s in zip(rx, sent):
        assert r == 1 and o == 0 and np.array_equal(p, s)
    st = net.stats
    assert st["bit_errors"] == 0 and st["bits_checked"] > 0 and st["rx_false_starts"] == 0
    assert all(d.detector[i] in (0, 7) for d in got for i in range(len(d)))  # front detectors


def test_frames_span_step_boundaries_and_slot_budget(rng):
    for rate in (310, 1670):  # 10 cm: inside the reliable range of both rates (the e-puck's detector response)
        links, net = _pair(0.1, rng, adc_model=NOISELESS, bitrate=rate, payload_bits=40)
        assert net.frame_slots() > 31
        net.send(0, np.ones(40, bool))
        n_del = sum(len(d) for d in _run(net, links, 10))
        assert n_del == 1
        assert net.stats["slots"] == rate  # 10 steps x 0.1 s, fractional remainder carried


def test_far_pair_below_threshold_receives_nothing(rng):
    d = 0.95
    y = detector_intensity(np.array([d, 0.0]), np.pi, np.zeros(2), 0.0, "epuck")
    links, net = _pair(d, rng, adc_model=NOISELESS, relative_threshold=10)
    assert len(links) == 2 and y.max() * 3930 < 10  # light arrives, but below m_tr
    deliveries = []
    for _ in range(5):
        net.send(0, np.ones(8, bool))
        deliveries += _run(net, links, 3)
    assert sum(len(x) for x in deliveries) == 0
    assert net.stats["rx_starts"] == 0 and net.stats["tx_started"] >= 5


def _three(rng, tx_positions, **kw):
    pos = np.vstack([[0.0, 0.0], tx_positions])
    head = np.arctan2(-pos[:, 1], -pos[:, 0])  # transmitters face the receiver
    head[0] = 0.0
    links = compute_links(pos, head, "epuck")
    return links, Network("epuck", 3, rng, adc_model=NOISELESS, **kw)


def test_hidden_terminals_collide_at_the_receiver(rng):
    # T1 - R - T2 in a row: R occludes T1 and T2 from each other, so CSMA cannot separate them
    links, net = _three(rng, [[0.2, 0.0], [-0.2, 0.0]])
    assert not ((links.rx == 1) & (links.tx == 2)).any()
    net.send(1, np.array([1, 0, 1, 0, 1, 0, 1, 0], bool))
    net.send(2, np.array([0, 1, 0, 1, 0, 1, 0, 1], bool))
    got = _run(net, links, 10)
    intact = sum(int((~d.corrupt).sum()) for d in got)
    assert net.stats["collisions"] >= 1
    assert intact < 2


def test_csma_separates_mutually_audible_transmitters(rng):
    ok = 0
    for trial in range(5):
        r = np.random.default_rng(100 + trial)
        links, net = _three(r, [[0.2, 0.06], [0.2, -0.06]])
        assert ((links.rx == 1) & (links.tx == 2)).any()
        net.send(1, np.array([1, 0, 1, 0, 1, 0, 1, 0], bool))
        net.send(2, np.array([0, 1, 0, 1, 0, 1, 0, 1], bool))
        got = _run(net, links, 10)
        at_r = [(d.origin[i], bool(d.corrupt[i])) for d in got for i in range(len(d)) if d.receiver[i] == 0]
        ok += sorted(at_r) == [(1, False), (2, False)]
    assert ok >= 4
    # the same geometry without carrier sense (forced simultaneous start) collides
    links, net = _three(np.random.default_rng(7), [[0.2, 0.06], [0.2, -0.06]], backoff_window=1)
    net.send(1, np.array([1, 0, 1, 0, 1, 0, 1, 0], bool))
    net.send(2, np.array([0, 1, 0, 1, 0, 1, 0, 1], bool))
    got = _run(net, links, 10)
    at_r = [(d.origin[i], bool(d.corrupt[i])) for d in got for i in range(len(d)) if d.receiver[i] == 0]
    assert sorted(at_r) != [(1, False), (2, False)]


def test_flooding_reaches_beyond_line_of_sight_and_dedupes(rng):
    pos = np.array([[0.0, 0.0], [0.2, 0.0], [0.4, 0.0]])  # B occludes A from C
    head = np.array([0.0, 0.0, np.pi])
    links = compute_links(pos, head, "epuck")
    assert not ((links.rx == 2) & (links.tx == 0)).any()
    results = {}
    for mode in ("broadcast", "flooding"):
        net = Network("epuck", 3, np.random.default_rng(3), adc_model=NOISELESS, comm_mode=mode)
        net.send(0, np.array([1, 1, 0, 0, 1, 0, 1, 1], bool))
        got = _run(net, links, 20)
        rec = [(int(d.receiver[i]), int(d.origin[i]), int(d.sender[i])) for d in got for i in range(len(d))]
        results[mode] = (rec, dict(net.stats))
    rec_b, st_b = results["broadcast"]
    rec_f, st_f = results["flooding"]
    assert sorted(rec_b) == [(1, 0, 0)]
    assert sorted(rec_f) == [(1, 0, 0), (2, 0, 1)]  # C hears A's message via relay B
    assert st_f["tx_started"] == 3  # A original, B relay, C relay; nothing is re-sent twice
    assert st_f["rx_duplicates"] >= 1  # B hears C's relay and drops it


def test_same_seed_same_result():
    rng0 = np.random.default_rng(0)
    pos = rng0.uniform(0, 0.6, (12, 2))
    pos = pos[np.argsort(pos[:, 0])]
    pos[:, 0] = np.arange(12) * 0.08  # non-overlapping
    head = rng0.uniform(-np.pi, np.pi, 12)
    links = compute_links(pos, head, "epuck")

    def run(seed):
        r = np.random.default_rng(seed)
        net = Network("epuck", 12, r, comm_mode="flooding")
        out = []
        for k in range(15):
            if k % 3 == 0:
                net.send_many(np.arange(0, 12, 4), np.ones((3, 8), bool))
            d = net.step(links)
            out.append((d.receiver.tolist(), d.origin.tolist(), d.seq.tolist(), d.payload.tolist()))
        return out, {k: v for k, v in net.stats.items() if not k.endswith("per_robot")}

    a, b, c = run(5), run(5), run(6)
    assert a == b
    assert a != c


@pytest.mark.parametrize("how", ["deepcopy", "pickle"])
def test_copied_network_continues_identically(how):
    """A deep copy / unpickled copy of a stepped network (its generator copied with it) delivers the same frames
    as the original from then on (the cached numba list of generators is rebuilt, not shared)."""
    import copy
    import pickle

    rng0 = np.random.default_rng(2)
    pos = np.stack([np.arange(8) * 0.08, np.zeros(8)], -1)
    links = compute_links(pos, rng0.uniform(-np.pi, np.pi, 8), "epuck")
    net = Network("epuck", 8, np.random.default_rng(3))
    net.send_many(np.arange(8), np.ones((8, 8), bool))
    net.step(links)
    twin = copy.deepcopy(net) if how == "deepcopy" else pickle.loads(pickle.dumps(net))
    assert twin.rng.generators[0] is not net.rng.generators[0]
    got = 0
    for _ in range(6):
        net.send_many(np.arange(0, 8, 2), np.ones((4, 8), bool))
        twin.send_many(np.arange(0, 8, 2), np.ones((4, 8), bool))
        d1, d2 = net.step(links), twin.step(links)
        np.testing.assert_array_equal(d1.receiver, d2.receiver)
        np.testing.assert_array_equal(d1.payload, d2.payload)
        got += len(d1)
    assert got > 0
    assert net.rng.generators[0].bit_generator.state == twin.rng.generators[0].bit_generator.state


@pytest.mark.parametrize("width,poly,check", [(8, 0x07, 0xF4), (16, 0x8005, 0xFEE8)])
def test_crc_reference_and_frame_check(width, poly, check):
    from swarm_envs.comm.protocol import crc

    def ref(bits):  # bitwise CRC, zero init, most significant bit first, no final XOR
        c, top = 0, 1 << (width - 1)
        for b in bits:
            fb = bool(c & top) ^ bool(b)
            c = (c << 1) & ((1 << width) - 1)
            if fb:
                c ^= poly
        return c

    rng = np.random.default_rng(9)
    B = rng.integers(0, 2, (30, 50)).astype(bool)
    L = rng.integers(0, 51, 30)
    assert crc(B, L, width).tolist() == [ref(B[i, : L[i]]) for i in range(30)]
    msg = np.unpackbits(np.frombuffer(b"123456789", np.uint8)).astype(bool)[None]
    assert crc(msg, [72], width)[0] == check  # CRC-8/ATM and CRC-16/UMTS check values
    fmt = FrameFormat.for_swarm(10, (15, 15), crc_bits=width)
    bits, slots = fmt.build(np.array([1, 1]), np.array([1, 2]), np.array([3, 4]), np.array([3, 4]), B[:2, :16], np.array([16, 5]))
    assert (slots == 1 + 15 * -(-(fmt.header_bits + np.array([16, 5]) + width) // 15)).all()  # whole blocks
    info = bits[:, 1:]
    h = fmt.parse_header(info)
    assert fmt.crc_ok(info, h["length"]).all()
    for pos in (2, fmt.header_bits - 1, fmt.header_bits + 2):  # a type, an origin and a payload bit
        bad = info.copy()
        bad[:, pos] ^= True
        assert not fmt.crc_ok(bad, h["length"]).any()


def test_crc16_is_the_firmwares_crc16_in_air_order():
    """The r-one's and the Droplet's CRC-16: a reflected table CRC (0xA001, zero init; avr-libc
    ``_crc16_update``) over bytes sent least significant bit first, its register sent least significant bit
    first. Read in air order that is our CRC-16 (x^16 + x^15 + x^2 + 1, most significant bit first)."""
    from swarm_envs.comm.protocol import crc

    def firmware(data):
        c = 0
        for byte in data:
            c ^= byte
            for _ in range(8):
                c = (c >> 1) ^ 0xA001 if c & 1 else c >> 1
        return c

    assert firmware(b"123456789") == 0xBB3D  # CRC-16/ARC check value
    rng = np.random.default_rng(4)
    for n_bytes in (1, 3, 5, 12):
        data = bytes(rng.integers(0, 256, n_bytes).tolist())
        air = np.array([[(b >> i) & 1 for b in data for i in range(8)]], bool)  # each byte LSB first
        register_on_air = [(firmware(data) >> i) & 1 for i in range(16)]  # sent LSB first
        assert crc(air, [8 * n_bytes], 16)[0] == int("".join(map(str, register_on_air)), 2)


def test_flooding_network_drops_corrupted_frames_with_crc(rng):
    # hidden terminals collide at the receiver; with CRC nothing corrupt reaches the application
    links, net = _three(rng, [[0.2, 0.0], [-0.2, 0.0]], comm_mode="flooding")
    assert net.crc_bits == 8
    for _ in range(5):
        net.send(1, np.array([1, 0, 1, 0, 1, 0, 1, 0], bool))
        net.send(2, np.array([0, 1, 0, 1, 0, 1, 0, 1], bool))
        got = _run(net, links, 6)
        assert not any(d.corrupt.any() for d in got)
    assert net.stats["collisions"] >= 1 and net.stats["rx_crc_failed"] >= 1
    # the same run without CRC lets a corrupted frame through to the application
    links, net = _three(np.random.default_rng(12345), [[0.2, 0.0], [-0.2, 0.0]], comm_mode="flooding", crc_bits=0)
    for _ in range(5):
        net.send(1, np.array([1, 0, 1, 0, 1, 0, 1, 0], bool))
        net.send(2, np.array([0, 1, 0, 1, 0, 1, 0, 1], bool))
        _run(net, links, 6)
    assert net.stats["rx_corrupt_delivered"] >= 1


@pytest.mark.parametrize("platform,d", [("droplet", 0.2), ("rone", 0.4)])
def test_other_platforms_run_the_same_protocol(platform, d):
    from swarm_envs.comm.channel import recommended_relative_threshold

    rng = np.random.default_rng(1)
    links = compute_links(np.array([[0.0, 0.0], [d, 0.0]]), np.array([0.0, np.pi]), platform)
    net = Network(platform, 2, rng, relative_threshold=recommended_relative_threshold(platform))
    sent = []
    got = []
    for k in range(40):
        if k % 4 == 0:
            p = rng.integers(0, 2, 8).astype(bool)
            sent.append(p)
            net.send(0, p)
        d_ = net.step(links)
        got += [d_.payload[i, :8] for i in range(len(d_))]
    assert len(got) == len(sent) and all(np.array_equal(a, b) for a, b in zip(got, sent))
    assert net.stats["bit_errors"] == 0


@pytest.mark.parametrize("bitrate", [310, 315])
def test_prepared_steps_deliver_the_same_frames(bitrate):
    """Drawing a step's random numbers ahead (prepare_step, before the payloads are queued, as the core does
    while the physics runs) gives the same deliveries, statistics and generator state as drawing them in
    step; 315 bps (31.5 slots per step) exercises the slot-clock remainder."""
    rng0 = np.random.default_rng(4)
    pos = np.stack([np.arange(10) * 0.07, np.zeros(10)], -1)
    links = compute_links(pos, rng0.uniform(-np.pi, np.pi, 10), "epuck")

    def run(ahead):
        net = Network("epuck", 10, np.random.default_rng(8), bitrate=bitrate, comm_mode="flooding")
        out, slots = [], []
        for k in range(12):
            prepared = net.prepare_step() if ahead else None
            if k % 2 == 0:
                net.send_many(np.arange(k % 3, 10, 3), np.ones((len(range(k % 3, 10, 3)), 8), bool))
            d = net.step(links, prepared)
            out.append((d.receiver.tolist(), d.origin.tolist(), d.seq.tolist(), d.payload.tolist()))
            slots.append(net.stats["slots"])
        return out, slots, net.rng.generators[0].bit_generator.state

    ahead, inline = run(True), run(False)
    assert ahead == inline
    assert sum(len(step[0]) for step in ahead[0]) > 0
    if bitrate == 315:
        assert sorted(set(np.diff(ahead[1]))) == [31, 32]


def test_a_prepared_step_is_for_one_step_only():
    links, net = _pair(0.05, np.random.default_rng(0))
    prepared = net.prepare_step()
    net.step(links, prepared)
    net.step(links)
    with pytest.raises(ValueError, match="another step"):
        net.step(links, prepared)


@pytest.mark.parametrize("platform, rate", [("epuck", 310), ("rone", 1250), ("droplet", 310)])
def test_the_default_bitrate_is_the_platforms(platform, rate):
    import dataclasses

    import swarm_envs
    from swarm_envs.sim.platforms import get_platform

    env = swarm_envs.make("swarm_envs/Flocking-v0", n_robots=3, platform=platform)
    assert env.core.sensing.network.bitrate == rate == get_platform(platform).ir_bitrate
    assert swarm_envs.make("swarm_envs/Flocking-v0", n_robots=3, platform=platform, bitrate=650).core.sensing.network.bitrate == 650
    for bad in (0, 15, 1e3, True, 10**6):
        with pytest.raises(ValueError, match="Platform.ir_bitrate"):
            dataclasses.replace(get_platform(platform), ir_bitrate=bad)
