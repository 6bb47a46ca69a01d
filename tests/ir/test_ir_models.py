"""IR hardware models (swarm_envs.ir.models): [F14 Eqs. (19)-(22)], [T20 Eqs. (24),(25),(27)], r-one cones."""

import numpy as np
import pytest

from swarm_envs.ir.models import DropletIR, EpuckIR, RoneIR
from swarm_envs.sim.platforms import get_platform, model_for


def test_model_for_cached_and_by_name():
    p = get_platform("droplet")
    assert isinstance(model_for(p), DropletIR)
    assert model_for(p) is model_for("droplet") is p.ir_model
    assert isinstance(model_for("epuck"), EpuckIR)
    assert isinstance(model_for("rone"), RoneIR)
    with pytest.raises(ValueError):
        model_for(type("P", (), {"name": "nope", "extras": {}})())


def test_droplet_sensor_emitter_continuous_at_switch_points():
    m = DropletIR()
    for f, x0 in ((m.sensor, m.sensor_switch), (m.emitter, m.emitter_switch)):
        below, above = f(x0 - 1e-9), f(x0 + 1e-9)
        assert abs(below - above) < 1e-5
        # on both sides the two branches are used (not a single formula)
        assert f(0.0) > f(x0) > f(1.5)
    assert m.sensor(0.0) == pytest.approx(1.0)
    assert m.emitter(0.0) == pytest.approx(0.9375)
    # paper values: S(1) = 1/8, E(1) = 1/4
    assert m.sensor(1.0) == pytest.approx(0.125)
    assert m.emitter(1.0) == pytest.approx(0.25)


def test_droplet_models_symmetric_and_decreasing():
    m = DropletIR()
    a = np.linspace(0, np.pi, 400)
    np.testing.assert_allclose(m.sensor(a), m.sensor(-a))
    np.testing.assert_allclose(m.emitter(a), m.emitter(-a))
    assert np.all(np.diff(m.sensor(a)) < 0)
    # the fitted emitter peaks off-axis: E = 1 at |b| = 0.5 rad, decreasing beyond
    assert m.emitter(0.5) == pytest.approx(1.0)
    b = a[a >= 0.5]
    assert np.all(np.diff(m.emitter(b)) < 0)
    assert np.all(np.diff(m.emitter(a[a <= 0.5])) > 0)


def test_droplet_amplitude_fit_and_inverse():
    m = DropletIR()
    # the paper's fit exactly, in its valid range
    r = np.linspace(4.0, 100.0, 500)
    np.testing.assert_allclose(m.amplitude(r), 14000.0 / (r - 3.0) ** 2 - 1.0)
    # strictly decreasing including the near-range continuation, continuous at 4 cm
    rr = np.linspace(1.0, 110.0, 5000)
    assert np.all(np.diff(m.amplitude(rr)) < 0)
    assert abs(m.amplitude(4.0 - 1e-9) - m.amplitude(4.0)) < 1e-3
    # A(A^-1(x)) ~ x (the paper's inverse uses 118 ~ sqrt(14000): within 1 %)
    x = np.geomspace(1.0, 60000.0, 300)
    np.testing.assert_allclose(m.amplitude(m.amplitude_inverse(x)) + 1.0, x + 1.0, rtol=0.01)
    np.testing.assert_allclose(m.amplitude_inverse(m.amplitude(rr)), rr, rtol=0.01)
    # the inverse uses the paper's 118
    assert m.amplitude_inverse(99.0) == pytest.approx(118.0 / 10.0 + 3.0)


def test_droplet_gain_product_in_metres():
    m = DropletIR()
    g = m.gain(0.10, 0.3, -0.2)
    assert g == pytest.approx(m.sensor(0.3) * m.emitter(0.2) * m.amplitude(10.0))
    # broadcasting
    assert m.gain(np.ones((3, 1)) * 0.1, np.zeros((1, 4)), 0.0).shape == (3, 4)


def test_epuck_models():
    m = EpuckIR()
    assert m.emitter(0.0) == 1.0 and m.sensor(0.0) == 1.0
    assert m.emitter(np.pi / 2 + 1e-6) == 0.0 and m.sensor(-np.pi / 2 - 1e-6) == 0.0
    assert m.emitter(0.5) == pytest.approx(np.cos(0.5) ** 7)
    assert m.sensor(0.5) == pytest.approx(np.cos(0.5) ** 3)
    # medium: continuous at the saturation distance o_m^(-1/k_m)
    d0 = 1.12202 ** (1 / 1.54557)
    assert m.d_sat_cm == pytest.approx(d0)
    assert m.amplitude(d0 * (1 - 1e-9)) == 1.0
    assert m.amplitude(d0 * (1 + 1e-9)) == pytest.approx(1.0, abs=1e-6)
    assert m.amplitude(10.0) == pytest.approx(1.12202 * 10.0**-1.54557)
    d = np.geomspace(1.2, 150, 100)
    np.testing.assert_allclose(m.amplitude_inverse(m.amplitude(d)), d, rtol=1e-9)
    # gain uses metres and the [T20] letters by role: emitter angle ^7, detector angle ^3
    assert m.gain(0.1, 0.4, 0.2) == pytest.approx(np.cos(0.4) ** 3 * np.cos(0.2) ** 7 * m.amplitude(10.0))


def test_rone_binary_cones():
    m = model_for("rone")
    half = np.deg2rad(34.0)
    assert m.gain(0.5, 0.0, 0.0) == 1.0
    assert m.gain(0.5, half - 1e-3, -half + 1e-3) == 1.0
    assert m.gain(0.5, half + 1e-3, 0.0) == 0.0
    # transmitters light their outward half-plane [L Sec. 3.2.1 "radially uniform"; RoneIR]
    assert m.gain(0.5, 0.0, -half - 1e-3) == 1.0
    assert m.gain(0.5, 0.0, np.pi / 2 - 1e-3) == 1.0
    assert m.gain(0.5, 0.0, -np.pi / 2 - 1e-3) == 0.0
    assert m.gain(1.2, 0.0, 0.0) == 0.0
