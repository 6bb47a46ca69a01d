"""Range & bearing collisions and decoded-id attribution (swarm_envs.sensing.range_bearing, issue 11)."""

from __future__ import annotations

import numpy as np
import pytest

from swarm_envs._compile import reference
from swarm_envs.sim.copies import CopyRandom
from swarm_envs.ir.layer import compute_links, pair_gains
from swarm_envs.ir.links import IRLinks
from swarm_envs.sim.geometry import wrap_angle
from swarm_envs.sensing import range_bearing as rbmod, range_bearing_frames as rb_frames
from swarm_envs.sensing.range_bearing import RangeBearingSensor
from swarm_envs.sensing.range_bearing_frames import CONFLICT, NOT_HEARD
from swarm_envs.sensing.range_bearing_model import read
from swarm_envs.sensing.range_bearing_frames import decode_ids, id_frames


def _polar(r, b):
    return np.array([r * np.cos(b), r * np.sin(b)])


def _hidden_pair_scene(rng, gap_extra=0.0):
    """RX (robot 0) at the origin between TX 1 and TX 2 on a line through it: the RX disc blocks every ray
    between the TXs (hidden terminals), both TXs see the RX. Robot 3 is far away (a bystander)."""
    d = rng.uniform(0.07, 0.12) + gap_extra
    a = rng.uniform(-np.pi, np.pi)
    pos = np.array([[0.0, 0.0], _polar(d, a), _polar(-d, a), [3.0, 3.0]])
    hd = rng.uniform(-np.pi, np.pi, 4)
    return pos, hd


def _links_from(pairs, pos, hd, n, platform="droplet"):
    """Hand-made links (rx, tx) with their model gains (line of sight assumed)."""
    rx = np.array([p[0] for p in pairs])
    tx = np.array([p[1] for p in pairs])
    order = np.lexsort((tx, rx))
    rx, tx = rx[order], tx[order]
    d = pos[tx] - pos[rx]
    c, s = np.cos(hd[rx]), np.sin(hd[rx])
    rel = np.stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]], -1)
    rh = wrap_angle(hd[tx] - hd[rx])
    return IRLinks(rx, tx, np.hypot(*d.T), rel, rh, pair_gains(rel, rh, platform), n)


def _truth_errors(r, links):
    """(range error m, bearing error rad) of each reading w.r.t. the link of (rx, tx) (NaN if no such link)."""
    idx = {(int(u), int(w)): k for k, (u, w) in enumerate(zip(links.rx, links.tx))}
    er, eb = np.full(len(r), np.nan), np.full(len(r), np.nan)
    for k, (u, w) in enumerate(zip(r.rx, r.tx)):
        p = idx.get((int(u), int(w)))
        if p is not None:
            er[k] = r.range[k] - links.distance[p]
            eb[k] = wrap_angle(r.bearing[k] - links.bearing[p])
    return er, eb


# --- collisions ----------------------------------------------------------------------------------------


def test_two_hidden_transmitters_do_not_both_give_clean_readings():
    rng = np.random.default_rng(0)
    n_checked = 0
    for trial in range(40):
        pos, hd = _hidden_pair_scene(rng)
        links = compute_links(pos, hd, "droplet")
        pairs = set(zip(links.rx.tolist(), links.tx.tolist()))
        assert (1, 2) not in pairs and (2, 1) not in pairs  # hidden from each other
        if not {(0, 1), (0, 2)} <= pairs:
            continue
        fired = np.array([False, True, True, False])
        # without superposition: both clean (what the collision model must not give)
        old = RangeBearingSensor("droplet", 4, np.random.default_rng(trial), collisions=False).step(links, fired=fired)
        at_rx = old.rx == 0
        assert set(old.tx[at_rx].tolist()) == {1, 2}
        er, eb = _truth_errors(old, links)
        assert np.all(np.abs(er[at_rx]) < 0.03) and np.all(np.abs(eb[at_rx]) < np.radians(25))
        # with collisions: at most one reading at the RX, and never two clean ones
        new = RangeBearingSensor("droplet", 4, np.random.default_rng(trial)).step(links, fired=fired)
        at_rx = new.rx == 0
        assert at_rx.sum() <= 1
        er, eb = _truth_errors(new, links)
        clean = at_rx & (np.abs(er) < 0.03) & (np.abs(eb) < np.radians(25))
        assert clean.sum() <= 1
        assert np.all(new.n_overlap[at_rx] == 2)
        n_checked += 1
    assert n_checked >= 20


def test_superposed_matrix_is_the_sum_of_the_two_lights():
    """Aligned slots: emitter j of both TXs lands in column j, light adds before noise and clipping."""
    rng = np.random.default_rng(1)
    pos, hd = _hidden_pair_scene(rng, gap_extra=0.05)
    links = compute_links(pos, hd, "droplet")
    sel = np.flatnonzero(links.rx == 0)
    assert set(links.tx[sel].tolist()) == {1, 2}
    # no noise: the reading equals the estimate of the summed noiseless matrix (power-selected)
    s = RangeBearingSensor("droplet", 4, np.random.default_rng(2), noise_sigma=0.0, id_check=False)
    monkey_ids = []

    def fake_decode(*args, **kwargs):  # attribute to TX 1 whatever was heard, to observe the matrix
        out = decode_ids(*args, **kwargs)
        monkey_ids.append(out.copy())
        return np.where(np.arange(out.size) == 0, 1, out)

    orig = rbmod.decode_ids
    rbmod.decode_ids = fake_decode
    try:
        r = s.step(links, fired=np.array([False, True, True, False]))
    finally:
        rbmod.decode_ids = orig
    lam = links.gains[sel].sum(axis=0, keepdims=True)
    R, th, ph, _ = read(lam, None, None, np.random.default_rng(0), 0.0, "droplet")
    k = np.flatnonzero(r.rx == 0)
    assert k.size == 1 and r.tx[k[0]] == 1 and r.true_tx[k[0]] in (1, 2)
    np.testing.assert_allclose([r.range[k[0]], r.bearing[k[0]], r.heading[k[0]]], [R[0], th[0], ph[0]])


# --- single firings unchanged -------------------------------------------------------------------------


def test_single_firing_is_unchanged_bit_for_bit():
    """A clique (everyone sees everyone): contention lets one robot fire per step, so no receiver ever sees
    two firings, and the sensor gives exactly the readings of the model without collisions."""
    rng = np.random.default_rng(3)
    n = 5
    ang = np.arange(n) * 2 * np.pi / n
    pos = 0.07 * np.stack([np.cos(ang), np.sin(ang)], -1)
    hd = rng.uniform(-np.pi, np.pi, n)
    links = compute_links(pos, hd, "droplet")
    assert len(links) == n * (n - 1)
    a = RangeBearingSensor("droplet", n, np.random.default_rng(7), schedule="contention")
    b = RangeBearingSensor("droplet", n, np.random.default_rng(7), collisions=False, schedule="contention")
    for _ in range(30):
        ra, rb = a.step(links), b.step(links)
        np.testing.assert_array_equal(a.last_fired, b.last_fired)
        for f in ("rx", "tx", "range", "bearing", "heading", "age", "true_tx", "n_overlap"):
            np.testing.assert_array_equal(getattr(ra, f), getattr(rb, f), err_msg=f)
    assert len(ra) == n * (n - 1) and np.all(ra.n_overlap == 1) and np.all(ra.tx == ra.true_tx)
    # and a forced single firing equals read() of that link with the same stream (the sensor's matrix noise
    # is the second of five child streams of its generator: priorities, matrix noise, id noise, timer
    # phases, late starts)
    s = RangeBearingSensor("droplet", n, np.random.default_rng(11))
    fired = np.zeros(n, bool)
    fired[2] = True
    r = s.step(links, fired=fired)
    sel = np.flatnonzero(links.tx == 2)
    noise = np.random.default_rng(11).spawn(3)[1]
    R, th, ph, _ = read(links.gains[sel], links.rel_position[sel], links.rel_heading[sel], noise)
    np.testing.assert_array_equal(r.rx, links.rx[sel])
    np.testing.assert_array_equal(r.range, R)
    np.testing.assert_array_equal(r.bearing, th)
    np.testing.assert_array_equal(r.heading, ph)


# --- decoded-id attribution ---------------------------------------------------------------------------


def test_id_frames_and_decoding_or_collisions():
    f = id_frames(np.array([1, 2, 3]))
    assert f.shape == (3, 33) and f[:, 0].all()
    assert f[0, 1] and not f[0, 2] and f[1, 2] and not f[1, 1]
    with pytest.raises(ValueError):
        id_frames(np.array([2**16]))
    light = np.array([[50.0, 0.0], [50.0, 0.0]])  # both TXs on detector 0 only
    rng = np.random.default_rng(0)
    # alone: each decodes to itself on detector 0
    out = decode_ids(light, f[:2], np.array([0, 1]), rng, 0.0)
    np.testing.assert_array_equal(out, [1, 2])
    # colliding: bits OR (1 | 2 = 3); the CRC of the OR-ed frame fails, without the check it names robot 3
    assert decode_ids(light, f[:2], np.array([0]), rng, 0.0, id_check=True)[0] == NOT_HEARD
    assert decode_ids(light, f[:2], np.array([0]), rng, 0.0, id_check=False)[0] == 3
    # on different detectors: both frames check -> two senders in one slot -> conflict
    light2 = np.array([[50.0, 0.0], [0.0, 50.0]])
    assert decode_ids(light2, f[:2], np.array([0]), rng, 0.0)[0] == CONFLICT
    # a corrupted bit (a 1 lost): the CRC fails; without the check the wrong id is decoded
    bad = f[2:3].copy()
    bad[0, 1] = False  # id 3 -> 2
    assert decode_ids(light[:1], bad, np.array([0]), rng, 0.0)[0] == NOT_HEARD
    assert decode_ids(light[:1], bad, np.array([0]), rng, 0.0, id_check=False)[0] == 2
    # below the 7-count floor nothing is heard
    assert decode_ids(np.array([[6.0, 0.0]]), f[:1], np.array([0]), rng, 0.0)[0] == NOT_HEARD


def _forced(decoded):
    def fake(light, frames, starts, *args, **kwargs):
        return np.full(len(starts), decoded, dtype=np.int64)

    return fake


@pytest.mark.parametrize("decoded, expect", [(3, 3), (0, None), (4, None), (NOT_HEARD, None), (CONFLICT, None)])
def test_reading_goes_to_the_decoded_id_or_is_rejected(monkeypatch, decoded, expect):
    """Force the decoder's output: the reading is keyed by the decoded id (a robot of the copy other than
    the receiver), else rejected; the true transmitter stays in ``true_tx`` only."""
    rng = np.random.default_rng(4)
    pos = np.array([[0.0, 0.0], [0.1, 0.0], [0.5, 0.5], [0.9, 0.9]])
    hd = rng.uniform(-np.pi, np.pi, 4)
    links = _links_from([(0, 1)], pos, hd, 4)
    monkeypatch.setattr(rbmod, "decode_ids", _forced(decoded))
    s = RangeBearingSensor("droplet", 4, np.random.default_rng(5))
    r = s.step(links, fired=np.array([False, True, False, False]))
    if expect is None:
        assert len(r) == 0
    else:
        assert len(r) == 1 and r.rx[0] == 0 and r.tx[0] == expect and r.true_tx[0] == 1
        # the measured geometry is still that of the true TX (misattributed, not re-measured)
        assert abs(r.range[0] - 0.1) < 0.03


def test_or_collision_misattributes_without_the_id_check_and_is_rejected_with_it():
    """Two hidden TXs (ids 1, 2) lighting the same detectors: OR-ed frames name robot 3 (a bystander).
    Without the CRC the RX attributes the superposed reading to 3; with it, the RX rejects the slot."""
    pos = np.array([[0.0, 0.0], _polar(0.2, np.radians(10)), _polar(0.2, np.radians(-10)), [0.6, 0.6]])
    hd = np.array([0.0, np.pi, np.pi, 0.0])  # TXs face the RX
    links = _links_from([(0, 1), (0, 2)], pos, hd, 4)
    fired = np.array([False, True, True, False])
    r = RangeBearingSensor("droplet", 4, np.random.default_rng(6), noise_sigma=0.0, id_check=False).step(links, fired=fired)
    assert len(r) == 1 and r.tx[0] == 3 and r.true_tx[0] in (1, 2) and r.n_overlap[0] == 2
    r = RangeBearingSensor("droplet", 4, np.random.default_rng(6), noise_sigma=0.0).step(links, fired=fired)
    assert len(r) == 0


# --- env copies ---------------------------------------------------------------------------------------


def test_no_reading_crosses_copies_and_each_copy_equals_a_single_sensor():
    """Two env copies stacked: copy b's readings equal a single sensor on copy b's robots bit for bit
    (collisions, decoding and their random draws all per copy), and no reading crosses copies."""
    n = 12
    seeds = [21, 22]
    rngs = [np.random.default_rng(s) for s in (1, 2)]
    scenes = []
    for g in rngs:  # dense: hidden terminals and collisions happen
        pos, hd = [], g.uniform(-np.pi, np.pi, n)
        while len(pos) < n:
            p = g.uniform(0, 0.25, 2)
            if all(np.hypot(*(p - q)) > 0.05 for q in pos):
                pos.append(p)
        scenes.append((np.array(pos), hd))
    pos = np.concatenate([s[0] for s in scenes])
    hd = np.concatenate([s[1] for s in scenes])
    copy = np.repeat([0, 1], n)
    links = compute_links(pos, hd, "droplet", copy=copy)
    vec = RangeBearingSensor("droplet", n, CopyRandom([np.random.default_rng(s) for s in seeds]))
    singles = [RangeBearingSensor("droplet", n, np.random.default_rng(s)) for s in seeds]
    single_links = [compute_links(p, h, "droplet") for p, h in scenes]
    overlapped = 0
    for _ in range(15):
        rv = vec.step(links)
        assert np.all(rv.rx // n == rv.tx // n) and np.all(rv.rx // n == rv.true_tx // n)
        for b in range(2):
            rs = singles[b].step(single_links[b])
            m = rv.rx // n == b
            np.testing.assert_array_equal(rv.rx[m] - b * n, rs.rx)
            np.testing.assert_array_equal(rv.tx[m] - b * n, rs.tx)
            np.testing.assert_array_equal(rv.true_tx[m] - b * n, rs.true_tx)
            for f in ("range", "bearing", "heading", "age", "n_overlap"):
                np.testing.assert_array_equal(getattr(rv, f)[m], getattr(rs, f), err_msg=f)
        overlapped += int((rv.n_overlap > 1).sum())
    assert overlapped > 0  # the scenes do exercise collisions
    # a forced decode of any id stays in the receiver's copy
    fired = np.zeros(2 * n, bool)
    fired[[0, n]] = True
    orig = rbmod.decode_ids
    rbmod.decode_ids = _forced(5)
    try:
        vec.reset()
        r = vec.step(links, fired=fired)
    finally:
        rbmod.decode_ids = orig
    assert len(r) > 0 and np.all(r.tx == (r.rx // n) * n + 5) and np.all(r.rx != r.tx)


def test_reset_of_one_copy_reseeds_its_id_stream():
    n = 6
    vec = RangeBearingSensor("droplet", n, CopyRandom([np.random.default_rng(1), np.random.default_rng(2)]))
    vec.reset(np.array([1]), [np.random.default_rng(9)])
    single = RangeBearingSensor("droplet", n, np.random.default_rng(0))
    single.reset(np.array([0]), [np.random.default_rng(9)])
    assert vec.id_rng.generators[1].random() == single.id_rng.generators[0].random()


def test_compiled_contention_schedule_equals_the_luby_rounds():
    """The compiled greedy independent set (kernels.priority_independent_set) equals the numpy Luby rounds
    on random scenes, and is a maximal independent set of the link graph."""
    from swarm_envs.sensing.range_bearing_kernels import priority_independent_set

    rng = np.random.default_rng(4)
    for n, side in [(1, 0.1), (5, 0.1), (40, 0.3), (300, 1.0), (300, 3.0)]:
        pos = rng.uniform(0, side, (n, 2))
        links = compute_links(pos, rng.uniform(-np.pi, np.pi, n), "droplet")
        prio = rng.random(n)
        got = priority_independent_set(prio, links.rx.astype(np.int64), links.tx.astype(np.int64))
        ref = reference.independent_set(prio, links.rx, links.tx)
        np.testing.assert_array_equal(got, ref)
        assert not np.any(got[links.rx] & got[links.tx])  # independent
        covered = got.copy()
        covered[links.rx[got[links.tx]]] = True
        assert covered.all()  # maximal: every robot fires or hears one that does


@pytest.mark.parametrize("platform", ["droplet", "epuck"])
def test_compiled_frame_words_equal_the_numpy_reference(platform):
    """kernels.frame_words reads the same id and CRC words as range_bearing.frame_words_numpy on random
    groups of colliding frames (1 to 40 links per group: reduceat's short and pairwise sums), with light
    around the floor so that noise and superposition decide bits."""
    from swarm_envs.sim.platforms import get_platform
    from swarm_envs.sensing.range_bearing_kernels import frame_words

    model = get_platform(platform).ir_model
    n_d = get_platform(platform).n_detectors
    scale, top, floor = float(model.adc_scale), float(model.adc_max), float(model.no_reading_floor)
    rng = np.random.default_rng(8)
    for _ in range(20):
        sizes = rng.choice([1, 1, 2, 3, 8, 9, 12, 40], size=int(rng.integers(1, 30)))
        L = int(sizes.sum())
        starts = np.r_[0, np.cumsum(sizes)[:-1]].astype(np.int64)
        light = rng.uniform(0, 3, (L, n_d)) * floor * (rng.random((L, n_d)) < 0.7)
        frames = id_frames(rng.integers(0, 2**16, L))
        heard = rng.random((sizes.size, n_d)) < 0.6
        noise = rng.normal(0, 2.0, (int(heard.sum()), frames.shape[1] - 1))
        got = frame_words(light, frames, starts, heard, noise, scale, top, floor, 16)
        ref = rb_frames.frame_words_numpy(light, frames, starts, heard, noise, scale, top, floor, 16)
        np.testing.assert_array_equal(got[0], ref[0])
        np.testing.assert_array_equal(got[1], ref[1])
        assert 0 < np.mean(ref[0] > 0) and np.any(ref[0] != ref[0][0])  # words vary: not all zero


def test_group_argmax_and_membership_helpers_match_their_plain_numpy_forms():
    rng = np.random.default_rng(12)
    for _ in range(50):
        sizes = rng.integers(1, 6, int(rng.integers(1, 20)))
        starts = np.r_[0, np.cumsum(sizes)[:-1]]
        values = rng.integers(0, 4, int(sizes.sum())).astype(float)  # many ties: the first one wins
        labels = rng.permutation(values.size)
        ref = [labels[s + int(np.argmax(values[s : s + n]))] for s, n in zip(starts, sizes)]
        np.testing.assert_array_equal(reference.group_argmax(values, starts, labels), ref)
        a, b = rng.integers(0, 30, 40), rng.integers(0, 30, int(rng.integers(0, 10)))
        np.testing.assert_array_equal(rbmod._member(a, b), np.isin(a, b))
