"""r-one sector bearing sensor [L Sec. 3.2.1, 3.2.3]: firmware longest-run rule and link-level readings."""

from __future__ import annotations

import numpy as np
import pytest

from swarm_envs.ir.layer import compute_links
from swarm_envs.sensing.bearing_sensor import (
    RONE_TX_ANGLES,
    run_mask,
    sector_bearing,
    sector_lut,
    sense_bearings,
)


def deg(x):
    return np.rad2deg(np.mod(x, 2 * np.pi))


@pytest.mark.parametrize("k", range(8))
def test_single_receiver_gives_its_axis(k):
    assert deg(sector_bearing(1 << k)) == pytest.approx(22.5 + 45 * k)


@pytest.mark.parametrize("k", range(7))
def test_adjacent_receivers_give_midpoint(k):
    assert deg(sector_bearing(3 << k)) == pytest.approx(45.0 * (k + 1))


def test_wrap_around_and_longest_run():
    # receivers 7 and 0 are adjacent: midpoint of 337.5 and 22.5 = 0 deg
    assert sector_bearing(0b10000001) == pytest.approx(0.0, abs=1e-12)
    # 6, 7, 0 -> middle axis 337.5
    assert deg(sector_bearing(0b11000001)) == pytest.approx(337.5)
    # run {4, 5} beats the lone receiver 0
    assert deg(sector_bearing(0b00110001)) == pytest.approx(225.0)
    # three in a row -> middle axis
    assert deg(sector_bearing(0b00000111)) == pytest.approx(67.5)
    # tie between single receivers 0 and 4 -> the run starting at the lower index
    assert deg(sector_bearing(0b00010001)) == pytest.approx(22.5)
    assert np.isnan(sector_bearing(0)) and np.isnan(sector_bearing(255))
    assert run_mask(0b10110011) == 0b10000011  # {7, 0, 1} is longer than {4, 5}


def test_lut_is_16_sectors_and_vectorised():
    lut = sector_lut()
    vals = np.unique(np.round(deg(lut[np.isfinite(lut)]), 6) % 360)
    assert len(vals) == 16
    np.testing.assert_allclose(np.diff(vals), 22.5)
    masks = np.arange(256).reshape(16, 16)
    np.testing.assert_array_equal(sector_bearing(masks), lut[masks])
    # transmitter rule: single transmitter k -> 45 k degrees
    assert deg(sector_bearing(1 << 3, RONE_TX_ANGLES)) == pytest.approx(135.0)


def test_link_readings_quantise_bearing_and_heading():
    rng = np.random.default_rng(0)
    n = 200
    ang = rng.uniform(-np.pi, np.pi, n)
    dist = rng.uniform(0.4, 0.9, n)
    errs, herrs = [], []
    for a, d in zip(ang, dist):
        pos = np.array([[0.0, 0.0], [d * np.cos(a), d * np.sin(a)]])
        hd = rng.uniform(-np.pi, np.pi, 2)
        links = compute_links(pos, hd, "rone")
        r = sense_bearings(links, "rone")
        assert len(r) == 2 and r.valid.all()
        e = np.abs(np.pi - np.mod(np.pi - (r.bearing - links.bearing), 2 * np.pi))
        he = np.abs(np.pi - np.mod(np.pi - (r.heading - links.rel_heading), 2 * np.pi))
        errs.extend(e)
        herrs.extend(he)
    errs, herrs = np.rad2deg(errs), np.rad2deg(herrs)
    # half a sector (11.25 deg) plus the parallax of receivers 5 cm off-centre at >= 0.4 m (< 8 deg)
    assert errs.max() < 11.25 + 8.0
    assert 3.0 < errs.mean() < 9.0  # ~uniform quantisation error, mean ~5.6 deg
    assert herrs.max() < 2 * (11.25 + 8.0)
    # every reported bearing is one of the 16 sector angles
    q = np.rad2deg(r.bearing) / 22.5
    np.testing.assert_allclose(q, np.round(q), atol=1e-9)
