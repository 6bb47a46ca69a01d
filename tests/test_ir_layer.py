"""Shared IR physical layer (swarm_envs.ir.layer), SPEC 2."""

import math

import numpy as np
import pytest

from swarm_envs.ir.layer import compute_links, line_of_sight, pair_gains, pair_geometry, wrap_angle
from swarm_envs.platforms import get_platform

DROPLET = get_platform("droplet")


def test_wrap_angle_range():
    a = np.array([-3 * np.pi, -np.pi, 0.0, np.pi, 3 * np.pi, 7.0])
    w = wrap_angle(a)
    assert np.all(w > -np.pi) and np.all(w <= np.pi)
    np.testing.assert_allclose(np.cos(w), np.cos(a), atol=1e-12)
    assert w[1] == pytest.approx(np.pi) and w[3] == pytest.approx(np.pi)


def test_droplet_facing_pair_geometry():
    # RX at origin facing +x; TX 10 cm ahead facing back (-x). RX sensor 0 (30 deg) and TX emitter 5
    # (30 + 300 deg, i.e. 150 deg in RX frame) are mirror images: 6.54 cm apart on the x-axis.
    d, det, em = pair_geometry(np.array([[0.10, 0.0]]), np.array([np.pi]), DROPLET)
    assert d[0, 0, 5] == pytest.approx(0.10 - 2 * 0.02 * math.cos(math.radians(30)))
    assert det[0, 0, 5] == pytest.approx(math.radians(-30))
    assert em[0, 0, 5] == pytest.approx(math.radians(30))
    g = pair_gains(np.array([[0.10, 0.0]]), np.array([np.pi]), DROPLET)[0]
    # strongest entries: sensors 0 and 5 (the two facing TX) with TX emitters 5 and 0 (facing RX)
    i, j = np.unravel_index(np.argmax(g), g.shape)
    assert (int(i), int(j)) in ((0, 5), (5, 0))
    assert g[0, 5] == pytest.approx(g[5, 0])
    # the sensors on RX's back (2, 3) see far less than the front ones
    assert g[2:4].max() < 0.01 * g.max()
    # mirror symmetry about the x-axis maps channel k to channel 5 - k
    np.testing.assert_allclose(g, g[::-1, ::-1], rtol=1e-9)
    # the scene is symmetric under swapping the robots: TX sees RX with the same matrix
    np.testing.assert_allclose(pair_gains(np.array([[0.10, 0.0]]), np.array([-np.pi]), DROPLET)[0], g, rtol=1e-9)


def test_droplet_tx_turned_away():
    # TX 10 cm ahead facing +x (its back towards RX): RX front sensors see TX emitters 2, 3 (150, 210 deg)
    g = pair_gains(np.array([[0.10, 0.0]]), np.array([0.0]), DROPLET)[0]
    i, j = np.unravel_index(np.argmax(g), g.shape)
    assert i in (0, 5) and j in (2, 3)


def test_epuck_front_sensors_face_each_other():
    ep = get_platform("epuck")
    g = pair_gains(np.array([[0.12, 0.0]]), np.array([np.pi]), ep)[0]
    i, j = np.unravel_index(np.argmax(g), g.shape)
    assert i in (0, 7) and j in (0, 7)
    # rear detectors (ps3, ps4) face away: directivity is zero beyond 90 degrees
    assert g[3].max() == 0.0 and g[4].max() == 0.0


def test_rone_binary_sectors():
    rone = get_platform("rone")
    g = pair_gains(np.array([[0.5, 0.0]]), np.array([np.pi]), rone)[0]
    # bearing 0 lies in receivers 0 (22.5 deg) and 7 (-22.5 deg); TX faces RX (heading pi), so its
    # forward transmitter 0 points at RX and its neighbours (45 deg off) miss it
    assert {(int(a), int(b)) for a, b in zip(*np.nonzero(g))} == {(0, 0), (7, 0)}
    assert set(np.unique(g)) == {0.0, 1.0}
    # beyond ir_range (centre distance) nothing
    assert pair_gains(np.array([[1.05, 0.0]]), np.array([np.pi]), rone).max() == 0.0


def test_links_both_directions_and_relative_frames():
    pos = np.array([[0.0, 0.0], [0.1, 0.05]])
    hd = np.array([0.3, 2.9])
    L = compute_links(pos, hd, DROPLET)
    assert sorted(zip(L.rx.tolist(), L.tx.tolist())) == [(0, 1), (1, 0)]
    k = int(np.nonzero(L.rx == 0)[0][0])
    d = pos[1] - pos[0]
    c, s = math.cos(0.3), math.sin(0.3)
    np.testing.assert_allclose(L.rel_position[k], [c * d[0] + s * d[1], -s * d[0] + c * d[1]])
    assert L.rel_heading[k] == pytest.approx(wrap_angle(2.6))
    assert L.rel_heading[1 - k] == pytest.approx(wrap_angle(-2.6))
    assert L.distance[k] == pytest.approx(np.hypot(*d))
    np.testing.assert_allclose(L.gains[k], pair_gains(L.rel_position[k : k + 1], L.rel_heading[k : k + 1], DROPLET)[0])


def test_occlusion_third_robot_blocks_and_moving_it_restores():
    pos = np.array([[0.0, 0.0], [0.20, 0.0], [0.10, 0.0]])
    hd = np.zeros(3)
    L = compute_links(pos, hd, DROPLET)
    pairs = set(zip(L.rx.tolist(), L.tx.tolist()))
    assert (0, 1) not in pairs and (1, 0) not in pairs
    assert {(0, 2), (2, 0), (1, 2), (2, 1)} <= pairs
    # just touching the line (centre 1 radius + 1 mm off the segment): no longer blocking
    pos[2] = [0.10, DROPLET.radius + 0.001]
    L = compute_links(pos, hd, DROPLET)
    pairs = set(zip(L.rx.tolist(), L.tx.tolist()))
    assert (0, 1) in pairs and (1, 0) in pairs
    # slightly inside: blocked again
    pos[2] = [0.10, DROPLET.radius - 0.001]
    L = compute_links(pos, hd, DROPLET)
    assert (0, 1) not in set(zip(L.rx.tolist(), L.tx.tolist()))
    # beyond the segment's end (behind robot 1) it does not block
    pos[2] = [0.26, 0.0]
    L = compute_links(pos, hd, DROPLET)
    assert (0, 1) in set(zip(L.rx.tolist(), L.tx.tolist()))


def _reference_links(pos, hd, platform):
    """Plain per-pair Python reference of SPEC 2 (brute-force pairs and occluders)."""
    model = platform.ir_model
    n = len(pos)
    out = {}
    for u in range(n):
        for w in range(n):
            if u == w:
                continue
            R = pos[w] - pos[u]
            if math.hypot(*R) > platform.ir_range:
                continue
            blocked = False
            for k in range(n):
                if k in (u, w):
                    continue
                seg = pos[w] - pos[u]
                t = min(1.0, max(0.0, float(np.dot(pos[k] - pos[u], seg) / np.dot(seg, seg))))
                if math.hypot(*(pos[u] + t * seg - pos[k])) < platform.radius:
                    blocked = True
            if blocked:
                continue
            G = np.zeros((platform.n_detectors, platform.n_emitters))
            for i in range(platform.n_detectors):
                for j in range(platform.n_emitters):
                    # world-frame emitter and detector positions and axes
                    ch, sh = math.cos(hd[u]), math.sin(hd[u])
                    dp = pos[u] + np.array([ch * platform.detector_positions[i, 0] - sh * platform.detector_positions[i, 1],
                                            sh * platform.detector_positions[i, 0] + ch * platform.detector_positions[i, 1]])
                    cw, sw = math.cos(hd[w]), math.sin(hd[w])
                    ep = pos[w] + np.array([cw * platform.emitter_positions[j, 0] - sw * platform.emitter_positions[j, 1],
                                            sw * platform.emitter_positions[j, 0] + cw * platform.emitter_positions[j, 1]])
                    r = ep - dp
                    da = math.atan2(r[1], r[0]) - (hd[u] + platform.detector_directions[i])
                    ea = math.atan2(-r[1], -r[0]) - (hd[w] + platform.emitter_directions[j])
                    da = math.atan2(math.sin(da), math.cos(da))
                    ea = math.atan2(math.sin(ea), math.cos(ea))
                    G[i, j] = float(model.gain(math.hypot(*r), da, ea))
            if G.max() > 0:
                out[(u, w)] = G
    return out


@pytest.mark.parametrize("name", ["droplet", "epuck", "rone"])
def test_vectorised_equals_loop_reference(name):
    platform = get_platform(name)
    rng = np.random.default_rng(7)
    n = 25
    side = 6 * platform.ir_range / 4
    # non-overlapping random scene
    pos = []
    while len(pos) < n:
        p = rng.uniform(0, side, 2)
        if all(np.hypot(*(p - q)) > 2 * platform.radius for q in pos):
            pos.append(p)
    pos = np.array(pos)
    hd = rng.uniform(-np.pi, np.pi, n)
    ref = _reference_links(pos, hd, platform)
    L = compute_links(pos, hd, platform)
    got = {(int(a), int(b)): L.gains[k] for k, (a, b) in enumerate(zip(L.rx, L.tx))}
    assert set(got) == set(ref)
    assert len(ref) > 20  # the scene actually has links, and some occlusions are exercised below
    for key, G in ref.items():
        np.testing.assert_allclose(got[key], G, rtol=1e-9, atol=1e-12)


def test_line_of_sight_vectorised_matches_bruteforce():
    rng = np.random.default_rng(3)
    pos = rng.uniform(0, 0.5, (60, 2))
    i, j = np.triu_indices(60, 1)
    los = line_of_sight(pos, 0.022, i, j)
    # brute force
    a, b = pos[i][:, None, :], pos[j][:, None, :]
    c = pos[None, :, :]
    seg = b - a
    t = np.clip(np.sum((c - a) * seg, -1) / np.sum(seg * seg, -1), 0, 1)
    d = np.linalg.norm(a + t[..., None] * seg - c, axis=-1)
    own = (np.arange(60)[None, :] == i[:, None]) | (np.arange(60)[None, :] == j[:, None])
    expected = ~np.any((d < 0.022) & ~own, axis=1)
    np.testing.assert_array_equal(los, expected)
    assert 0 < expected.sum() < len(expected)
