"""Bit-rate-dependent detector response (comm/channel.py ``detector_response``, docs/design.md#swarmcom-messaging, [T20 Secs. 5.3, 7])."""

import numpy as np
import pytest

from swarm_envs.comm.channel import ADCModel, adc_model_for, detector_response
from swarm_envs.comm.network import Network
from swarm_envs.sim.copies import CopyRandom
from swarm_envs.ir.layer import compute_links
from swarm_envs.validate.swarmcom_pairs import comm_range_cm, reliable_range_cm, run_pairs
from swarm_envs.validate.swarmcom_setup import SEP

RATES = (310, 650, 1160, 1800)


def test_response_is_the_exact_solution_of_the_circuit_ode():
    """One slot of detector_response equals a fine Euler integration of dv/dt = (y - v)(v + b)/c."""
    c, b, T = 2e-5, 0.01, 1 / 1800
    for v0, y in ((0.0, 0.04), (0.04, 0.0), (0.2, 0.9), (0.7, 0.1), (0.0, 1.0)):
        v = v0
        dt = T / 200_000
        for _ in range(200_000):
            v += dt * (y - v) * (v + b) / c
        assert detector_response(np.array(v0), np.array(y), T, c, b) == pytest.approx(v, abs=1e-4)


def test_weak_light_settles_slower_and_higher_rates_settle_less():
    """The detector's rate grows with its photocurrent: within one slot from dark, a weak signal reaches a
    smaller fraction of its final level than a strong one, and a shorter slot (higher bit rate) less."""
    a = adc_model_for("epuck")
    assert a.response_c > 0
    frac = {}
    for br in RATES:
        for y in (0.003, 0.04, 0.5):
            frac[br, y] = float(detector_response(np.zeros(1), np.full(1, y), 1 / br, a.response_c, a.response_bias)[0]) / y
    for br in RATES:
        assert frac[br, 0.003] < frac[br, 0.04] < frac[br, 0.5] <= 1.0
    for y in (0.003, 0.04):
        assert all(frac[lo, y] > frac[hi, y] for lo, hi in zip(RATES, RATES[1:]))
    # no response: instantaneous, clipped to [0, 1]
    np.testing.assert_array_equal(detector_response(np.zeros(3), np.array([-0.2, 0.3, 1.4]), 1e-3, 0.0, 0.01), [0.0, 0.3, 1.0])


def test_other_platforms_sample_instantly():
    assert adc_model_for("droplet").response_c == 0 and adc_model_for("rone").response_c == 0


def test_messages_stop_arriving_closer_as_the_bit_rate_grows():
    """Two e-pucks facing each other: the distance at which messages stop arriving (message loss > 0.5,
    the paper moves the receiver away until messages are lost [T20 Sec. 5.1]) and the reliable range
    (P_e < 0.01) shrink as the bit rate grows (310 > 650 > 1160 > 1800 bps)."""
    dist = np.arange(7.0, 90.0, 2.0) / 100
    comm, reliable = {}, {}
    for br in RATES:
        res = run_pairs(dist, np.random.default_rng(br), 40, bitrate=br)
        comm[br], reliable[br] = comm_range_cm(res), reliable_range_cm(res)
    assert all(comm[lo] > comm[hi] for lo, hi in zip(RATES, RATES[1:])), comm
    assert all(reliable[lo] > reliable[hi] for lo, hi in zip(RATES, RATES[1:])), reliable


def test_without_the_response_nothing_depends_on_bit_rate():
    """The instantaneous detector (response_c = 0) reaches the same reliable range at 310 and 1800 bps
    (no response model): the bit-rate dependence comes from the response only."""
    dist = np.arange(7.0, 70.0, 3.0) / 100
    r = {br: reliable_range_cm(run_pairs(dist, np.random.default_rng(1), 40, bitrate=br, adc_model=ADCModel(response_c=0.0))) for br in (310, 1800)}
    assert abs(r[310] - r[1800]) <= 6 and r[1800] > 40, r


def _pair_scene(copies: int, d: float = 0.1):
    pos = np.zeros((2 * copies, 2))
    pos[0::2, 0] = SEP * np.arange(copies) + d
    pos[1::2, 0] = SEP * np.arange(copies)
    head = np.zeros(2 * copies)
    head[0::2] = np.pi
    return pos, head


def test_response_state_resets_per_copy():
    """Network.reset_copies zeroes the detector levels of the restarted copies only, and a restarted copy
    then runs exactly like a fresh network with the same generator (no charge carried over)."""
    pos, head = _pair_scene(2)
    links = compute_links(pos, head, "epuck")
    net = Network("epuck", 2, CopyRandom([np.random.default_rng(0), np.random.default_rng(1)]), bitrate=1800, n_copies=2)
    net.send_many(np.array([0, 2]), np.ones((2, 200), bool))  # ~250 slots: still on air after a step
    net.step(links)
    assert (net.rx_level[[1, 3]] > 0).any(axis=1).all()  # both receivers' detectors are charged
    before = net.rx_level[2:].copy()
    net.reset_copies(np.array([0]), [np.random.default_rng(7)])
    assert (net.rx_level[:2] == 0).all()
    np.testing.assert_array_equal(net.rx_level[2:], before)
    fresh = Network("epuck", 2, np.random.default_rng(7), bitrate=1800)
    single = compute_links(pos[:2], head[:2], "epuck")
    for k in range(4):
        for nt in (net, fresh):
            nt.send_many(np.array([0]), np.ones((1, 30), bool))
        d = net.step(links)
        f = fresh.step(single)
        np.testing.assert_array_equal(net.rx_level[:2], fresh.rx_level)
        mine = d.receiver < 2
        np.testing.assert_array_equal(d.slot[mine], f.slot)
        np.testing.assert_array_equal(d.payload[mine][:, :30], f.payload[:, :30])
    assert fresh.stats["rx_delivered"] > 0


@pytest.mark.slow
def test_reliable_range_matches_the_paper_at_310_and_1800_bps():
    """Statistical check of the fitted model (c fitted to 14 cm at 1800 bps; 61 cm at 310 bps is a
    prediction): reliable range (P_e < 0.01) within 3 cm of [T20 Sec. 7] at both rates."""
    dist = np.arange(7.0, 75.0, 1.0) / 100
    r = {br: reliable_range_cm(run_pairs(dist, np.random.default_rng(2 + br), 300, bitrate=br)) for br in (310, 1800)}
    assert abs(r[310] - 61) <= 3 and abs(r[1800] - 14) <= 3, r
