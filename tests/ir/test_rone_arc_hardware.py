"""r-one receiver arcs as per-robot hardware [L Sec. 3.2.1, Fig. 3.9(b)]: law, seeding, copies."""

from __future__ import annotations

import numpy as np
import pytest

from swarm_envs.ir.layer import compute_links
from swarm_envs.sim.platforms import get_platform
from swarm_envs.sensing.bearing_sensor import (
    RONE_ARC_MEAN_DEG,
    RONE_ARC_RANGE_DEG,
    MessageBearings,
    arc_widths_deg,
    draw_half_arcs,
    pair_half_arcs,
)
from tests.sensing.test_rone_bearings import frames, triangle

RONE = get_platform("rone")


def test_arc_law_has_the_thesis_minimum_maximum_and_mean():
    """63 to 74 degrees with a mean of 68 [L Sec. 3.2.1]: the sample mean is within 4 standard errors."""
    arcs = draw_half_arcs(np.random.default_rng(0), 4000, RONE)
    assert np.all(arcs[:, 8:] == np.pi / 2)  # the transmitters keep their nominal half-plane (RoneIR)
    w = np.rad2deg(2.0 * arcs[:, :8])
    lo, hi = RONE_ARC_RANGE_DEG
    assert w.min() >= lo and w.max() <= hi
    mode = 3 * RONE_ARC_MEAN_DEG - lo - hi
    sd = np.sqrt((lo**2 + hi**2 + mode**2 - lo * hi - lo * mode - hi * mode) / 18.0)  # triangular law's std
    se = sd / np.sqrt(w.size)
    assert abs(w.mean() - RONE_ARC_MEAN_DEG) < 4 * se
    assert abs(w.std() - sd) < 0.05 * sd
    # the uniform law (mean None) would have mean 68.5, outside that band
    assert abs(arc_widths_deg(np.random.default_rng(1).random(w.size), RONE_ARC_RANGE_DEG).mean() - 68.5) < 4 * se
    assert abs(68.5 - RONE_ARC_MEAN_DEG) > 8 * se
    with pytest.raises(ValueError):
        arc_widths_deg(np.zeros(1), (63.0, 74.0), 73.0)  # no triangular law on 63-74 has mean 73


def test_pair_arcs_are_the_receivers_detectors_and_the_transmitters_emitters():
    arcs = np.arange(3 * 16, dtype=float).reshape(3, 16)
    out = pair_half_arcs(arcs, np.array([0, 2]), np.array([1, 0]), RONE)
    np.testing.assert_array_equal(out[0], np.r_[arcs[0, :8], arcs[1, 8:]])
    np.testing.assert_array_equal(out[1], np.r_[arcs[2, :8], arcs[0, 8:]])


def _mb(seed: int) -> MessageBearings:
    return MessageBearings(RONE, 3, np.random.default_rng(seed), arc_range=RONE_ARC_RANGE_DEG, arc_mean=RONE_ARC_MEAN_DEG)


def test_each_robot_keeps_its_arcs_for_every_frame_until_reset():
    pos, hd, links = triangle()
    mb = _mb(4)
    arcs = mb.half_arcs.copy()
    lo, hi = np.deg2rad(RONE_ARC_RANGE_DEG) / 2
    assert arcs.shape == (3, 16) and (arcs >= lo).all() and (arcs <= hi).all()
    assert np.unique(arcs).size == arcs.size  # every channel of every robot its own
    f = frames([0, 1, 2], [1, 2, 0], [1, 2, 0])
    mb.step(f, links)
    first = (mb.fresh.bearing.copy(), mb.fresh.heading.copy())
    for _ in range(5):
        mb.step(f, links)
        np.testing.assert_array_equal(mb.fresh.bearing, first[0])  # the same hardware: the same reading
        np.testing.assert_array_equal(mb.fresh.heading, first[1])
    np.testing.assert_array_equal(mb.half_arcs, arcs)  # frames draw nothing
    mb.reset(np.array([0]), [np.random.default_rng(5)])
    assert not np.array_equal(mb.half_arcs, arcs)  # a reset gives new robots


def test_arcs_are_deterministic_under_seeding_and_independent_across_copies():
    np.testing.assert_array_equal(_mb(7).half_arcs, _mb(7).half_arcs)
    assert not np.array_equal(_mb(7).half_arcs, _mb(8).half_arcs)
    two = MessageBearings(RONE, 3, None, n_copies=2, arc_range=RONE_ARC_RANGE_DEG, arc_mean=RONE_ARC_MEAN_DEG)
    two.reset(np.array([0, 1]), [np.random.default_rng(9), np.random.default_rng(7)])
    one9, one7 = _mb(9), _mb(7)
    np.testing.assert_array_equal(two.half_arcs[:3], one9.half_arcs)  # copy b's robots come from copy b's stream
    np.testing.assert_array_equal(two.half_arcs[3:], one7.half_arcs)
    keep = two.half_arcs[3:].copy()
    two.reset(np.array([0]), [np.random.default_rng(1)])  # resetting copy 0 leaves copy 1's robots alone
    np.testing.assert_array_equal(two.half_arcs[3:], keep)


def test_sector_error_from_the_arcs_is_unbiased_and_bounded_by_one_sector():
    """The thesis reports no bearing bias for the r-one; the arc spread moves boundary readings to the
    neighbouring sector either way, so the mean error stays near 0 and no reading errs by more than a
    sector plus the half-sector quantisation. Pairs closer than 13 cm (centre distance; overlapping or
    touching bodies in these random layouts) are left out: there the perimeter channels' parallax, not the
    arcs, sets the error (tests/ir/test_rone_close_range.py)."""
    from swarm_envs.sensing.bearing_sensor import sense_bearings

    rng = np.random.default_rng(2)
    errs = []
    for _ in range(20):
        n = 40
        pos = rng.uniform(0, 2.0, (n, 2))
        hd = rng.uniform(-np.pi, np.pi, n)
        links = compute_links(pos, hd, RONE, occlusion="none", drop_zero=False)
        arcs = draw_half_arcs(rng, n, RONE)
        rd = sense_bearings(links, RONE, half_arcs=pair_half_arcs(arcs, links.rx, links.tx, RONE))
        ok = rd.valid & (links.distance <= RONE.ir_range) & (links.distance >= 0.13)
        errs.append(np.angle(np.exp(1j * (rd.bearing[ok] - links.bearing[ok]))))
    e = np.rad2deg(np.concatenate(errs))
    assert e.size > 5000
    assert abs(e.mean()) < 4 * e.std() / np.sqrt(e.size)
    assert np.abs(e).max() <= 22.5 + 11.25 + 1e-6


def test_the_env_draws_each_robots_arcs_from_its_seed():
    from tests.sensing.test_rone_bearings import full_stack

    a = full_stack(4, seed=3).bearings.half_arcs
    np.testing.assert_array_equal(a, full_stack(4, seed=3).bearings.half_arcs)
    assert not np.array_equal(a, full_stack(4, seed=4).bearings.half_arcs)
    assert a.shape == (4, 16)
    assert full_stack(4, seed=3, bearing_noise=False).bearings.half_arcs is None
