"""[T20] Fig. 20a / 21 validation helper: the centre robot's received amplitude uses the simulator's physics."""

import numpy as np
import pytest

from swarm_envs.ir.layer import compute_links
from swarm_envs.validate.swarmcom import M_MAX, M_MIN, centre_amplitude, channels_of_centre, disc_configuration


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
