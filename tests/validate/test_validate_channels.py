"""[T20] Fig. 20a / 21 validation helper: the centre robot's received amplitude uses the simulator's physics."""

import numpy as np
import pytest

from swarm_envs.ir.layer import compute_links
from swarm_envs.comm.channel import M_MAX, M_MIN
from swarm_envs.validate.swarmcom_channels import centre_amplitude, channels_of_centre, detector_channels
from swarm_envs.validate.swarmcom_setup import disc_configuration


@pytest.mark.parametrize("occlusion", ["ray", "centre"])
def test_centre_amplitude_equals_compute_links(occlusion):
    rng = np.random.default_rng(5)
    pos = disc_configuration(60, rng)
    head = rng.uniform(-np.pi, np.pi, pos.shape[0])
    amp = centre_amplitude(pos, head, max_range=10.0, occlusion=occlusion)
    L = compute_links(pos, head, "epuck", occlusion=occlusion)
    expected = np.zeros(pos.shape[0])
    sel = L.tx == 0
    y = np.minimum(1.0, L.gains[sel].sum(axis=-1))  # e-puck: gains are intensities [T20 Eq. (10)]
    expected[L.rx[sel]] = M_MAX - np.floor((M_MAX - M_MIN) * (1.0 - y) + M_MIN).min(axis=1)
    np.testing.assert_array_equal(amp, expected)
    assert 5 < channels_of_centre(pos, head, 5, 10.0, occlusion) < 60


def _scenes(n_others, count, seed):
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        pos = disc_configuration(n_others, rng)
        out.append((pos, rng.uniform(-np.pi, np.pi, pos.shape[0])))
    return out


def test_detector_count_never_exceeds_the_noiseless_count():
    """Through the simulated receiver (noise, detector response, start detection) a robot needs more than an
    amplitude above m_tr: the detector's n_C is at most the noiseless count, scene by scene, and below it in sum."""
    scenes = _scenes(30, 8, seed=3)
    res = detector_channels(scenes, 5, np.random.default_rng(4), frames=4)
    noiseless = np.array([channels_of_centre(p, h, 5) for p, h in scenes])
    assert res["n_c"].shape == (8,)
    assert np.all(res["sent"] == 4)
    assert np.all(res["n_c"] <= noiseless)
    assert res["n_c"].sum() < noiseless.sum()
    assert res["n_c"].sum() > 0.5 * noiseless.sum()


@pytest.mark.parametrize(("distance", "is_channel"), [(0.2, True), (0.95, False)])
def test_detector_counts_a_facing_neighbour_only_within_range(distance, is_channel):
    """A facing neighbour 20 cm away (78 counts) is a channel; at 95 cm (6 counts, just above m_tr = 5) its
    detector rarely decodes a frame intact, so it is not, although the noiseless count takes it."""
    pos = np.array([[0.0, 0.0], [distance, 0.0]])
    head = np.array([0.0, np.pi])  # facing each other
    assert channels_of_centre(pos, head, 5, max_range=1.0) == 1
    res = detector_channels([(pos, head)], 5, np.random.default_rng(0), frames=10, max_range=1.0)
    assert int(res["n_c"][0]) == int(is_channel)
    assert (res["intact"][0][1] >= 5) == is_channel
