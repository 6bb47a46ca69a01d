"""Compiled glue of the range & bearing sensor and the bearing exchange (swarm_envs.sensing.range_bearing_kernels, exchange_kernels) against
their numpy references (swarm_envs._compile.reference, or the formulas written out here), bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from swarm_envs._compile import reference
from swarm_envs.sensing import range_bearing as rbmod, range_bearing_frames as rb_frames
from swarm_envs.sensing.exchange import BearingExchange


def _same_bits(a: np.ndarray, b: np.ndarray) -> None:
    """Equal including the sign of zeros and NaN positions."""
    assert a.shape == b.shape and a.dtype == b.dtype
    np.testing.assert_array_equal(np.asarray(a).view(np.int64), np.asarray(b).view(np.int64))


def test_adc_pass_equals_the_numpy_ladder_pass():
    """kernels.adc_pass = clip(round(p * lam * scale + noise), 0, top) and its saturation flag, with
    negative noise (a rounded -0.0 must stay -0.0 as in numpy's clip), saturating rows, no noise,
    and a subset of rows."""
    from swarm_envs.sensing.range_bearing_kernels import adc_pass

    rng = np.random.default_rng(3)
    for scale, top in [(1.0, 255.0), (0.37, 1023.0)]:
        for _ in range(20):
            P, m = int(rng.integers(1, 60)), int(rng.choice([36, 64]))
            lam = rng.uniform(0, 400, (P, m)) * (rng.random((P, m)) < 0.6)
            rows = np.sort(rng.choice(P, int(rng.integers(1, P + 1)), replace=False)).astype(np.int64)
            p = float(rng.choice([1.0, 0.5, 2.0**-8]))
            for noise in (rng.normal(0, 2.0, (rows.size, m)), None):
                ref = p * lam[rows] * scale
                if noise is not None:
                    ref = ref + noise
                ref = np.clip(np.round(ref), 0.0, top)
                got, sat = adc_pass(lam, rows, np.zeros((0, m)) if noise is None else noise, p, scale, top)
                _same_bits(got, ref)
                np.testing.assert_array_equal(sat, ref.max(axis=1) >= top)
    # the -0.0 case explicitly
    got, _ = adc_pass(np.zeros((1, 2)), np.array([0]), np.array([[-0.3, 0.2]]), 1.0, 1.0, 255.0)
    _same_bits(got, np.clip(np.round(np.array([[-0.3, 0.2]])), 0.0, 255.0))


def test_group_brightest_equals_group_argmax_of_row_maxima():
    from swarm_envs.sensing.range_bearing_kernels import group_brightest

    rng = np.random.default_rng(5)
    for _ in range(50):
        sizes = rng.integers(1, 6, int(rng.integers(1, 20)))
        L = int(sizes.sum())
        starts = np.r_[0, np.cumsum(sizes)[:-1]].astype(np.int64)
        gains = np.round(rng.uniform(0, 5, (L, 8)))  # rounded: ties between rows are common
        labels = rng.integers(0, 1000, L)
        ref = reference.group_argmax(gains.max(axis=1), starts, labels)
        np.testing.assert_array_equal(group_brightest(gains, starts, labels), ref)


@pytest.mark.parametrize("id_check", [True, False])
def test_pick_ids_equals_the_numpy_decode_rule(id_check):
    from swarm_envs.sensing.range_bearing_kernels import pick_ids

    rng = np.random.default_rng(6)
    outcomes = set()
    for _ in range(100):
        G, n_d = int(rng.integers(1, 30)), int(rng.choice([6, 8]))
        heard = rng.random((G, n_d)) < 0.4
        H = int(heard.sum())
        ident = rng.integers(0, 4, H)  # few ids: agreeing and conflicting channels
        crc = np.where(rng.random(H) < 0.7, rb_frames.CRC16[ident], rng.integers(0, 2**16, H))
        got = pick_ids(heard, ident, crc, rb_frames.CRC16, id_check, rb_frames.NOT_HEARD, rb_frames.CONFLICT)
        ref = reference.pick_ids(heard, ident, crc, id_check)
        np.testing.assert_array_equal(got, ref)
        outcomes.update(np.sign(ref).tolist())
    assert outcomes == {-1, 0, 1}  # not heard / conflict, id 0, ids > 0 all exercised


def test_merge_readings_equals_the_numpy_reference():
    from swarm_envs.sensing.range_bearing_kernels import merge_readings

    rng = np.random.default_rng(7)
    for _ in range(100):
        K, M = int(rng.integers(0, 40)), int(rng.integers(0, 20))
        old_key = np.sort(rng.choice(200, K, replace=False)).astype(np.int64)
        new_key = np.sort(rng.choice(200, M, replace=False)).astype(np.int64)  # overlaps old keys
        old_f, new_f = rng.normal(size=(3, K)), rng.normal(size=(3, M))
        old_i = np.stack([rng.integers(0, 12, K), rng.integers(0, 50, K), rng.integers(1, 4, K)]).astype(np.int64)
        new_i = np.stack([np.zeros(M), rng.integers(0, 50, M), rng.integers(1, 4, M)]).astype(np.int64)
        got = merge_readings(old_key, old_f, old_i, 10, new_key, new_f, new_i)
        ref = rbmod.merge_readings_numpy(old_key, old_f, old_i, 10, new_key, new_f, new_i)
        for a, b in zip(got, ref):
            np.testing.assert_array_equal(a, b)
        assert np.all(np.diff(got[0]) > 0)


def test_compiled_round_start_equals_the_numpy_round_start():
    """kernels.roll_tables (BearingExchange.start_rounds) = reference.roll_tables: the started robots' filled
    tables become their published ones and are emptied, the other robots' tables are untouched."""
    from swarm_envs.sensing.exchange import _FILL, _PUB, NEVER

    rng = np.random.default_rng(9)
    for _ in range(20):
        exs = [BearingExchange(30, mode="network", k_max=6, period=3, rng=np.random.default_rng(1), n_copies=2) for _ in range(2)]
        seed = int(rng.integers(1 << 30))
        for ex in exs:  # identical random filled and published tables: entries and rows of many ages, some slots empty
            r = np.random.default_rng(seed)
            for names in (_FILL, _PUB):
                ids, bear, time, row_ids, row_bear, row_time = (getattr(ex, name) for name in names)
                time[:] = np.where(r.random(time.shape) < 0.3, -(10**9), r.integers(-5, 30, time.shape))
                ids[:] = np.where(time > -(10**9), r.integers(-1, 30, ids.shape), -1)
                bear[:] = np.where(ids >= 0, r.normal(size=ids.shape), np.nan)
                row_time[:] = np.where(r.random(row_time.shape) < 0.3, -(10**9), r.integers(-5, 30, row_time.shape))
                row_ids[:] = np.where((row_time > -(10**9))[:, :, None], r.integers(-1, 30, row_ids.shape), -1)
                row_bear[:] = np.where(row_ids >= 0, r.normal(size=row_ids.shape), np.nan)
        robots = np.sort(rng.choice(exs[0].n, int(rng.integers(1, 20)), replace=False))
        filled = {name: getattr(exs[0], name)[robots].copy() for name in _FILL}
        before = {name: getattr(exs[0], name).copy() for name in _FILL + _PUB}
        exs[0].start_rounds(robots)
        reference.roll_tables(robots, *(getattr(exs[1], name) for name in _FILL + _PUB), NEVER)
        for name in _FILL + _PUB:
            np.testing.assert_array_equal(getattr(exs[0], name), getattr(exs[1], name))
        others = np.setdiff1d(np.arange(exs[0].n), robots)
        for fill, pub in zip(_FILL, _PUB):
            np.testing.assert_array_equal(getattr(exs[0], pub)[robots], filled[fill])  # published
            np.testing.assert_array_equal(getattr(exs[0], pub)[others], before[pub][others])
            np.testing.assert_array_equal(getattr(exs[0], fill)[others], before[fill][others])
        assert (exs[0].tab_ids[robots] == -1).all() and (exs[0].row_ids[robots] == -1).all()  # emptied
        assert np.isnan(exs[0].row_bear[robots]).all() and (exs[0].row_time[robots] == -(10**9)).all()


def test_knowledge_views_equal_copies():
    ex = BearingExchange(10, mode="network", k_max=4, rng=np.random.default_rng(0))
    ex.pub_ids[0, 0], ex.pub_bear[0, 0], ex.pub_time[0, 0] = 3, 0.5, 0
    a, b = ex.knowledge(), ex.knowledge(copy=False)
    for name in ("ids", "bearings", "row_ids", "row_bearings", "row_age"):
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
    assert np.shares_memory(b.ids, ex.pub_ids) and not np.shares_memory(a.ids, ex.pub_ids)


def _random_tables(ex: BearingExchange, seed: int, published: bool = False) -> None:
    """Random own entries in the filled tables (``tab_*``), or in the published ones (``pub_*``, which the
    messages encode)."""
    r = np.random.default_rng(seed)
    ids, bear, time = (ex.pub_ids, ex.pub_bear, ex.pub_time) if published else (ex.tab_ids, ex.tab_bear, ex.tab_time)
    shape = ids.shape
    time[:] = np.where(r.random(shape) < 0.3, -(10**9), r.integers(0, 4, shape))  # many equal times: ties
    ids[:] = np.where(time > -(10**9), ex.offset[:, None] + r.integers(0, ex.copy_size, shape), -1)
    bear[:] = np.where(ids >= 0, r.uniform(-4, 4, shape), np.nan)
    bear[r.random(shape) < 0.05] = np.nan  # an entry without a bearing is sent as sector 0


@pytest.mark.parametrize("n, k_max", [(30, 6), (1000, 20)])  # 1000 robots, 20 slots: max_entries (17) < k_max
def test_compiled_message_encoding_equals_encode_rows(n, k_max):
    from swarm_envs.sensing import exchange as exmod

    ex = BearingExchange(n, mode="network", k_max=k_max, rng=np.random.default_rng(0), n_copies=2)
    assert (ex.max_entries < k_max) == (n == 1000)
    for seed in range(10):
        _random_tables(ex, seed, published=True)
        robots = np.sort(np.random.default_rng(seed).choice(ex.n, 25, replace=False))
        bits, lens = ex.encode(robots)
        ref_bits, ref_lens = reference.encode_tables(
            ex.pub_ids, ex.pub_bear, ex.pub_time, robots, ex.offset, ex.max_entries, ex.id_bits, ex.count_bits, ex.bearing_bits
        )
        np.testing.assert_array_equal(bits, ref_bits)
        np.testing.assert_array_equal(lens, ref_lens)
        assert lens.min() < lens.max()
        # and back: the compiled decoding equals the numpy one, on whole rows and on rows cut at their length
        for rows in (bits, np.where(np.arange(bits.shape[1]) < lens.min(), bits, 0)[:, : max(lens.min(), 1)]):
            got = exmod.decode_rows(rows, ex.id_bits, ex.count_bits, ex.max_entries, ex.bearing_bits)
            ref = reference.decode_rows(rows, ex.id_bits, ex.count_bits, ex.max_entries, ex.bearing_bits)
            np.testing.assert_array_equal(got[0], ref[0])
            _same_bits(got[1], ref[1])


def test_firing_sums_equal_the_gathered_numpy_sums():
    """kernels.firing_sums = segment_sum / sum_last / brightest row of the firing links' gains, bit for bit, for groups of
    1 to 40 links (reduceat's short and pairwise branches)."""
    from swarm_envs.sensing.range_bearing_kernels import firing_sums
    from swarm_envs.sensing.numpy_sums import PAIRWISE_INIT, segment_sum, sum_last

    rng = np.random.default_rng(11)
    for n_d in (6, 8):
        for _ in range(20):
            L = int(rng.integers(50, 400))
            gains = rng.exponential(50, (L, n_d, n_d)) * (rng.random((L, n_d, n_d)) < 0.5)
            sizes = rng.choice([1, 1, 2, 3, 8, 9, 12, 40], size=int(rng.integers(1, 8)))
            sel = np.sort(rng.choice(L, int(min(sizes.sum(), L)), replace=False)).astype(np.int64)
            sizes = sizes[np.cumsum(sizes) <= sel.size]
            if sizes.size == 0:
                continue
            sel = sel[: int(sizes.sum())]
            starts = np.r_[0, np.cumsum(sizes)[:-1]].astype(np.int64)
            g = gains[sel]
            lam, light, start, best = firing_sums(g.reshape(sel.size, -1), starts, n_d, PAIRWISE_INIT)
            _same_bits(lam.reshape(-1, n_d, n_d), np.add.reduceat(g, starts, axis=0))
            _same_bits(light, sum_last(g))
            _same_bits(start, segment_sum(sum_last(g), starts))
            np.testing.assert_array_equal(sel[best], reference.group_argmax(g.reshape(sel.size, -1).max(axis=1), starts, sel))


def test_adc_bits_equal_the_numpy_start_bit_reading():
    from swarm_envs.sensing.range_bearing_kernels import adc_bits

    rng = np.random.default_rng(12)
    for scale, top, floor in [(1.0, 255.0, 7.0), (0.37, 1023.0, 3.0)]:
        level = rng.uniform(0, 3 * floor / scale, (200, 8))
        for noise in (rng.normal(0, 2.0, level.shape), None):
            counts = level * scale + (0.0 if noise is None else noise)
            ref = np.clip(np.round(counts), 0.0, top) / scale >= floor
            got = adc_bits(level, np.zeros((0, 8)) if noise is None else noise, scale, top, floor)
            np.testing.assert_array_equal(got, ref)
            assert 0 < ref.mean() < 1


def test_sorted_independent_set_equals_the_adjacency_version():
    """kernels.priority_independent_set_sorted (edges sorted by u, possibly one-directional) equals
    priority_independent_set and the numpy Luby rounds; unsorted edges are refused."""
    from swarm_envs.ir.layer import compute_links
    from swarm_envs.sensing.range_bearing_kernels import priority_independent_set, priority_independent_set_sorted

    rng = np.random.default_rng(13)
    for n, side in [(1, 0.1), (5, 0.1), (40, 0.3), (300, 1.0), (300, 3.0)]:
        links = compute_links(rng.uniform(0, side, (n, 2)), rng.uniform(-np.pi, np.pi, n), "epuck")
        u, v = links.rx.astype(np.int64), links.tx.astype(np.int64)
        for drop in (0.0, 0.3):  # 0.3: many links only one way
            keep = rng.random(u.size) >= drop
            prio = rng.random(n)
            got, ok = priority_independent_set_sorted(prio, u[keep], v[keep])
            assert ok
            np.testing.assert_array_equal(got, priority_independent_set(prio, u[keep], v[keep]))
            np.testing.assert_array_equal(got, reference.independent_set(prio, u[keep], v[keep]))
    if u.size > 1:
        assert not priority_independent_set_sorted(prio, u[::-1].copy(), v[::-1].copy())[1]


def test_slot_keys_equal_the_numpy_keys():
    """kernels.slot_keys = the validity, np.mod bearing keys and id keys of coordinates_all, bit for bit,
    on bearings that include exact multiples of 2 pi, -0.0, tiny negatives, NaN and inf."""
    from swarm_envs.sensing.scale_free_kernels import slot_keys

    rng = np.random.default_rng(14)
    two_pi = 2.0 * np.pi
    special = np.array([0.0, -0.0, two_pi, -two_pi, np.pi, -np.pi, -1e-300, 1e-300, 3 * two_pi, np.nan, np.inf, -np.inf])
    for _ in range(20):
        ids = rng.integers(-1, 50, (40, 16))
        th = rng.uniform(-10, 10, ids.shape)
        pick = rng.random(ids.shape) < 0.3
        th[pick] = rng.choice(special, int(pick.sum()))
        ok, key_b, key_id, cap = slot_keys(ids, th, two_pi, np.iinfo(np.int64).max)
        ref_ok = (ids >= 0) & np.isfinite(th)
        np.testing.assert_array_equal(ok, ref_ok)
        with np.errstate(invalid="ignore"):  # mod(inf)
            _same_bits(key_b, np.where(ref_ok, np.mod(th, two_pi), np.inf))
        np.testing.assert_array_equal(key_id, np.where(ref_ok, ids, np.iinfo(np.int64).max))
        deg = ref_ok.sum(1)
        assert cap == int((deg * (deg - 1)).sum())


def test_compiled_delivery_store_equals_the_numpy_waves():
    """kernels.store_deliveries (one delivery after the other) leaves the same tables as the numpy waves of
    reference.store_deliveries (one delivery per receiver and wave), with receivers hearing several senders, a
    sender twice, and deliveries without an own bearing."""
    from swarm_envs.sensing.exchange_kernels import store_deliveries

    rng = np.random.default_rng(15)
    for _ in range(30):
        exs = [BearingExchange(12, mode="network", k_max=4, period=3, rng=np.random.default_rng(1), n_copies=2) for _ in range(2)]
        seed = int(rng.integers(1 << 30))
        for ex in exs:
            _random_tables(ex, seed)
            ex.t[:] = 5
            ex.row_time[:] = ex.tab_time
        D = int(rng.integers(1, 60))
        recv = np.sort(rng.integers(0, exs[0].n, D))
        origin = exs[0].offset[recv] + rng.integers(0, 12, D)
        hit = rng.random(D) < 0.7
        own_b = np.where(hit, rng.uniform(-3, 3, D), np.nan)
        w = exs[0].row_ids.shape[2]
        ids = np.where(rng.random((D, w)) < 0.5, rng.integers(0, 24, (D, w)), -1)
        th = np.where(ids >= 0, rng.uniform(-3, 3, (D, w)), np.nan)
        perm = rng.permutation(D)  # deliveries in any order (not grouped by receiver)
        recv, origin, hit, own_b, ids, th = recv[perm], origin[perm], hit[perm], own_b[perm], ids[perm], th[perm]
        a, b = exs
        store_deliveries(recv, origin, own_b, hit, ids, th, a._now, a.tab_ids, a.tab_bear, a.tab_time, a.row_ids, a.row_bear, a.row_time)
        reference.store_deliveries(recv, origin, own_b, hit, ids, th, b._now, b.tab_ids, b.tab_bear, b.tab_time, b.row_ids, b.row_bear, b.row_time)
        for name in ("tab_ids", "tab_bear", "tab_time", "row_ids", "row_bear", "row_time"):
            np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
