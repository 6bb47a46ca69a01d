"""The compiled IR kernels equal the numpy reference (models of swarm_envs.ir.models, SPEC 2)."""

import numpy as np
import pytest
from scipy.spatial import cKDTree

from swarm_envs.ir import kernels, layer
from swarm_envs.ir.models import DropletLowPowerIR
from swarm_envs.platforms import get_platform

pytestmark = pytest.mark.skipif(not kernels.HAVE_NUMBA, reason="numba is not installed: only the numpy path exists")


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
    reference = layer._pair_gains_numpy(R, psi, platform, model)
    assert (reference > 0).sum() > 1000 and (reference == 0).sum() > 100
    np.testing.assert_allclose(fast, reference, rtol=1e-9, atol=1e-12)


def test_occlusion_kernel_equals_numpy_reference(monkeypatch):
    rng = np.random.default_rng(12)
    pos = rng.uniform(0, 2.0, (150, 2))
    tree = cKDTree(pos)
    pairs = tree.query_pairs(1.0, output_type="ndarray")
    fast = layer.line_of_sight(pos, 0.035, pairs[:, 0], pairs[:, 1], tree)
    monkeypatch.setattr(kernels, "HAVE_NUMBA", False)
    reference = layer.line_of_sight(pos, 0.035, pairs[:, 0], pairs[:, 1], tree)
    assert 0.05 < reference.mean() < 0.95
    np.testing.assert_array_equal(fast, reference)
