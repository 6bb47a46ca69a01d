"""Per-robot hardware variation of the IR channels (swarm_envs.ir.hardware, docs/design.md#hardware-variation):
drawn per robot at reset, applied to the true gains (range & bearing and SwarmCom), never to the estimator."""

from __future__ import annotations

import numpy as np
import pytest

from swarm_envs.ir import layer
from swarm_envs.ir.hardware import Hardware, draw_hardware
from swarm_envs.ir.models import DropletLowPowerIR
from swarm_envs.sim.platforms import get_platform
from swarm_envs.sensing.range_bearing_model import read
from swarm_envs.validate.envs import scene_core


def _pairs(platform, rng, P):
    R = rng.uniform(-1.1, 1.1, (P, 2)) * platform.ir_range
    R[: P // 10] = rng.uniform(-1, 1, (P // 10, 2)) * 3 * platform.radius
    return R, rng.uniform(-np.pi, np.pi, P)


def _sequential_sums(gains):
    out = np.zeros(gains.shape[:2])
    for j in range(gains.shape[2]):
        out += gains[:, :, j]
    return out


@pytest.mark.parametrize("name", ["droplet", "droplet_low", "epuck", "rone"])
def test_varied_gains_equal_the_numpy_reference(name):
    """Compiled kernel == numpy reference with per-pair channel multipliers and axis offsets (large spreads,
    so that rays near the e-puck's and r-one's cut-offs change side)."""
    platform = get_platform(name.split("_")[0])
    model = DropletLowPowerIR(platform) if name == "droplet_low" else platform.ir_model
    rng = np.random.default_rng(12)
    R, psi = _pairs(platform, rng, 3000)
    hw = draw_hardware(rng, len(R), platform, 0.3, 0.3, 10.0)
    fast = layer.pair_gains(R, psi, platform, model=model, hardware=hw)
    ref = layer._pair_gains_numpy(R, psi, platform, model, hw)
    nominal = layer._pair_gains_numpy(R, psi, platform, model)
    assert (ref > 0).sum() > 1000
    np.testing.assert_allclose(fast, ref, rtol=1e-9, atol=1e-12)
    np.testing.assert_array_equal(fast > 0, ref > 0)
    if name != "rone":  # binary arcs: a multiplier changes no 0/1 gain's zero-ness, but offsets do
        assert not np.allclose(fast, nominal, rtol=1e-3)


@pytest.mark.parametrize("name", ["droplet", "epuck"])
def test_nominal_hardware_gives_exactly_the_nominal_links(name):
    platform = get_platform(name)
    rng = np.random.default_rng(13)
    n = 60
    pos = rng.uniform(0, 4 * platform.ir_range / 3, (n, 2))
    hd = rng.uniform(-np.pi, np.pi, n)
    a = layer.compute_links(pos, hd, platform)
    b = layer.compute_links(pos, hd, platform, hardware=Hardware.nominal(n, platform))
    for f in ("rx", "tx", "gains", "emitter_sums"):
        np.testing.assert_array_equal(getattr(a, f), getattr(b, f))


@pytest.mark.parametrize("name", ["droplet", "epuck"])
def test_links_carry_each_robots_own_channels_serial_and_threaded(name, monkeypatch):
    """compute_links with per-robot hardware: each link's gains are those of its receiver's detectors and its
    transmitter's emitters (pair_gains with the pairs' rows), the emitter sums SwarmCom reads are those gains
    summed, and the threaded kernel gives the same links bit for bit."""
    platform = get_platform(name)
    rng = np.random.default_rng(14)
    n = 300
    pos = rng.uniform(0, 3 * platform.ir_range, (n, 2))
    hd = rng.uniform(-np.pi, np.pi, n)
    hw = draw_hardware(rng, n, platform, 0.1, 0.1, 3.0)
    links = layer.compute_links(pos, hd, platform, hardware=hw, occlusion="none")
    assert len(links) > 500
    expect = layer.pair_gains(links.rel_position, links.rel_heading, platform, hardware=hw.pairs(links.rx, links.tx))
    np.testing.assert_allclose(links.gains, expect, rtol=1e-9, atol=1e-12)
    np.testing.assert_array_equal(links.emitter_sums, _sequential_sums(links.gains))
    nominal = layer.pair_gains(links.rel_position, links.rel_heading, platform)
    assert not np.allclose(links.emitter_sums, _sequential_sums(nominal), rtol=1e-3)
    serial = layer.compute_links(pos, hd, platform, hardware=hw)
    monkeypatch.setattr(layer, "gain_threads", lambda n_pairs: 3)
    threaded = layer.compute_links(pos, hd, platform, hardware=hw)
    for f in ("rx", "tx", "gains", "emitter_sums"):
        np.testing.assert_array_equal(getattr(serial, f), getattr(threaded, f))


def test_draws_are_per_robot_fixed_in_count_and_scaled_by_the_spreads():
    platform = get_platform("droplet")
    a = draw_hardware(np.random.default_rng(1), 500, platform, 0.1, 0.2, 3.0)
    b = draw_hardware(np.random.default_rng(1), 500, platform, 0.0, 0.0, 0.0)
    assert np.all(b.emitter_gain == 1.0) and np.all(b.detector_gain == 1.0) and np.all(b.detector_offset == 0.0)
    np.testing.assert_allclose(np.log(a.emitter_gain).std(), 0.1, rtol=0.1)
    np.testing.assert_allclose(np.log(a.detector_gain).std(), 0.2, rtol=0.1)
    np.testing.assert_allclose(np.degrees(a.emitter_offset).std(), 3.0, rtol=0.1)
    np.testing.assert_allclose(np.degrees(a.detector_offset).std(), 3.0, rtol=0.1)
    # the same stream positions whatever the spreads: z is drawn once per reset
    np.testing.assert_allclose(np.log(a.detector_gain) / 0.2, np.log(draw_hardware(np.random.default_rng(1), 500, platform, 1.0, 1.0, 1.0).detector_gain))


def _pair_core(seed, **settings):
    """One static Droplet pair in the env: robot 0 at the origin facing +x, robot 1 10 cm away."""
    pos = np.array([[0.0, 0.0], [0.06, 0.08]])
    hd = np.array([0.0, 2.0])
    cfg = dict(platform="droplet", n_robots=2, sensing="full", arena_size=1.0, rb_noise=0.0, rb_schedule="every_step")
    return scene_core("swarm_envs/Aggregation-v0", [pos], [hd], [seed], **{**cfg, **settings}), pos, hd


def test_the_env_draws_each_robots_channels_at_reset_and_the_estimator_keeps_the_nominal_calibration():
    """Default env (hw_variation=True): each robot has its own channels, drawn at reset from the seed; the
    reading robot 0 takes of robot 1 (noise-free, measured alone) is the estimate of the brightness of
    robot 0's detectors and robot 1's emitters, inverted with the nominal models, so it differs from the
    nominal pair's reading. hw_variation=False gives exactly the nominal reading."""
    core, pos, hd = _pair_core(5)
    hw = core.sensing.hardware
    assert hw is not None and len(hw) == 2
    assert not np.allclose(hw.emitter_gain[0], hw.emitter_gain[1])
    again, *_ = _pair_core(5)
    other, *_ = _pair_core(6)
    np.testing.assert_array_equal(again.sensing.hardware.emitter_offset, hw.emitter_offset)
    assert not np.array_equal(other.sensing.hardware.emitter_offset, hw.emitter_offset)

    rel = pos[1][None, :]  # robot 1 in robot 0's frame (robot 0 faces +x at the origin)
    rh = np.array([hd[1] - hd[0]])
    platform = get_platform("droplet")
    varied = read(layer.pair_gains(rel, rh, platform, hardware=hw.pairs([0], [1])), rel, rh, np.random.default_rng(0), 0.0, platform)
    nominal = read(layer.pair_gains(rel, rh, platform), rel, rh, np.random.default_rng(0), 0.0, platform)

    def reading(c):
        nb = c.frame.neighbours
        k = np.flatnonzero((nb.rx == 0) & (nb.tx == 1))
        assert k.size == 1
        return nb.range[k[0]], nb.bearing[k[0]], nb.heading[k[0]]

    got = reading(core)
    np.testing.assert_allclose(got, [v[0] for v in varied[:3]], rtol=1e-12)
    assert abs(got[0] - nominal[0][0]) > 1e-4 or abs(got[1] - nominal[1][0]) > 1e-4
    off, *_ = _pair_core(5, hw_variation=False)
    assert off.sensing.hardware is None
    np.testing.assert_allclose(reading(off), [v[0] for v in nominal[:3]], rtol=1e-12)


def test_rone_has_no_hardware_variation():
    pos = np.array([[0.0, 0.0], [0.2, 0.0]])
    core = scene_core("swarm_envs/Aggregation-v0", [pos], [np.zeros(2)], [1], platform="rone", n_robots=2, sensing="full", arena_size=2.0)
    assert core.sensing.hardware is None
