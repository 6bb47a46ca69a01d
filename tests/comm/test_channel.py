"""SwarmCom channel [T20 Sec. 3]: received intensity against hand-computed gains, ADC, occlusion."""

import numpy as np
import pytest

from swarm_envs.comm.channel import ADCModel, adc, adc_model_for, detector_intensity
from swarm_envs.ir.layer import compute_links
from swarm_envs.sim.platforms import get_platform


def _hand_intensity(d_m: float) -> np.ndarray:
    """Facing pair: receiver at the origin heading 0, transmitter at (d, 0) heading pi.
    Direct use of [T20 Eqs. (3)-(5), (7), (8)-(14), (24), (25), (27)] in cm."""
    p = get_platform("epuck")
    e_loc = p.emitter_positions * 100.0
    d_loc = p.detector_positions * 100.0
    th = p.emitter_directions
    # transmitter rotated by pi and shifted to (100 d, 0)
    e_w = -e_loc + np.array([100.0 * d_m, 0.0])
    th_e = th + np.pi
    y = np.zeros(8)
    for j in range(8):  # detector j of the receiver
        for i in range(8):  # emitter i of the transmitter
            v = d_loc[j] - e_w[i]
            alpha = th_e[i] - np.arctan2(v[1], v[0])  # Eq. (3)
            beta = np.arctan2(-v[1], -v[0]) - p.detector_directions[j]  # Eq. (4)
            alpha = (alpha + np.pi) % (2 * np.pi) - np.pi
            beta = (beta + np.pi) % (2 * np.pi) - np.pi
            dist = np.hypot(*v)  # Eq. (5), cm
            he = abs(np.cos(alpha)) ** 7 if abs(alpha) <= np.pi / 2 else 0.0
            hd = abs(np.cos(beta)) ** 3 if abs(beta) <= np.pi / 2 else 0.0
            hm = 1.0 if dist <= 1.12202 ** (1 / 1.54557) else 1.12202 * dist**-1.54557
            y[j] += he * hm * hd
    return np.minimum(1.0, y)


@pytest.mark.parametrize("d", [0.10, 0.25])
def test_facing_pair_matches_hand_computation(d):
    y = detector_intensity(np.array([d, 0.0]), np.pi, np.zeros(2), 0.0, "epuck")
    ref = _hand_intensity(d)
    assert y.shape == (8,)
    np.testing.assert_allclose(y, ref, rtol=1e-9, atol=1e-15)
    # front detectors (ps0, ps7) see most light; rear ones see none
    assert set(np.argsort(y)[-2:]) == {0, 7}
    assert y[3] == 0.0 and y[4] == 0.0
    # at 10 cm the front detectors get ~ h_m(10 cm) ~ 0.03-0.06 of full scale
    if d == 0.10:
        assert 0.02 < y.max() < 0.1


def test_intensity_broadcasts_and_falls_with_distance():
    d = np.array([0.1, 0.2, 0.4, 0.8])
    tx = np.stack([d, np.zeros(4)], -1)
    y = detector_intensity(tx, np.pi, np.zeros(2), 0.0, "epuck")
    assert y.shape == (4, 8)
    assert np.all(np.diff(y.max(axis=1)) < 0)
    # touching robots saturate nothing beyond 1
    y0 = detector_intensity(np.array([0.07, 0.0]), np.pi, np.zeros(2), 0.0, "epuck")
    assert y0.max() <= 1.0


def test_adc_quantisation_and_clipping(rng):
    # noiseless: Eq. (21)
    m = adc(np.array([0.0, 1.0, 2.0, 0.5, 0.001]), rng, noise_var=0.0)
    assert m.tolist() == [4080, 150, 150, 2115, int(np.floor(3930 * 0.999 + 150))]
    assert m.dtype == np.int32
    # clipping to [0, 4095]
    assert adc(np.array([0.0]), rng, m_max=5000.0, noise_var=0.0)[0] == 4095
    assert adc(np.array([1.0]), rng, m_min=-10.0, noise_var=0.0)[0] == 0
    # noise: floor(4080 + N(0, 2.5)) has mean ~4079.5 and variance ~2.5 + 1/12
    s = adc(np.zeros(200_000), rng)
    assert abs(s.mean() - 4079.5) < 0.02
    assert abs(s.var() - (2.5 + 1 / 12)) < 0.05
    assert np.all(s == np.floor(s))


def test_adc_model_for_platforms():
    e = adc_model_for("epuck")
    assert (e.m_max, e.m_min, e.m_sup, e.noise_var, e.intensity_scale) == (4080.0, 150.0, 4095, 2.5, 1.0)
    d = adc_model_for("droplet")
    assert d.m_max == 255.0 and d.m_min == 0.0 and np.isclose(d.intensity_scale, 1 / 255)
    r = adc_model_for("rone")
    assert r.noise_var == 0.0 and r.intensity_scale == 1.0 and r.m_max - r.m_min > 100
    assert isinstance(e, ADCModel)


def test_blocked_line_of_sight_carries_nothing():
    # A -- B -- C in a row: B occludes A from C
    pos = np.array([[0.0, 0.0], [0.15, 0.0], [0.30, 0.0]])
    links = compute_links(pos, np.array([0.0, 0.0, np.pi]), "epuck")
    pairs = set(zip(links.rx.tolist(), links.tx.tolist()))
    assert (1, 0) in pairs and (2, 1) in pairs
    assert (2, 0) not in pairs and (0, 2) not in pairs
    # without the blocker, C would receive A well above threshold
    y = detector_intensity(pos[0], 0.0, pos[2], np.pi, "epuck")
    assert y.max() * 3930 > 20  # counts, far above m_tr = 5
