"""The compiled 2-hop scale-free path (swarm_envs.sensing.scale_free_kernels) equals the numpy reference
(swarm_envs._compile.reference.coordinates_all) bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from swarm_envs._compile import reference
from swarm_envs.sensing.scale_free import NeighbourKnowledge, coordinates_all, knowledge_from_matrix


def _bearings(rng, n, side, quantise):
    pos = rng.uniform(0, side, (n, 2))
    hd = rng.uniform(-np.pi, np.pi, n)
    d = pos[None] - pos[:, None]
    B = np.arctan2(d[..., 1], d[..., 0]) - hd[:, None]
    if quantise:  # 16 sectors: many exactly equal angles (ties in the MST and in the slot order)
        B = np.rint(B / (np.pi / 8)) * (np.pi / 8)
    else:
        B = B + rng.normal(0, 0.05, B.shape)
    B = np.pi - np.mod(np.pi - B, 2 * np.pi)
    B[np.hypot(d[..., 0], d[..., 1]) > 1.0] = np.nan
    return B


def _damaged(rng, kn: NeighbourKnowledge) -> NeighbourKnowledge:
    """Lossy, stale, shuffled knowledge: dropped rows and entries, NaN bearings, duplicated ids, permuted slots."""
    ids, th = kn.ids.copy(), kn.bearings.copy()
    rid, rth = kn.row_ids.copy(), kn.row_bearings.copy()
    n, k = ids.shape
    perm = np.argsort(rng.random((n, k)), 1)  # slot layout not in bearing order
    ids, th = np.take_along_axis(ids, perm, 1), np.take_along_axis(th, perm, 1)
    rid, rth = np.take_along_axis(rid, perm[..., None], 1), np.take_along_axis(rth, perm[..., None], 1)
    rid[rng.random(rid.shape[:2]) < 0.15] = -1  # rows never received
    rid[rng.random(rid.shape) < 0.1] = -1  # entries lost
    rth[rng.random(rth.shape) < 0.05] = np.nan
    th[rng.random(th.shape) < 0.03] = np.nan
    dup = rng.random(rid.shape[:2]) < 0.1  # a row that lists its first id twice
    rid[dup, -1], rth[dup, -1] = rid[dup, 0], rth[dup, 0] + 0.1
    return NeighbourKnowledge(ids=ids, bearings=th, row_ids=rid, row_bearings=rth)


def _assert_same(a, b):
    for name in ("xy", "valid", "rigid", "ids", "length"):
        x, y = getattr(a, name), getattr(b, name)
        assert x.shape == y.shape and x.dtype == y.dtype, name
        np.testing.assert_array_equal(x, y, err_msg=name)  # bit for bit (NaN == NaN)


@pytest.mark.parametrize("noise_sensitivity", [True, False])
@pytest.mark.parametrize("balance", [True, False])
def test_compiled_equals_numpy_reference(noise_sensitivity, balance):
    rng = np.random.default_rng(7)
    checked_valid = 0
    for trial in range(24):
        n = int(rng.integers(3, 40))
        B = _bearings(rng, n, side=float(rng.uniform(0.8, 2.5)), quantise=trial % 2 == 0)
        kn = knowledge_from_matrix(B)
        if trial % 3 == 1:
            kn = _damaged(rng, kn)
        if trial % 5 == 2:  # a subset of robots, with their own ids
            sel = np.sort(rng.choice(n, size=max(1, n // 2), replace=False))
            kn = NeighbourKnowledge(kn.ids[sel], kn.bearings[sel], kn.row_ids[sel], kn.row_bearings[sel], robot_ids=sel)
        ref = reference.coordinates_all(kn, noise_sensitivity=noise_sensitivity, angle_balance=balance)
        got = coordinates_all(kn, noise_sensitivity=noise_sensitivity, angle_balance=balance)
        _assert_same(got, ref)
        checked_valid += int(ref.valid.sum())
    assert checked_valid > 200  # the comparison covered many computed lengths, not only empty outputs


def test_defaults_and_tiny_inputs_equal_the_reference():
    """Default options, and inputs with no robot, one slot per robot (empty or not) and two slots."""
    rng = np.random.default_rng(3)
    kn = knowledge_from_matrix(_bearings(rng, 12, 1.2, quantise=False))
    _assert_same(coordinates_all(kn), reference.coordinates_all(kn))
    empty = NeighbourKnowledge(np.full((2, 1), -1), np.full((2, 1), np.nan), np.full((2, 1, 1), -1), np.full((2, 1, 1), np.nan))
    one = NeighbourKnowledge(np.array([[1], [0], [-1]]), np.array([[0.3], [-2.8], [np.nan]]), np.array([[[0]], [[-1]], [[-1]]]), np.array([[[-2.8]], [[np.nan]], [[np.nan]]]))
    none = NeighbourKnowledge(np.zeros((0, 3), np.int64), np.zeros((0, 3)), np.zeros((0, 3, 3), np.int64), np.zeros((0, 3, 3)))
    two = knowledge_from_matrix(_bearings(rng, 3, 0.5, quantise=True))
    two = NeighbourKnowledge(two.ids[:, :2], two.bearings[:, :2], two.row_ids[:, :2], two.row_bearings[:, :2])
    for kn in (empty, one, none, two):
        for noise_sensitivity in (True, False):
            _assert_same(coordinates_all(kn, noise_sensitivity), reference.coordinates_all(kn, noise_sensitivity))
    assert coordinates_all(one).valid[:2, 0].all() and coordinates_all(one).rigid.tolist() == [True, True, False]


def test_segment_sum_equals_reduceat():
    from swarm_envs.sensing.numpy_sums import segment_sum

    rng = np.random.default_rng(5)
    for shape in [(1, 3), (7, 8), (40, 8, 8), (300, 32), (400, 2)]:  # segments up to > 128 rows
        a = rng.normal(size=shape) * 10.0 ** rng.integers(-8, 8, size=shape)  # mixed magnitudes: order matters
        a[rng.random(shape) < 0.2] = -0.0  # signed zeros: the kernel must start each sum as numpy does
        a[rng.random(shape) < 0.1] = 0.0
        for _ in range(10):
            starts = np.sort(rng.choice(shape[0], size=int(rng.integers(1, shape[0] + 1)), replace=False))
            starts[0] = rng.integers(0, 2) * starts[0]  # with and without a leading unsummed block
            got, ref = segment_sum(a, starts), np.add.reduceat(a, starts, axis=0)
            assert got.shape == ref.shape
            np.testing.assert_array_equal(got, ref)
            np.testing.assert_array_equal(np.signbit(got), np.signbit(ref))
    with pytest.raises(IndexError):
        segment_sum(np.zeros((3, 2)), np.array([0, 3]))


def test_sum_last_equals_its_numpy_reference():
    from swarm_envs.sensing.numpy_sums import sum_last

    rng = np.random.default_rng(6)
    for shape in [(5,), (0, 8), (7, 1), (40, 8, 8), (3, 6, 6)]:
        a = rng.normal(size=shape) * 10.0 ** rng.integers(-8, 8, size=shape)  # order matters at mixed magnitudes
        for view in (a, np.moveaxis(a, -1, 0)):  # contiguous and strided
            got = sum_last(view)
            assert got.shape == view.shape[:-1]
            if view.shape[-1]:
                np.testing.assert_array_equal(got, reference.sum_last(view))
            np.testing.assert_allclose(got, view.sum(axis=-1), rtol=1e-9, atol=1e-9 * np.abs(view).max(initial=0))


def test_pair_sorting_matches_lexsort():
    from scipy.spatial import cKDTree

    from swarm_envs.sensing.ideal import candidate_pairs, directed_pairs

    rng = np.random.default_rng(2)
    pos = rng.uniform(0, 3, (500, 2))
    copy = np.repeat(np.arange(5), 100)
    got = candidate_pairs(pos, 0.3, copy)
    lift = np.c_[pos, copy * 1.6]
    ref = cKDTree(lift).query_pairs(0.3, output_type="ndarray").astype(np.int64)
    ref = ref[np.lexsort((ref[:, 1], ref[:, 0]))]
    assert len(ref) > 100
    np.testing.assert_array_equal(got, ref)
    rx, tx = directed_pairs(got)
    r2, t2 = np.r_[got[:, 0], got[:, 1]], np.r_[got[:, 1], got[:, 0]]
    o = np.lexsort((t2, r2))
    np.testing.assert_array_equal(rx, r2[o])
    np.testing.assert_array_equal(tx, t2[o])
