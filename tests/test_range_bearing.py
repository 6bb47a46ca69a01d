"""Range & bearing from the brightness matrix [F14]: estimator, measurement, scheduling."""

import numpy as np
import pytest

from swarm_envs.geometry import wrap_angle
from swarm_envs.ir.layer import compute_links
from swarm_envs.platforms import get_platform
from swarm_envs.sensing.range_bearing import POWER_LADDER, RangeBearingSensor, brightness, estimate, measure, read

DROPLET = get_platform("droplet")


def random_geometry(rng, n, r_min, r_max):
    R = rng.uniform(r_min, r_max, n)
    theta = rng.uniform(-np.pi, np.pi, n)
    phi = rng.uniform(-np.pi, np.pi, n)
    return np.stack([R * np.cos(theta), R * np.sin(theta)], -1), theta, phi, R


def test_heading_sign_convention_geometric_truth():
    """Eq. (10) with the sign the PDF lost: phi = theta + pi - angle(tau)."""
    pos = np.array([[0.10, 0.0], [0.0, 0.12], [-0.09, -0.05]])
    headings = np.array([np.pi / 2, -2.5, 0.7])
    R, theta, phi = estimate(brightness(pos, headings, DROPLET), DROPLET)
    error = np.abs(np.degrees(wrap_angle(phi - headings)))
    assert np.all(error < 12.0)
    # the other sign of Eq. (10) mirrors the heading about the bearing: clearly worse in every case
    mirrored = np.abs(np.degrees(wrap_angle(2 * theta - phi - headings)))
    assert np.all(mirrored > error + 15.0)


def test_explicit_facing_pair():
    """TX 12 cm ahead, facing the RX: RX sensors 0/5 (+-30 deg) and TX emitters 0/5 (+-30 deg, towards the
    RX) are lit, brightest on the crossing diagonal (sensor 0 sees emitter 5 and vice versa)."""
    lam = brightness(np.array([[0.12, 0.0]]), np.array([np.pi]), DROPLET)[0]
    i, j = np.unravel_index(lam.argmax(), lam.shape)
    assert {int(i), int(j)} == {0, 5}
    assert lam[0, 5] == pytest.approx(lam[5, 0]) and lam[0, 5] > lam[0, 0] > lam[2, 2]
    R, theta, phi = estimate(lam[None], DROPLET)
    assert R[0] == pytest.approx(0.12, abs=0.01)
    assert abs(theta[0]) < np.radians(3) and abs(wrap_angle(phi[0] - np.pi)) < np.radians(10)


def test_noiseless_accuracy_over_random_geometries():
    rng = np.random.default_rng(0)
    pos, theta, phi, R = random_geometry(rng, 2000, 0.066, 0.20)
    est_R, est_theta, est_phi = estimate(brightness(pos, phi, DROPLET), DROPLET)
    range_err = est_R - R
    assert abs(range_err.mean()) + range_err.std() < 0.01  # well inside one diameter (4.4 cm)
    assert np.degrees(np.abs(wrap_angle(est_theta - theta))).max() < 20.0
    assert np.degrees(np.abs(wrap_angle(est_theta - theta))).mean() < 8.0
    assert np.degrees(np.abs(wrap_angle(est_phi - phi))).mean() < 10.0


def test_error_grows_with_noise():
    rng = np.random.default_rng(1)
    pos, theta, phi, R = random_geometry(rng, 3000, 0.10, 0.25)
    lam = brightness(pos, phi, DROPLET)
    spreads = []
    for sigma in (0.0, 2.0, 8.0):
        meas, p = measure(lam, np.random.default_rng(2), sigma, DROPLET)
        est_R, est_theta, _ = estimate(meas, DROPLET, power=p)
        ok = np.isfinite(est_R)
        spreads.append((np.std(est_R[ok] - R[ok]), np.std(wrap_angle(est_theta[ok] - theta[ok]))))
    assert spreads[0][0] < spreads[1][0] < spreads[2][0]
    assert spreads[0][1] < spreads[1][1] < spreads[2][1]


def test_no_reading_at_long_range_and_below_floor():
    pos = np.array([[0.05 + 0.0, 0.0], [0.6, 0.0], [0.0, 0.8]])
    pos[0] = [0.10, 0.0]
    R, theta, phi = estimate(brightness(pos, np.array([np.pi, np.pi, -np.pi / 2]), DROPLET), DROPLET)
    assert np.isfinite(R[0]) and np.isnan(R[1]) and np.isnan(R[2])
    assert np.isnan(theta[1]) and np.isnan(phi[2])
    assert np.isnan(estimate(np.full((1, 6, 6), 6.0), DROPLET)[0][0])  # all entries < 7 counts
    assert np.isfinite(estimate(np.full((1, 6, 6), 8.0), DROPLET)[0][0])


def test_power_selection_keeps_close_pairs_usable():
    """One radius of gap (R = 6.6 cm) saturates at full power; the re-fire at lower power keeps R&B usable."""
    rng = np.random.default_rng(3)
    pos, theta, phi, R = random_geometry(rng, 500, 0.066, 0.070)
    lam = brightness(pos, phi, DROPLET)
    assert (lam.reshape(500, -1).max(1) > 255).all()
    meas, p = measure(lam, rng, 2.0, DROPLET)
    assert (p < 1).all() and set(np.unique(p)) <= set(POWER_LADDER)
    assert (meas * p[:, None, None]).max() < 255  # the kept reading did not saturate
    est_R, _, _ = estimate(meas, DROPLET, power=p)
    err = est_R - R
    assert abs(err.mean()) + err.std() < DROPLET.diameter


def test_measurement_rounds_and_clips():
    lam = np.full((1, 6, 6), 10.4)
    meas, p = measure(lam, np.random.default_rng(0), 0.0, DROPLET)
    assert p[0] == 1.0 and np.all(meas == 10.0)


def test_vectorised_estimate_equals_per_matrix_loop():
    rng = np.random.default_rng(4)
    pos, _, phi, _ = random_geometry(rng, 50, 0.066, 0.4)
    meas, p = measure(brightness(pos, phi, DROPLET), rng, 2.0, DROPLET)
    batch = estimate(meas, DROPLET, power=p)
    for k in range(50):
        single = estimate(meas[k : k + 1], DROPLET, power=p[k : k + 1])
        for a, b in zip(batch, single):
            np.testing.assert_allclose(a[k], b[0], rtol=1e-12, equal_nan=True)


@pytest.mark.parametrize("platform", ["droplet", "epuck"])
def test_estimator_generalises_to_the_epuck(platform):
    plat = get_platform(platform)
    rng = np.random.default_rng(5)
    pos, theta, phi, R = random_geometry(rng, 1000, 1.5 * plat.diameter, 3 * plat.diameter)
    est_R, est_theta, _ = estimate(brightness(pos, phi, plat), plat)
    err = est_R - R
    # [F14] claims the method generalises to any circular robot with n channels: within one diameter here
    assert abs(np.nanmean(err)) + np.nanstd(err) < plat.diameter
    assert np.degrees(np.nanmean(np.abs(wrap_angle(est_theta - theta)))) < 15.0


def scene(n=30, side=0.6, seed=0):
    rng = np.random.default_rng(seed)
    pos = []
    while len(pos) < n:
        q = rng.uniform(0, side, 2)
        if all(np.hypot(*(q - o)) > 2.2 * DROPLET.radius for o in pos):
            pos.append(q)
    return np.array(pos), rng.uniform(-np.pi, np.pi, n)


def test_contention_never_fires_two_linked_robots():
    pos, hd = scene()
    links = compute_links(pos, hd, DROPLET)
    sensor = RangeBearingSensor(DROPLET, len(pos), np.random.default_rng(0))
    for _ in range(20):
        fired = sensor.fire_mask(links)
        assert fired.any()
        assert not np.any(fired[links.rx] & fired[links.tx])
        # maximal: every silent robot has a firing neighbour
        silent = np.flatnonzero(~fired)
        has_firing_neighbour = np.zeros(len(pos), bool)
        has_firing_neighbour[links.rx[fired[links.tx]]] = True
        assert has_firing_neighbour[silent].all()


def test_readings_age_and_drop_out():
    pos, hd = scene(12, 0.4, seed=1)
    links = compute_links(pos, hd, DROPLET)
    sensor = RangeBearingSensor(DROPLET, len(pos), np.random.default_rng(1), max_age=3)
    r = sensor.step(links)
    assert len(r) and np.all(r.age == 0)
    empty = compute_links(pos[:1], hd[:1], DROPLET)  # all neighbours lost
    ages = []
    for _ in range(5):
        kept = sensor.step(empty)
        ages.append(int(kept.age.max()) if len(kept) else None)
    assert ages == [1, 2, 3, None, None]


def test_every_step_schedule_reads_all_links_each_step():
    pos, hd = scene(15, 0.4, seed=2)
    links = compute_links(pos, hd, DROPLET)
    sensor = RangeBearingSensor(DROPLET, len(pos), np.random.default_rng(0), schedule="every_step")
    r = sensor.step(links)
    assert np.all(r.age == 0)
    assert len(r) >= 0.9 * len(links)


def test_sensor_is_deterministic_for_a_seed():
    pos, hd = scene(20, 0.5, seed=3)
    links = compute_links(pos, hd, DROPLET)
    a = RangeBearingSensor(DROPLET, 20, np.random.default_rng(9))
    b = RangeBearingSensor(DROPLET, 20, np.random.default_rng(9))
    for _ in range(5):
        ra, rb = a.step(links), b.step(links)
        for f in ("rx", "tx", "range", "bearing", "heading", "age"):
            np.testing.assert_array_equal(getattr(ra, f), getattr(rb, f))


def test_rone_has_no_range_model():
    with pytest.raises(ValueError, match="no range & bearing"):
        estimate(np.ones((1, 8, 8)), get_platform("rone"))


def test_low_power_near_model_matches_the_firmware_fit_and_inverts():
    from swarm_envs.ir.models import DropletLowPowerIR

    low = DropletLowPowerIR(DROPLET)
    R = np.linspace(5.0, 14.0, 10)  # centre distance (cm); facing emitter-sensor distance r = R - 2 rho
    np.testing.assert_allclose(low.amplitude(R - 4.0), 1100.0 / (R - 4.0) ** 2 + 12.5)
    x = low.amplitude(np.linspace(1.0, 30.0, 20))
    np.testing.assert_allclose(low.amplitude_inverse(x), np.linspace(1.0, 30.0, 20))
    assert np.isinf(low.amplitude_inverse(12.0))


def test_near_model_option_reads_close_pairs_without_the_ladder():
    rng = np.random.default_rng(6)
    pos, theta, phi, R = random_geometry(rng, 800, 0.066, 0.12)
    lam = brightness(pos, phi, DROPLET)
    est_R, est_theta, _, p = read(lam, pos, phi, rng, 2.0, DROPLET, near_model=True)
    assert np.isnan(p).mean() > 0.9  # nearly all saturate at full power and use the low-power fit
    err = est_R - R
    assert np.isfinite(est_R).all()
    assert abs(err.mean()) + err.std() < DROPLET.diameter
    assert np.degrees(np.abs(wrap_angle(est_theta - theta))).mean() < 10.0
    with pytest.raises(ValueError, match="low-power"):
        RangeBearingSensor("epuck", 2, rng, near_model=True)
