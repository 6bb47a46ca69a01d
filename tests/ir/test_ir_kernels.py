"""The compiled IR kernels equal the numpy references (models of swarm_envs.ir.models, docs/design.md#infrared-physical-layer;
swarm_envs._compile.reference)."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

from swarm_envs._compile import reference
from swarm_envs.ir import gain_kernels, layer, occlusion, pair_kernels, ray_kernels
from swarm_envs.ir import links as ir_links
from swarm_envs.ir.models import DropletLowPowerIR
from swarm_envs.sim.platforms import get_platform


@pytest.mark.parametrize("name", ["droplet", "droplet_low", "epuck", "rone"])
def test_gains_kernel_equals_numpy_reference(name):
    platform = get_platform(name.split("_")[0])
    model = DropletLowPowerIR(platform) if name == "droplet_low" else platform.ir_model
    rng = np.random.default_rng(11)
    P = 4000
    R = rng.uniform(-1.2, 1.2, (P, 2)) * platform.ir_range
    R[:200] = rng.uniform(-1, 1, (200, 2)) * 3 * platform.radius  # close pairs, including the near fits
    psi = rng.uniform(-np.pi, np.pi, P)
    fast = layer.pair_gains(R, psi, platform, model=model)
    ref = layer._pair_gains_numpy(R, psi, platform, model)
    assert (ref > 0).sum() > 1000 and (ref == 0).sum() > 100
    np.testing.assert_allclose(fast, ref, rtol=1e-9, atol=1e-12)
    # the kernel skips rays behind a detector or an emitter without computing them: exactly the same
    # rays must be lit as in the reference
    np.testing.assert_array_equal(fast > 0, ref > 0)


def _occluded_pairs(platform, rng, P, dark=None):
    """P random (receiver, transmitter) pairs, 10 % close, with 0-2 occluders each in the receiver frame (so
    that some pairs are dark); ``dark``: pairs put out of range. Returns R, psi, offsets, xy and the
    gain kernels' leading arguments."""
    R = rng.uniform(-1.1, 1.1, (P, 2)) * platform.ir_range
    R[: P // 10] = rng.uniform(-1, 1, (P // 10, 2)) * 3 * platform.radius
    if dark is not None:
        R[dark] = 2.0 * platform.ir_range
    psi = rng.uniform(-np.pi, np.pi, P)
    counts = rng.integers(0, 3, P)
    offsets = np.concatenate([[0], np.cumsum(counts)]).astype(np.int64)
    pair = np.repeat(np.arange(P), counts)
    xy = R[pair] * rng.uniform(0.2, 0.8, (len(pair), 1)) + rng.normal(0, platform.radius, (len(pair), 2))
    kind, params = gain_kernels.model_params(platform.ir_model)
    args = gain_kernels.GainInputs(
        R, np.stack([np.cos(psi), np.sin(psi)], axis=-1), platform.detector_positions, platform.detector_directions, platform.emitter_positions,
        platform.emitter_directions, kind, params, float(platform.ir_range), offsets, xy, float(platform.radius),
    )
    return R, psi, offsets, xy, args


@pytest.mark.parametrize("name", ["droplet", "epuck", "rone"])
def test_gains_kernel_compact_rows_are_the_lit_pairs(name):
    """compact=True returns only the pairs with light, in order, with the same values as the full output."""
    platform = get_platform(name)
    P = 3000
    R, psi, offsets, xy, args = _occluded_pairs(platform, np.random.default_rng(21), P)
    full, lit_full, sums_full = gain_kernels.gains_kernel(args, False)
    compact, lit, sums = gain_kernels.gains_kernel(args, True)
    expected = np.flatnonzero(full.reshape(P, -1).max(axis=1) > 0)
    assert 0 < len(expected) < P
    np.testing.assert_array_equal(lit, expected)
    np.testing.assert_array_equal(lit_full, expected)
    np.testing.assert_array_equal(compact, full[expected])
    np.testing.assert_array_equal(sums_full, _sequential_sums(full))
    np.testing.assert_array_equal(sums, sums_full[expected])
    ref = layer._pair_gains_numpy(R, psi, platform, platform.ir_model) * ir_links.clear_rays_numpy(R, psi, platform, offsets, xy)
    np.testing.assert_array_equal(full > 0, ref > 0)
    np.testing.assert_allclose(full, ref, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("name", ["droplet", "epuck", "rone"])
def test_threaded_gain_kernel_equals_the_serial_kernel_bit_for_bit(name):
    """The threaded kernel (pairs cut into chunks, compacted, chunks moved together) gives exactly the serial
    kernel's rows, lit pairs and sums, for any chunk count, including chunks with no lit pair."""
    platform = get_platform(name)
    P = 2500
    # a run of out-of-range pairs: a whole chunk can be dark
    *_, args = _occluded_pairs(platform, np.random.default_rng(31), P, dark=slice(1000, 1400))
    serial, lit, sums = gain_kernels.gains_kernel(args, True)
    assert 0 < len(lit) < P
    for chunks in (1, 2, 3, 7, 40, P + 5):
        threaded, lit_t, sums_t = gain_kernels.gains_kernel_threaded(args, chunks)
        np.testing.assert_array_equal(lit_t, lit)
        np.testing.assert_array_equal(threaded, serial)
        np.testing.assert_array_equal(sums_t, sums)
        # the gain rows left where the chunks put them: lit and sums final on return, any rows readable by
        # lit index before the gather (in any order, repeated, none), all of them after it
        later, lit_b, sums_b, rows = gain_kernels.gains_kernel_threaded(args, chunks, True)
        np.testing.assert_array_equal(lit_b, lit)
        np.testing.assert_array_equal(sums_b, sums)
        assert rows.n_rows == len(lit)
        pick = np.random.default_rng(chunks).integers(0, len(lit), 300)
        for idx in (pick, np.arange(len(lit)), np.zeros(0, dtype=np.int64)):
            np.testing.assert_array_equal(rows.take(idx), serial[idx])
        np.testing.assert_array_equal(rows.gather(), serial)
        np.testing.assert_array_equal(later, serial)
        np.testing.assert_array_equal(rows.take(pick), serial[pick])  # reads the gathered rows now
        np.testing.assert_array_equal(rows.gather(), serial)  # gathers once


def test_compute_links_on_threads_equals_one_thread(monkeypatch):
    """A scene large enough for the threaded gain kernel and occluder search gives the same links as with
    one thread, also when the gain rows are left in the chunks and gathered later (FullSensing's path)."""
    platform = get_platform("epuck")
    rng = np.random.default_rng(5)
    positions, headings = _dense_scene(platform, 500, 5.0, rng)
    threaded = layer.compute_links(positions, headings, platform)
    assert len(threaded) >= layer.THREADED_MIN_PAIRS * 0.5
    monkeypatch.setattr(layer, "THREADED_MIN_PAIRS", 1)
    monkeypatch.setattr(layer, "gain_threads", lambda n_pairs: 3)
    on_three = layer.compute_links(positions, headings, platform)
    background, rows = layer.compute_links_with_rows(positions, headings, platform, deferred=True)
    assert rows is not None
    monkeypatch.setattr(layer, "gain_threads", lambda n_pairs: 1)
    serial = layer.compute_links(positions, headings, platform)
    some = np.arange(0, len(serial), 7)
    np.testing.assert_array_equal(rows.take(some), serial.gains[some])  # the sensing's path: rows before the gather
    rows.gather()
    assert layer.compute_links_with_rows(positions, headings, platform, deferred=True)[1] is None  # one thread: nothing deferred
    for links in (threaded, on_three, background):
        for name in ("rx", "tx", "distance", "rel_position", "rel_heading", "gains", "emitter_sums"):
            np.testing.assert_array_equal(getattr(links, name), getattr(serial, name))
        for got, expected in zip(links.occluders, serial.occluders):  # the threaded occluder search too
            np.testing.assert_array_equal(got, expected)


def _sequential_sums(gains):
    """sum over emitters, one scalar addition at a time in emitter order from 0.0 (the documented order)."""
    out = np.zeros(gains.shape[:2])
    for p in range(gains.shape[0]):
        for i in range(gains.shape[1]):
            acc = 0.0
            for j in range(gains.shape[2]):
                acc += float(gains[p, i, j])
            out[p, i] = acc
    return out


@pytest.mark.parametrize("name", ["droplet", "epuck", "rone"])
@pytest.mark.parametrize("occlusion", ["ray", "centre", "none"])
@pytest.mark.parametrize("kernel", [True, False])
def test_emitter_sums_are_the_sequential_sums_of_the_gains(name, occlusion, kernel, monkeypatch):
    """IRLinks.emitter_sums: bit for bit the emitter-order sum of each detector's gains, aligned with the
    rows, for every platform, occlusion rule and both gain paths (the kernel, and numpy for a model without
    one), with and without dropped pairs, and empty."""
    if not kernel:
        monkeypatch.setattr(gain_kernels, "MODEL_IDS", {})
    platform = get_platform(name)
    rng = np.random.default_rng(14)
    pos, hd = _dense_scene(platform, 60, 1.2 * platform.ir_range, rng)
    for drop_zero in (True, False):
        L = layer.compute_links(pos, hd, platform, drop_zero=drop_zero, occlusion=occlusion)
        assert L.emitter_sums.shape == (len(L), platform.n_detectors) and len(L) > 50
        assert (L.emitter_sums > 0).any()
        np.testing.assert_array_equal(L.emitter_sums, _sequential_sums(L.gains))
    # several lit rays per detector, so the order of the additions matters somewhere
    assert ((L.gains > 0).sum(axis=-1) >= 2).any()
    empty = layer.compute_links(pos[:1], hd[:1], platform, occlusion=occlusion)
    assert empty.emitter_sums.shape == (0, platform.n_detectors)
    far = layer.compute_links(np.array([[0.0, 0.0], [10.0, 0.0]]), np.zeros(2), platform, occlusion=occlusion)
    assert len(far) == 0 and far.emitter_sums.shape == (0, platform.n_detectors)


def test_centre_line_of_sight_kernel_equals_numpy_reference():
    rng = np.random.default_rng(12)
    pos = rng.uniform(0, 2.0, (150, 2))
    tree = cKDTree(pos)
    pairs = tree.query_pairs(1.0, output_type="ndarray")
    fast = occlusion.line_of_sight(pos, 0.035, pairs[:, 0], pairs[:, 1], tree)
    ref = np.diff(reference.occluder_lists(pos, pairs[:, 0], pairs[:, 1], 0.035, tree)[0]) == 0
    assert 0.05 < ref.mean() < 0.95
    np.testing.assert_array_equal(fast, ref)


def _dense_scene(platform, n, side, rng):
    pos = []
    while len(pos) < n:
        p = rng.uniform(0, side, 2)
        if all(np.hypot(*(p - q)) > 2 * platform.radius for q in pos):
            pos.append(p)
    return np.array(pos), rng.uniform(-np.pi, np.pi, n)


def _reference_links(pos, hd, platform, pairs, tree):
    """compute_links (per-ray occlusion, dark pairs dropped) from the numpy references: (rx, tx, gains)."""
    rx, tx, pair_of, rel, _, rel_heading, _ = reference.ir_directed_pairs(pairs, pos, hd)
    offsets, idx = reference.occluder_lists(pos, pairs[:, 0], pairs[:, 1], occlusion.occluder_width(platform), tree)
    occ_offsets, xy = reference.occluder_frames(pos, hd, rx, pair_of, offsets, idx)
    gains = layer._pair_gains_numpy(rel, rel_heading, platform, platform.ir_model)
    gains = gains * ir_links.clear_rays_numpy(rel, rel_heading, platform, occ_offsets, xy)
    lit = gains.reshape(len(gains), -1).max(axis=1) > 0
    return rx[lit], tx[lit], gains[lit]


@pytest.mark.parametrize("name", ["droplet", "epuck", "rone"])
def test_per_ray_occlusion_kernel_equals_numpy_reference(name):
    """Occluder lists and per-ray occluded gains: compiled kernels == the numpy references."""
    platform = get_platform(name)
    rng = np.random.default_rng(13)
    pos, hd = _dense_scene(platform, 120, 1.5 * platform.ir_range, rng)
    tree = cKDTree(pos)
    pairs = tree.query_pairs(platform.ir_range, output_type="ndarray")
    rx, tx = np.concatenate([pairs[:, 0], pairs[:, 1]]), np.concatenate([pairs[:, 1], pairs[:, 0]])
    w = occlusion.occluder_width(platform)
    fast_occ = occlusion.pair_occluders(pos, hd, rx, tx, w, tree)
    fast_links = layer.compute_links(pos, hd, platform)
    ref_offsets, ref_idx = reference.occluder_lists(pos, rx, tx, w, tree)
    ref_xy = reference.occluder_frames(pos, hd, rx, np.arange(len(rx)), ref_offsets, ref_idx)[1]
    ref_rx, ref_tx, ref_gains = _reference_links(pos, hd, platform, pairs, tree)
    np.testing.assert_array_equal(fast_occ[0], ref_offsets)
    np.testing.assert_array_equal(fast_occ[1], ref_idx)
    np.testing.assert_allclose(fast_occ[2], ref_xy, rtol=0, atol=1e-15)
    assert np.diff(ref_offsets).max() >= 2 and (np.diff(ref_offsets) == 0).any()
    np.testing.assert_array_equal(fast_links.rx, ref_rx)
    np.testing.assert_array_equal(fast_links.tx, ref_tx)
    # the same rays are lit; values to 1e-12 (numpy computes the gains from cosines with other roundings)
    np.testing.assert_array_equal(fast_links.gains > 0, ref_gains > 0)
    np.testing.assert_allclose(fast_links.gains, ref_gains, rtol=1e-9, atol=1e-12)
    free = layer.compute_links(pos, hd, platform, occlusion="none", drop_zero=False)
    assert len(free) > len(ref_rx)  # some pairs are fully occluded ...
    # ... and some kept links lose only part of their rays
    key = free.rx * len(pos) + free.tx
    sel = np.isin(key, ref_rx * len(pos) + ref_tx)
    lost = (free.gains[sel] > 0) & (ref_gains == 0)
    assert lost.reshape(len(ref_rx), -1).any(axis=1).sum() > 0


def test_occluder_lists_equal_the_exact_segment_test_near_the_disc_edge():
    """occluders_kernel decides candidates within 1e-6 of the width by the exact segment test: the same
    lists as segment_hits_disc over every third robot, for third robots placed at the width (to +-1e-15
    .. 1e-3 relative) from the centre segment, inside it, beyond either end and near the ends. (The numpy
    reference, swarm_envs._compile.reference.occluder_lists, rounds the segment differently and may disagree within
    ~1e-16 of the width.)"""
    rng = np.random.default_rng(35)
    width = 0.0686
    pos = list(rng.uniform(0, 2.0, (40, 2)))
    pairs = []
    for _ in range(150):
        a, b = rng.integers(0, 40, 2)
        if a == b:
            continue
        pa, pb = pos[a], pos[b]
        s = pb - pa
        n = np.array([-s[1], s[0]]) / np.hypot(*s)
        t = rng.choice([rng.uniform(-0.1, 1.1), 0.0, 1.0, 0.5])
        h = width * (1.0 + rng.choice([0.0, 1e-15, -1e-15, 1e-9, -1e-9, 1e-7, -1e-7, 1e-3, -1e-3]))
        pos.append(pa + t * s + rng.choice([-1.0, 1.0]) * h * n)
        pairs.append((a, b))
    pos = np.array(pos)
    pairs = np.array(pairs, dtype=np.int64)
    a, b = np.ascontiguousarray(pairs[:, 0]), np.ascontiguousarray(pairs[:, 1])
    offsets, idx = occlusion.occluder_lists(pos, a, b, width, None)
    n_edge = 0
    for p in range(len(a)):
        pa, s = pos[a[p]], pos[b[p]] - pos[a[p]]
        expected = [
            k for k in range(len(pos))
            if k != a[p] and k != b[p] and ray_kernels.segment_hits_disc(pa[0], pa[1], pa[0] + s[0], pa[1] + s[1], pos[k, 0], pos[k, 1], width**2)
        ]
        np.testing.assert_array_equal(idx[offsets[p] : offsets[p + 1]], expected)
        n_edge += len(expected)
    assert n_edge > 100


@pytest.mark.parametrize("name", ["droplet", "epuck"])
def test_threaded_occluder_search_equals_the_serial_search_bit_for_bit(name):
    """occluders_kernel_threaded (robots' lists sorted and pairs searched in chunks, gathered in order)
    gives exactly the serial kernel's lists for any chunk count, more chunks than pairs included."""
    platform = get_platform(name)
    pos, _ = _dense_scene(platform, 150, 1.5 * platform.ir_range, np.random.default_rng(37))
    tree = cKDTree(pos)
    pairs = tree.query_pairs(platform.ir_range, output_type="ndarray")
    a, b = np.ascontiguousarray(pairs[:, 0], dtype=np.int64), np.ascontiguousarray(pairs[:, 1], dtype=np.int64)
    w = occlusion.occluder_width(platform)
    length = float(np.hypot(*(pos[b] - pos[a]).T).max())
    serial = occlusion.occluder_lists(pos, a, b, w, tree, length, pairs, platform.ir_range)
    assert len(serial[1]) > 100 and (np.diff(serial[0]) == 0).any()
    for chunks in (1, 2, 3, 7, len(a) + 5):
        threaded = occlusion.occluder_lists(pos, a, b, w, tree, length, pairs, platform.ir_range, chunks)
        np.testing.assert_array_equal(threaded[0], serial[0])
        np.testing.assert_array_equal(threaded[1], serial[1])


@pytest.mark.parametrize("name", ["droplet", "epuck"])
def test_neighbour_lists_from_the_candidate_pairs_give_the_same_occluders(name):
    """compute_links takes the occluder search's neighbour lists from its candidate pairs (no second
    KD-tree query): the same occluder lists as with the KD-tree query, bit for bit."""
    platform = get_platform(name)
    rng = np.random.default_rng(36)
    pos, _ = _dense_scene(platform, 150, 1.5 * platform.ir_range, rng)
    tree = cKDTree(pos)
    pairs = tree.query_pairs(platform.ir_range, output_type="ndarray")
    a, b = np.ascontiguousarray(pairs[:, 0], dtype=np.int64), np.ascontiguousarray(pairs[:, 1], dtype=np.int64)
    w = occlusion.occluder_width(platform)
    length = float(np.hypot(*(pos[b] - pos[a]).T).max())
    via_tree = occlusion.occluder_lists(pos, a, b, w, tree, length)
    via_pairs = occlusion.occluder_lists(pos, a, b, w, tree, length, pairs, platform.ir_range)
    assert len(via_tree[1]) > 100
    np.testing.assert_array_equal(via_pairs[0], via_tree[0])
    np.testing.assert_array_equal(via_pairs[1], via_tree[1])
    reach2 = 0.25 * length**2 + w**2 + 2e-9
    starts, counts, nbrs = pair_kernels.neighbour_csr_kernel(pos, pairs.astype(np.int64), reach2)
    ref = occlusion.neighbour_csr(pos, np.sqrt(reach2), tree)
    np.testing.assert_array_equal(counts, ref[1])
    for r in range(len(pos)):
        assert sorted(nbrs[starts[r] : starts[r] + counts[r]]) == sorted(ref[2][ref[0][r] : ref[0][r] + ref[1][r]])


def test_disc_test_verdicts_equal_the_exact_segment_test_near_the_disc_edge():
    """hits_disc (the gain kernel's occlusion test) skips the division except near the radius: its verdicts equal segment_hits_disc's,
    including rays that graze the disc within rounding and discs near either end."""
    rng = np.random.default_rng(31)
    r = 0.035
    n = 0
    for _ in range(3000):
        x0, y0 = rng.uniform(-0.05, 0.05, 2)
        L = rng.uniform(0.0, 1.0)
        phi = rng.uniform(-np.pi, np.pi)
        dx, dy = L * np.cos(phi), L * np.sin(phi)
        t = rng.choice([rng.uniform(-0.2, 1.2), 0.0, 1.0])  # the foot of the centre on the ray's line
        h = r * (1.0 + rng.choice([0.0, 1e-15, -1e-15, 1e-9, -1e-9, 1e-7, -1e-7, 1e-3, -1e-3]))
        side = rng.choice([-1.0, 1.0])
        cx = x0 + t * dx - side * h * np.sin(phi)
        cy = y0 + t * dy + side * h * np.cos(phi)
        x1, y1 = x0 + dx, y0 + dy
        dx, dy = x1 - x0, y1 - y0  # as the kernel computes the ray
        r2 = r * r
        fast = ray_kernels.hits_disc(x0, y0, x1, y1, dx, dy, dx * dx + dy * dy, cx, cy, r2, r2 * (1 + ray_kernels.DISC_TOL), r2 * (1 - ray_kernels.DISC_TOL))
        exact = ray_kernels.segment_hits_disc(x0, y0, x1, y1, cx, cy, r * r)
        assert fast == exact
        n += exact
    assert 100 < n < 2900


@pytest.mark.parametrize("offsets", [(1e-14, -1e-14, 1e-13, -1e-13, 1e-11, -1e-11), (0.0, 1e-17, -1e-17)])
def test_epuck_kernel_decides_grazing_rays_like_the_reference(offsets):
    """e-puck rays with a cosine near 0 (emitter on a detector's side line, or detector on an emitter's side
    line): lit exactly when the numpy reference lights them for offsets above the geometry's rounding
    (~1e-16 m; the kernel's short cut stops at 1e-12 m); within rounding the gains (<< 1e-12) are never
    negative."""
    platform = get_platform("epuck")
    rng = np.random.default_rng(32)
    dp, dd = platform.detector_positions, platform.detector_directions
    ep, ed = platform.emitter_positions, platform.emitter_directions
    R, psi = [], []
    for _ in range(2000):
        i, j = rng.integers(0, 8, 2)
        L = rng.uniform(0.02, 0.8)
        off = rng.choice(offsets)
        u = np.array([np.cos(dd[i]), np.sin(dd[i])])
        side = np.array([-u[1], u[0]]) * rng.choice([-1.0, 1.0])
        if rng.random() < 0.5:  # emitter on detector i's side line: cos(detector angle) ~ 0
            target = dp[i] + L * side + off * u
            # emitter axis towards the detector, within +-60 degrees
            axis = np.arctan2(*(-side)[::-1]) + rng.uniform(-1.0, 1.0)
        else:  # detector on emitter j's side line: cos(emitter angle) ~ 0
            target = dp[i] + L * (u + rng.uniform(-0.5, 0.5) * side)
            back = dp[i] - target
            axis = np.arctan2(back[1], back[0]) + np.pi / 2 * rng.choice([-1.0, 1.0]) + off / L
        h = axis - ed[j]
        c, s = np.cos(h), np.sin(h)
        R.append(target - np.array([c * ep[j, 0] - s * ep[j, 1], s * ep[j, 0] + c * ep[j, 1]]))
        psi.append(h)
    R, psi = np.array(R), np.array(psi)
    fast = layer.pair_gains(R, psi, platform)
    ref = layer._pair_gains_numpy(R, psi, platform, platform.ir_model)
    assert fast.min() >= 0.0
    if offsets[0] != 0.0:
        np.testing.assert_array_equal(fast > 0, ref > 0)
    np.testing.assert_allclose(fast, ref, rtol=1e-9, atol=1e-12)


def test_directed_pairs_kernel_equals_numpy_reference():
    """Both directions of the KD-tree pairs sorted by (rx, tx), and their frames: compiled == numpy, bit for bit."""
    rng = np.random.default_rng(33)
    pos = rng.uniform(0, 3.0, (300, 2))
    hd = rng.uniform(-np.pi, np.pi, 300)
    pairs = cKDTree(pos).query_pairs(0.5, output_type="ndarray")
    pairs = pairs[rng.permutation(len(pairs))]  # any order of the unordered pairs
    fast = layer._directed_pairs(pairs, pos, hd)
    ref = reference.ir_directed_pairs(pairs, pos, hd)
    assert len(ref[0]) == 2 * len(pairs) > 1000
    key = ref[0] * 300 + ref[1]
    assert (np.diff(key) > 0).all()
    for a, b in zip(fast, ref):
        np.testing.assert_array_equal(a, b)


def test_directed_pairs_kernel_wraps_any_heading_like_numpy():
    """Relative headings wrapped without fmod where possible: the same bits as numpy's wrap_angle, for
    wrapped and unwrapped headings (including exact multiples of pi)."""
    rng = np.random.default_rng(34)
    n = 200
    pos = rng.uniform(0, 1.0, (n, 2))
    hd = np.concatenate([rng.uniform(-np.pi, np.pi, n // 2), rng.uniform(-30, 30, n // 4), np.pi * rng.integers(-6, 7, n - n // 2 - n // 4)])
    pairs = cKDTree(pos).query_pairs(0.3, output_type="ndarray")
    fast = layer._directed_pairs(pairs, pos, hd)
    np.testing.assert_array_equal(fast[5], reference.ir_directed_pairs(pairs, pos, hd)[5])
    assert fast[5].min() > -np.pi and fast[5].max() <= np.pi


def test_gain_threads_only_for_large_scenes_on_the_main_thread():
    import threading

    assert layer.gain_threads(layer.THREADED_MIN_PAIRS - 1) == 1
    import numba

    assert layer.gain_threads(layer.THREADED_MIN_PAIRS) == numba.get_num_threads()
    seen = []
    worker = threading.Thread(target=lambda: seen.append(layer.gain_threads(10 * layer.THREADED_MIN_PAIRS)))
    worker.start()
    worker.join()
    assert seen == [1]
