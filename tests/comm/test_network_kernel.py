"""Compiled SwarmCom slot loop (comm/kernels.py) against the numpy reference (comm/network.py)."""

import numpy as np
import pytest

from swarm_envs.comm.bch import SUPPORTED, code as bch_code
from swarm_envs.comm.channel import ADCModel
from swarm_envs.comm.kernels import decode_words
from swarm_envs.comm.draws import GeneratorList, _draw_copies_py, draw_copies, draw_step
from swarm_envs.comm.network import Network
from swarm_envs.ir.layer import compute_links

FIELDS = ("receiver", "origin", "sender", "seq", "detector", "kind", "length", "slot", "corrupt", "transmitter", "interference")


def _scene(rng, n, density):
    """Small swarms on a jittered ring (all in range), larger ones uniform in a square of the density."""
    if n < 25:
        a = 2 * np.pi * np.arange(n) / n + rng.uniform(-0.1, 0.1, n)
        rad = max(0.06, 0.12 * n / (2 * np.pi))
        return np.stack([rad * np.cos(a), rad * np.sin(a)], -1), rng.uniform(-np.pi, np.pi, n)
    side = np.sqrt(n / density)
    return rng.uniform(0, side, (n, 2)), rng.uniform(-np.pi, np.pi, n)


def _traffic(net, rng, p_app, p_sys, max_len):
    n = net.n
    send = np.flatnonzero(rng.random(n) < p_app)
    if send.size:
        lengths = rng.integers(0, max_len + 1, send.size)
        net.send_many(send, rng.random((send.size, max_len)) < 0.5, lengths=lengths)
    sys = np.flatnonzero(rng.random(n) < p_sys)
    if sys.size:
        net.queue_system(sys, rng.random((sys.size, 20)) < 0.5, kind="bearing")


def _assert_same(d_ref, d_k, step):
    assert len(d_ref) == len(d_k), f"step {step}: {len(d_ref)} vs {len(d_k)} deliveries"
    for f in FIELDS:
        np.testing.assert_array_equal(getattr(d_ref, f), getattr(d_k, f), err_msg=f"step {step}: {f}")
    for a, b in zip(d_ref.payloads(), d_k.payloads()):
        np.testing.assert_array_equal(a, b, err_msg=f"step {step}: payload")
    for k, v in d_ref.stats.items():
        np.testing.assert_array_equal(v, d_k.stats[k], err_msg=f"step {step}: counter {k}")


CASES = [
    # seed, n, mode, code, bitrate, density (robots/m^2), extra Network kwargs
    (0, 2, "broadcast", (15, 15), 310, 200.0, {}),
    (1, 7, "broadcast", (15, 11), 310, 300.0, {}),
    (2, 25, "flooding", (15, 15), 310, 100.0, {}),
    (3, 60, "broadcast", (15, 15), 1800, 150.0, {}),
    (4, 40, "flooding", (15, 11), 1800, 100.0, {}),
    (5, 12, "flooding", (15, 1), 1800, 150.0, {}),
    (6, 9, "broadcast", (15, 1), 1800, 300.0, {}),
    (7, 30, "broadcast", (15, 15), 310, 150.0, {"intensity_sigma": 0.02}),
    (8, 50, "flooding", (15, 15), 310, 300.0, {"crc_bits": 0}),
    (9, 20, "broadcast", (15, 11), 310, 100.0, {"crc_bits": 8, "relative_threshold": 2}),
    (12, 30, "broadcast", (15, 15), 310, 150.0, {"crc_bits": 16, "relative_threshold": 2}),
    (13, 25, "flooding", (15, 11), 1800, 200.0, {"crc_bits": 16}),
    # detector response (channel.detector_response): the e-puck default at high bit rates is in every case
    # above; these make it dominate (slow circuit, intensity noise clipped at 0) or switch it off
    (10, 30, "broadcast", (15, 15), 1670, 150.0, {"adc_model": ADCModel(response_c=4e-5), "intensity_sigma": 0.01}),
    (11, 20, "flooding", (15, 11), 1800, 300.0, {"adc_model": ADCModel(response_c=2.5e-5, response_bias=0.005)}),
    (4, 40, "flooding", (15, 11), 1800, 100.0, {"adc_model": ADCModel(response_c=0.0)}),  # case 4, instantaneous detector
    # a noiseless instantaneous ADC (the r-one's): a robot no light reaches reads one sample on every detector
    (14, 40, "broadcast", (15, 15), 1800, 150.0, {"adc_model": ADCModel(response_c=0.0, noise_var=0.0)}),
    (15, 25, "flooding", (15, 11), 310, 200.0, {"adc_model": ADCModel(response_c=0.0, noise_var=0.0)}),
    (16, 30, "broadcast", (15, 15), 1250, 150.0, {"platform": "rone"}),
]


@pytest.mark.parametrize("seed,n,mode,code,bitrate,density,kw", CASES)
def test_kernel_equals_numpy_reference(seed, n, mode, code, bitrate, density, kw):
    scene_rng = np.random.default_rng(1000 + seed)
    pos, head = _scene(scene_rng, n, density)
    kw = dict(kw)
    platform = kw.pop("platform", "epuck")
    nets = {
        b: Network(platform, n, np.random.default_rng(seed), bitrate=bitrate, code=code, comm_mode=mode, backend=b, **kw)
        for b in ("numpy", "numba")
    }
    max_len = 40 if code != (15, 1) else 8
    delivered = interfered = 0
    seen_level = 0.0
    for step in range(20):
        for net in nets.values():  # the same traffic for both
            _traffic(net, np.random.default_rng(10_000 * seed + step), 0.4, 0.2, max_len)
        pos = pos + scene_rng.normal(0, 0.003, pos.shape)
        head = head + scene_rng.normal(0, 0.1, n)
        links = compute_links(pos, head, platform)
        d_ref = nets["numpy"].step(links)
        d_k = nets["numba"].step(links)
        _assert_same(d_ref, d_k, step)
        np.testing.assert_allclose(nets["numpy"].rx_level, nets["numba"].rx_level, rtol=1e-12, atol=1e-15, err_msg=f"step {step}")
        seen_level = max(seen_level, float(nets["numba"].rx_level.max()))
        delivered += len(d_ref)
        interfered += int((d_ref.interference != 0).sum())
    ref, k = nets["numpy"], nets["numba"]
    for name, v in ref.stats.items():
        np.testing.assert_array_equal(v, k.stats[name], err_msg=name)
    np.testing.assert_array_equal(ref.det.m_max_est, k.det.m_max_est)
    np.testing.assert_allclose(ref.rx_level, k.rx_level, rtol=1e-12, atol=1e-15)
    if ref.response_kt > 0:  # the detector response was exercised
        assert seen_level > 0
    else:
        assert (ref.rx_level == 0).all()
    np.testing.assert_array_equal(ref.csma.backoff, k.csma.backoff)
    np.testing.assert_array_equal(ref.q_count, k.q_count)
    assert ref.slot == k.slot
    np.testing.assert_array_equal(ref.cur_id, k.cur_id)
    # the scenes are not trivial: frames get through, and (in the dense ones) frames collide or abort
    assert delivered > 0
    assert ref.stats["tx_started"] > 0 and ref.stats["rx_starts"] > 0
    if n >= 25:
        assert ref.stats["collisions"] > 0 and ref.stats["rx_aborted"] > 0
        assert interfered > 0  # delivered frames whose detectors caught other robots' light (Deliveries.interference)


def test_dense_scenes_exercise_losses_and_corruption():
    """Across the cases, the comparison covers losses, corrupt deliveries, flooding relays and CSMA
    deferrals (so equality above is not only about clean frames)."""
    totals = {}
    for seed, n, mode, code, bitrate, density, kw in CASES:
        if n < 25:
            continue
        rng = np.random.default_rng(1000 + seed)
        pos, head = _scene(rng, n, density)
        kw = dict(kw)
        platform = kw.pop("platform", "epuck")
        net = Network(platform, n, np.random.default_rng(seed), bitrate=bitrate, code=code, comm_mode=mode, **kw)
        links = compute_links(pos, head, platform)
        for step in range(10):
            _traffic(net, np.random.default_rng(77 + step), 0.4, 0.2, 40)
            net.step(links)
        for k in ("rx_lost", "rx_corrupt_delivered", "tx_relays", "deferrals", "rx_false_starts", "rx_duplicates"):
            totals[k] = totals.get(k, 0) + net.stats[k]
    for k, v in totals.items():
        assert v > 0, k


@pytest.mark.parametrize("nk", SUPPORTED)
def test_kernel_block_decoder_matches_bch(nk):
    c = bch_code(*nk)
    words = np.arange(1 << c.n, dtype=np.int64)
    msg, ok = decode_words(words, c.n, c.k, c._table_msg, c._table_ok)
    bits = ((words[:, None] >> np.arange(c.n - 1, -1, -1)) & 1).astype(bool)
    info, ok_ref = c.decode(bits)
    np.testing.assert_array_equal(ok, ok_ref)
    np.testing.assert_array_equal(((msg[:, None] >> np.arange(c.k - 1, -1, -1)) & 1).astype(bool), info)


def test_random_stream_does_not_depend_on_traffic():
    """Every draw of a step has a shape fixed by (slots, robots): two networks with the same seed but
    different traffic consume their generators identically (a batched engine can draw per copy)."""
    n = 15
    rng = np.random.default_rng(3)
    pos, head = _scene(rng, n, 150.0)
    links = compute_links(pos, head, "epuck")
    a = Network("epuck", n, np.random.default_rng(5))
    b = Network("epuck", n, np.random.default_rng(5))
    for step in range(8):
        _traffic(a, np.random.default_rng(step), 0.8, 0.3, 16)
        a.step(links)
        b.step(links if step % 2 else None)
        assert a.rng.generators[0].bit_generator.state == b.rng.generators[0].bit_generator.state
    assert a.stats["tx_started"] > 0 and b.stats["tx_started"] == 0


def test_draw_step_shapes():
    d = draw_step(np.random.default_rng(0), 31, 7, 8, 1.58, 0.0, 32)
    assert d.noise.shape == (31, 7, 8) and d.noise.dtype == np.float32
    assert d.intensity_noise.size == 0
    assert draw_step(np.random.default_rng(0), 31, 7, 8, 0.0, 0.0, 32).noise.shape == (0, 0, 0)  # an ADC without noise
    assert d.backoff.shape == (7, 31) and d.backoff.min() >= 0 and d.backoff.max() < 32
    assert d.access.shape == (7,)


@pytest.mark.parametrize("B,n,intensity_sigma", [(3, 7, 0.0), (2, 5, 0.01), (1, 40, 0.0)])
def test_compiled_draws_equal_numpy_generator_calls(B, n, intensity_sigma):
    """The compiled drawer (NumPy's float32 ziggurat inlined, numba's bounded integers and normal) gives bit for bit what
    NumPy's own Generator methods give in plain Python, and leaves every generator in the same state; 2000
    slots so the ziggurat's rare paths (wedges, tail) are exercised."""
    S = 2000
    g1 = [np.random.default_rng([seed, 11]) for seed in range(B)]
    g2 = [np.random.default_rng([seed, 11]) for seed in range(B)]
    a = draw_copies(GeneratorList(g1).sync(g1), S, n, 8, 1.58, intensity_sigma, 32)
    b = _draw_copies_py(g2, S, n, 8, 1.58, intensity_sigma, 32)
    for x, y in zip(a, b):
        assert x.dtype == y.dtype
        np.testing.assert_array_equal(x, y)
    assert all(x.bit_generator.state == y.bit_generator.state for x, y in zip(g1, g2))
    z = a.noise / np.float32(1.58)
    assert abs(float(z.mean())) < 0.01 and abs(float(z.std()) - 1.0) < 0.01 and float(np.abs(z).max()) > 4.5


@pytest.mark.parametrize("window", [1, 2, 3, 32, 1000, 3 * 2**29, 2**31 - 1])
def test_compiled_integers_equal_numpy_integers(window):
    """The compiled backoff/access draws are NumPy's ``integers(0, window)`` bit for bit for windows from 1
    (no draw) to 2**31 - 1; 3 * 2**29 rejects about a quarter of the 32-bit words (Lemire's rejection path)."""
    g1 = [np.random.default_rng([seed, 3]) for seed in range(2)]
    g2 = [np.random.default_rng([seed, 3]) for seed in range(2)]
    a = draw_copies(GeneratorList(g1).sync(g1), 50, 6, 8, 0.0, 0.0, window)
    _, _, backoff, access = _draw_copies_py(g2, 50, 6, 8, 0.0, 0.0, window)
    np.testing.assert_array_equal(a.backoff, backoff)
    np.testing.assert_array_equal(a.access, access)
    assert all(x.bit_generator.state == y.bit_generator.state for x, y in zip(g1, g2))
    assert a.backoff.min() >= 0 and a.backoff.max() < window


@pytest.mark.parametrize("window", [0, -1, 2**31])
def test_csma_window_out_of_range_is_refused(window):
    from swarm_envs.comm.protocol import CSMA

    with pytest.raises(ValueError, match="backoff window"):
        CSMA(4, window)


def test_compiled_normals_follow_numpy_wedge_test():
    """Seed 5 reaches, at sample 1,321,334, a ziggurat wedge sample whose accept decision differs when
    exp(-x^2/2) is rounded to float32 (as numba's own Generator.standard_normal does); the compiled drawer
    compares in double as NumPy does, so the whole stream stays NumPy's."""
    g = np.random.default_rng(5)
    d = draw_copies(GeneratorList([g]).sync([g]), 1000, 166, 8, 1.0, 0.0, 32)
    ref = np.random.default_rng(5).standard_normal(size=(1000, 166, 8), dtype=np.float32)
    np.testing.assert_array_equal(d.noise, ref)


def test_copy_draws_equal_single_env_draws():
    """Copy b of a batched draw is what a single env with generator b draws (rows b*n .. b*n+n-1), also
    after a copy's generator is replaced (GeneratorList.sync swaps it in)."""
    S, n, B = 31, 6, 4
    gens = [np.random.default_rng(100 + b) for b in range(B)]
    gl = GeneratorList(gens)
    for step in range(3):
        if step == 2:
            gens[1] = np.random.default_rng(999)
        twins = [np.random.default_rng() for _ in gens]
        for t, g in zip(twins, gens):
            t.bit_generator.state = g.bit_generator.state
        singles = [draw_step(t, S, n, 8, 1.58, 0.0, 32) for t in twins]
        d = draw_copies(gl.sync(gens), S, n, 8, 1.58, 0.0, 32)
        for b, one in enumerate(singles):
            rows = slice(b * n, (b + 1) * n)
            np.testing.assert_array_equal(d.noise[:, rows], one.noise)
            np.testing.assert_array_equal(d.backoff[rows], one.backoff)
            np.testing.assert_array_equal(d.access[rows], one.access)
            assert twins[b].bit_generator.state == gens[b].bit_generator.state


def test_bad_backend():
    with pytest.raises(ValueError, match="backend"):
        Network("epuck", 3, np.random.default_rng(0), backend="cuda")


@pytest.mark.parametrize("backend", ["numpy", "numba"])
def test_ir_emitter_sums_give_the_same_network(backend):
    """``links.emitter_sums`` (the IR layer's all-emitters-on sums, accumulated from 0.0 in emitter order) is
    used instead of the (P, n_det, n_emitters) gains: same deliveries, counters and detector levels, bit for
    bit, as summing the gains in the network."""
    n = 40
    scene_rng = np.random.default_rng(5)
    pos, head = _scene(scene_rng, n, 150.0)
    nets = [Network("epuck", n, np.random.default_rng(3), bitrate=1080, backend=backend) for _ in range(2)]
    lit = 0
    for step in range(15):
        for net in nets:
            _traffic(net, np.random.default_rng(500 + step), 0.4, 0.2, 24)
        pos = pos + scene_rng.normal(0, 0.003, pos.shape)
        head = head + scene_rng.normal(0, 0.1, n)
        links = compute_links(pos, head, "epuck")
        d_plain = nets[0].step(links)
        g = np.asarray(links.gains, dtype=np.float64)
        sums = np.zeros(g.shape[:2])
        for e in range(g.shape[2]):  # sequential from 0.0, emitter order
            sums += g[:, :, e]
        links.emitter_sums = sums
        links.gains = np.full_like(g, np.nan)  # the sums must be what is read
        d_sums = nets[1].step(links)
        _assert_same(d_plain, d_sums, step)
        np.testing.assert_array_equal(nets[0].rx_level, nets[1].rx_level)
        lit += len(d_plain)
    assert lit > 0
    np.testing.assert_array_equal(nets[0].det.m_max_est, nets[1].det.m_max_est)
    links.emitter_sums = sums[:, :4]
    with pytest.raises(ValueError, match="emitter_sums"):
        nets[1].step(links)


@pytest.mark.parametrize("code", [(15, 15), (15, 11), (15, 5), (15, 1)])
@pytest.mark.parametrize("with_sender,crc_bits", [(False, 0), (True, 8), (False, 8), (False, 16), (True, 16)])
def test_compiled_frame_builder_equals_reference(code, with_sender, crc_bits):
    """kernels.build_frames gives FrameFormat.build's frames bit for bit (same array shape), for mixed
    lengths including 0 and the maximum."""
    from swarm_envs.comm.kernels import build_frames
    from swarm_envs.comm.protocol import MAX_PAYLOAD, FrameFormat, crc_table

    rng = np.random.default_rng(hash((code, with_sender, crc_bits)) % 2**32)
    for n_robots, M, lmax in ((12, 7, 40), (1000, 30, MAX_PAYLOAD), (300, 1, 0)):
        fmt = FrameFormat.for_swarm(n_robots, code, with_sender=with_sender, crc_bits=crc_bits)
        c = fmt.code
        length = rng.integers(0, lmax + 1, M)
        length[0] = lmax
        payload = rng.random((M, lmax + 3)) < 0.5
        args = (rng.integers(1, 8, M), rng.integers(0, 300, M), rng.integers(0, n_robots, M), rng.integers(0, n_robots, M))
        ref_bits, ref_slots = fmt.build(*args, payload, length)
        bits, slots = build_frames(*args, payload, length, fmt.header_bits, fmt.id_bits, fmt.with_sender, fmt.crc_bits,
                                   crc_table(crc_bits or 8, fmt.header_bits + MAX_PAYLOAD + crc_bits), c.n, c.k, c._codewords)
        np.testing.assert_array_equal(slots, ref_slots)
        assert bits.shape == ref_bits.shape and bits.dtype == ref_bits.dtype
        np.testing.assert_array_equal(bits, ref_bits)
        assert bits[:, 1:].any()


def test_send_rejects_bad_payload_lengths():
    for backend in ("numpy", "numba"):
        net = Network("epuck", 4, np.random.default_rng(0), backend=backend)
        for lengths in ([3, -1], [3, 9]):
            with pytest.raises(ValueError, match="payload length"):
                net.send_many(np.array([0, 1]), np.zeros((2, 8), bool), lengths=np.array(lengths))


@pytest.mark.parametrize("noisy", [False, True])
def test_compiled_detector_response_equals_the_reference(noisy):
    """The slot loop's branch-free detector response (kernels._respond) equals channel.detector_response bit
    for bit: lit and dark detectors, levels decaying to the dark cut-off, light above 1 and below 0 clipped."""
    from swarm_envs.comm.channel import adc_model_for, detector_response
    from swarm_envs.comm.kernels import _respond

    a = adc_model_for("epuck")
    slot_s, rng = 1.0 / 310, np.random.default_rng(8)
    n = 4000
    y = np.where(rng.random(n) < 0.4, 0.0, rng.uniform(0.0, 1.3, n))
    level = np.where(rng.random(n) < 0.3, 0.0, 10.0 ** rng.uniform(-8, 0, n))
    inoise = rng.normal(0.0, 0.05, n) if noisy else np.zeros(0)
    ref = level.copy()
    for _ in range(6):  # a few slots: levels decay, some below the dark cut-off
        expect = detector_response(ref, y + inoise if noisy else y, slot_s, a.response_c, a.response_bias)
        _respond(y.copy(), inoise, level, float(a.response_bias), slot_s / a.response_c)
        np.testing.assert_array_equal(level, expect)
        ref = expect
        y = np.where(rng.random(n) < 0.5, 0.0, y)
    assert (level == 0.0).any() and (level > 0.0).any()


@pytest.mark.parametrize("mode,bitrate", [("broadcast", 310), ("flooding", 1800)])
def test_copies_in_groups_on_threads_equal_one_loop(mode, bitrate):
    """The slot loop over groups of env copies on threads (Network.step(threads=k)) gives every delivery,
    counter and transceiver state of the single loop, bit for bit, and both equal the numpy reference."""
    from swarm_envs.sim.copies import CopyRandom

    copies, size = 5, 14
    nets = {
        key: Network("epuck", size, CopyRandom([np.random.default_rng(s) for s in range(copies)]), bitrate=bitrate, comm_mode=mode,
                     backend=backend, n_copies=copies)
        for key, backend in (("ref", "numpy"), (1, "numba"), (2, "numba"), (3, "numba"))
    }  # fmt: skip
    scene_rng = np.random.default_rng(5)
    pos, head = _scene(scene_rng, copies * size, 200.0)
    copy_of = np.repeat(np.arange(copies), size)
    delivered = 0
    for step in range(25):
        for net in nets.values():
            _traffic(net, np.random.default_rng(step), 0.4, 0.2, 40)
        pos = pos + scene_rng.normal(0, 0.003, pos.shape)
        links = compute_links(pos, head, "epuck", copy=copy_of)
        out = {key: net.step(links) if key == "ref" else net.step(links, threads=key) for key, net in nets.items()}
        for key in (1, 2, 3):
            _assert_same(out["ref"], out[key], step)
        delivered += len(out[1])
    for key in (2, 3):
        for name in ("cur_id", "cur_pos", "sending", "q_count", "gt_tx", "gt_id", "collided", "rx_foreign", "rx_level"):
            np.testing.assert_array_equal(getattr(nets[1], name), getattr(nets[key], name), err_msg=name)
        np.testing.assert_array_equal(nets[1].det.m_max_est, nets[key].det.m_max_est)
        for name, v in nets[1].stats.items():
            np.testing.assert_array_equal(v, nets[key].stats[name], err_msg=name)
    assert delivered > 0 and nets[1].stats["collisions"] > 0
