"""Shared IR physical layer (swarm_envs.ir.layer), docs/design.md#infrared-physical-layer."""

import math

import numpy as np
import pytest

from swarm_envs.ir.layer import compute_links, pair_gains, pair_geometry
from swarm_envs.ir.occlusion import line_of_sight, occluder_width
from swarm_envs.sim.geometry import wrap_angle
from swarm_envs.sim.platforms import get_platform

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
    # bearing 0 lies in receivers 0 (22.5 deg) and 7 (-22.5 deg); TX faces RX (heading pi): its transmitters
    # 7, 0, 1 (within 90 deg of RX, their outward half-planes) reach them, 2 and 6 (just beyond 90) do not
    assert {(int(a), int(b)) for a, b in zip(*np.nonzero(g))} == {(i, j) for i in (0, 7) for j in (7, 0, 1)}
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


def _pair_gain(pos, hd, platform, occlusion="ray"):
    """Gain matrix of receiver 0 from transmitter 1 (zeros if no link)."""
    L = compute_links(pos, hd, platform, drop_zero=False, occlusion=occlusion)
    k = np.flatnonzero((L.rx == 0) & (L.tx == 1))
    return L.gains[k[0]] if k.size else np.zeros((platform.n_detectors, platform.n_emitters))


@pytest.mark.parametrize("name", ["droplet", "epuck"])
def test_occlusion_per_ray_full_partial_and_none(name):
    platform = get_platform(name)
    r = platform.radius
    # robots 0 and 1 face each other 8 radii apart; robot 2 sits on the way at lateral offset y
    pos = np.array([[0.0, 0.0], [8 * r, 0.0], [4 * r, 0.0]])
    hd = np.array([0.0, np.pi, 0.0])
    free = _pair_gain(pos[:2], hd[:2], platform)
    assert free.sum() > 0
    # on the centre line it covers every ray (rays stay within rho < radius of the centre line): no light
    G = _pair_gain(pos, hd, platform)
    assert G.max() == 0.0
    L = compute_links(pos, hd, platform)
    assert (0, 1) not in set(zip(L.rx.tolist(), L.tx.tolist()))
    # just inside the centre line (1 mm): the centre-line rule blocks the pair, but the rays on the far
    # side of the centre line pass: some light, less than unblocked
    pos[2, 1] = r - 0.001
    G = _pair_gain(pos, hd, platform)
    assert 0.0 < G.sum() < free.sum()
    assert ((G == 0) & (free > 0)).any() and ((G > 0) & (G == free)).any()  # blocked rays and untouched rays
    assert _pair_gain(pos, hd, platform, occlusion="centre").max() == 0.0
    L = compute_links(pos, hd, platform)
    assert (0, 1) in set(zip(L.rx.tolist(), L.tx.tolist())) and (1, 0) in set(zip(L.rx.tolist(), L.tx.tolist()))
    # just off the centre line (1 mm): the centre-line rule sees a clear pair, per ray some light is lost
    pos[2, 1] = r + 0.001
    G = _pair_gain(pos, hd, platform)
    assert 0.0 < G.sum() < free.sum()
    np.testing.assert_array_equal(_pair_gain(pos, hd, platform, occlusion="centre"), free)
    # beyond every ray (centre farther than radius + rho from the centre line), or behind robot 1: no effect
    pos[2, 1] = occluder_width(platform) + 0.001
    np.testing.assert_array_equal(_pair_gain(pos, hd, platform), free)
    pos[2] = [8 * r + 2.5 * r, 0.0]
    np.testing.assert_array_equal(_pair_gain(pos, hd, platform), free)
    np.testing.assert_array_equal(_pair_gain(pos, hd, platform, occlusion="none"), free)


def test_occlusion_argument_checks():
    pos = np.array([[0.0, 0.0], [0.1, 0.0]])
    with pytest.raises(ValueError, match="occlusion"):
        compute_links(pos, np.zeros(2), DROPLET, occlusion="rays")
    with pytest.raises(ValueError, match="offsets"):
        pair_gains(np.array([[0.1, 0.0]]), np.array([np.pi]), DROPLET, occluders=(np.array([0, 2]), np.zeros((1, 2))))


def _ray_blocked(a, b, pos, skip, radius):
    """Whether the segment a-b passes closer than ``radius`` to any robot centre in ``pos`` but ``skip``."""
    seg = b - a
    for k in range(len(pos)):
        if k in skip:
            continue
        t = min(1.0, max(0.0, ((pos[k][0] - a[0]) * seg[0] + (pos[k][1] - a[1]) * seg[1]) / (seg[0] ** 2 + seg[1] ** 2)))
        if math.hypot(a[0] + t * seg[0] - pos[k][0], a[1] + t * seg[1] - pos[k][1]) < radius:
            return True
    return False


def _reference_links(pos, hd, platform):
    """Plain per-pair, per-ray Python reference of docs/design.md#infrared-physical-layer (brute-force pairs and occluders): returns
    {(u, w): (gains with per-ray occlusion, gains without occlusion)} for links with some light."""
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
            G = np.zeros((platform.n_detectors, platform.n_emitters))
            free = np.zeros_like(G)
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
                    free[i, j] = float(model.gain(math.hypot(*r), da, ea))
                    if free[i, j] > 0 and not _ray_blocked(ep, dp, pos, (u, w), platform.radius):
                        G[i, j] = free[i, j]
            if G.max() > 0:
                out[(u, w)] = (G, free)
    return out


@pytest.mark.parametrize(
    "name,n,seed",
    [("droplet", 25, 7), ("epuck", 25, 7), ("rone", 25, 7)]
    + [pytest.param(name, 40, seed, marks=pytest.mark.slow) for name, seed in (("droplet", 8), ("epuck", 9), ("rone", 10))],
)
def test_vectorised_equals_loop_reference(name, n, seed):
    """The compiled kernels equal the per-ray loop reference."""
    platform = get_platform(name)
    rng = np.random.default_rng(seed)
    side = (6 if n <= 25 else 4) * platform.ir_range / 4
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
    assert len(ref) > 20  # the scene actually has links
    partial = 0
    for key, (G, free) in ref.items():
        # same set of lit rays exactly; values to 1e-12 (the reference goes through atan2 angles and
        # model.gain, the kernel through cosines: the same numbers up to rounding)
        np.testing.assert_array_equal(got[key] > 0, G > 0)
        np.testing.assert_allclose(got[key], G, rtol=1e-9, atol=1e-12)
        partial += bool(((G == 0) & (free > 0)).any())
    assert partial > 0  # per-ray occlusion is exercised: some links lose some of their rays


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


@pytest.mark.parametrize("name", ["droplet", "epuck", "rone"])
def test_ray_clear_mask_matches_occluded_gains(name):
    """IRLinks.ray_clear: the per-ray occlusion mask, for code that recomputes gains with another model."""
    platform = get_platform(name)
    rng = np.random.default_rng(21)
    pos = []
    while len(pos) < 60:
        p = rng.uniform(0, platform.ir_range, 2)
        if all(np.hypot(*(p - q)) > 2 * platform.radius for q in pos):
            pos.append(p)
    pos, hd = np.array(pos), rng.uniform(-np.pi, np.pi, 60)
    free = compute_links(pos, hd, platform, drop_zero=False, occlusion="none")
    for drop in (False, True):
        L = compute_links(pos, hd, platform, drop_zero=drop)
        sel = np.isin(free.rx * 60 + free.tx, L.rx * 60 + L.tx)
        lit = free.gains[sel] > 0
        clear = L.ray_clear(platform)
        np.testing.assert_array_equal(clear[lit], L.gains[lit] > 0)
        assert (~clear[lit]).any() and clear[lit].any()
    assert compute_links(pos, hd, platform, occlusion="centre").ray_clear(platform).all()
