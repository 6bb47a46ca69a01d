"""The motors' compiled force kernel against its numpy reference (its bounds: tests/sim/test_world.py)."""

import numpy as np
from hypothesis import given, settings, strategies as st

from swarm_envs._compile import reference
from swarm_envs.sim.substep_kernel import motor_forces

velocity = st.floats(-2.0, 2.0, allow_nan=False)


@settings(max_examples=60, deadline=None)
@given(
    seed=st.integers(0, 2**31 - 1),
    n=st.integers(1, 40),
    spread=velocity.map(abs),
    force=st.floats(0.0, 100.0),
    torque=st.floats(0.0, 5.0),
    substeps=st.integers(1, 40),
)
def test_kernel_equals_the_numpy_reference_bit_for_bit(seed, n, spread, force, torque, substeps):
    """Any velocities, bounds and sub-step: the same rows, bit for bit (clipped and unclipped robots alike)."""
    rng = np.random.default_rng(seed)
    control = rng.uniform(-spread, spread, (n, 3))
    motion = rng.uniform(-spread, spread, (n, 3))
    motion[: n // 3] = control[: n // 3]  # some robots already at their control velocity
    mass, moment, h = 0.15, 1.2e-4, 0.1 / substeps
    out = np.full(3 * n + 3, np.nan)  # the space's static body row after the robots stays untouched
    motor_forces(control, motion.reshape(-1), out, mass, moment, h, force, torque)
    assert np.array_equal(out[: 3 * n].reshape(n, 3), reference.motor_forces(control, motion, mass, moment, h, force, torque))
    assert np.isnan(out[3 * n :]).all()

