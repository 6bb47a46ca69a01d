"""BCH codes [T20 Sec. 4.3]: round trip, correction of every <= t error pattern, galois cross-check."""

from itertools import combinations
from math import comb

import numpy as np
import pytest

from swarm_envs.comm.bch import SUPPORTED, code, error_free_probability

CODES = [(15, 15), (15, 11), (15, 7), (15, 5), (15, 1)]
T_EXPECTED = {(15, 15): 0, (15, 11): 1, (15, 7): 2, (15, 5): 3, (15, 1): 7}


def _all_messages(k):
    return ((np.arange(1 << k)[:, None] >> np.arange(k - 1, -1, -1)) & 1).astype(bool)


@pytest.mark.parametrize("nk", CODES)
def test_round_trip_all_messages(nk):
    c = code(*nk)
    assert (c.n, c.k, c.t) == (nk[0], nk[1], T_EXPECTED[nk])
    msgs = _all_messages(c.k)
    cw = c.encode(msgs)
    assert cw.shape == (msgs.shape[0], 15)
    assert np.array_equal(cw[:, : c.k], msgs)  # systematic
    dec, ok = c.decode(cw)
    assert ok.all() and np.array_equal(dec, msgs)
    # minimum distance >= 2t+1 (sampled pairs for the large codes)
    ints = cw.astype(int) @ (1 << np.arange(14, -1, -1))
    if len(ints) > 1:
        sub = ints[:256]
        x = sub[:, None] ^ sub[None, :]
        w = np.vectorize(lambda v: bin(v).count("1"))(x[np.triu_indices(len(sub), 1)])
        assert w.min() >= 2 * c.t + 1


@pytest.mark.parametrize("nk", [nk for nk in CODES if nk[1] < 15])
def test_every_pattern_up_to_t_is_corrected(nk):
    c = code(*nk)
    rng = np.random.default_rng(1)
    msgs = _all_messages(c.k)
    msgs = msgs[rng.choice(len(msgs), size=min(len(msgs), 16), replace=False)]
    cw = c.encode(msgs)
    pats = [np.zeros(15, bool)]
    for w in range(1, c.t + 1):
        for comb_ in combinations(range(15), w):
            e = np.zeros(15, bool)
            e[list(comb_)] = True
            pats.append(e)
    pats = np.array(pats)
    assert len(pats) == sum(comb(15, i) for i in range(c.t + 1))
    rx = cw[:, None, :] ^ pats[None, :, :]
    dec, ok = c.decode(rx)
    assert ok.all()
    assert np.array_equal(dec, np.broadcast_to(msgs[:, None, :], dec.shape))


def test_t_plus_one_errors_not_silently_fixed_for_imperfect_codes():
    c = code(15, 7)
    msgs = _all_messages(7)
    cw = c.encode(msgs)
    rng = np.random.default_rng(2)
    e = np.zeros((len(msgs), 15), bool)
    for row in e:
        row[rng.choice(15, 3, replace=False)] = True
    dec, ok = c.decode(cw ^ e)
    # 3 errors on a t=2 code: either detected (ok False) or decoded to a wrong codeword, never right
    assert not (ok & (dec == msgs).all(-1)).any()
    assert (~ok).any()


@pytest.mark.slow  # galois compiles its own numba code in each process (~10 s)
@pytest.mark.parametrize("nk", [nk for nk in CODES if nk[1] < 15])
def test_cross_check_galois(nk):
    galois = pytest.importorskip("galois")
    c = code(*nk)
    g = galois.BCH(*nk)
    assert g.t == c.t
    rng = np.random.default_rng(3)
    msgs = rng.integers(0, 2, (64, c.k))
    ours = c.encode(msgs)
    theirs = np.asarray(g.encode(galois.GF2(msgs)))
    assert np.array_equal(ours.astype(int), theirs.astype(int))
    # random corruption up to t errors: both decoders agree
    noisy = ours.copy()
    for row in noisy:
        nerr = rng.integers(0, c.t + 1)
        row[rng.choice(15, nerr, replace=False)] ^= True
    dec, ok = c.decode(noisy)
    gd = np.asarray(g.decode(galois.GF2(noisy.astype(int))))
    assert ok.all() and np.array_equal(dec.astype(int), gd.astype(int))


def test_stream_helpers_and_errors():
    c = code(15, 11)
    info = np.random.default_rng(4).integers(0, 2, (5, 30)).astype(bool)
    enc = c.encode_stream(info)
    assert enc.shape == (5, 45)
    enc[:, 3] ^= True
    dec, ok = c.decode_stream(enc)
    assert ok.all() and np.array_equal(dec[:, :30], info)
    with pytest.raises(ValueError):
        code(15, 9)
    assert set(CODES) == set(SUPPORTED)


def test_error_free_probability_eq34():
    p = 0.05
    assert error_free_probability(0.0, 15, 0) == 1.0
    assert np.isclose(error_free_probability(p, 15, 0), (1 - p) ** 15)
    assert np.isclose(error_free_probability(p, 15, 1), (1 - p) ** 15 + 15 * p * (1 - p) ** 14)
    assert np.isclose(error_free_probability(0.5, 15, 7), 0.5)  # symmetric binomial
    arr = error_free_probability(np.array([0.01, 0.1]), 15, 1)
    assert arr.shape == (2,) and arr[0] > arr[1]
