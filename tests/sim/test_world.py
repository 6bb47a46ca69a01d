"""Physics: kinematics, contacts, walls, spawn, bump sensing."""

import numpy as np
import pytest

from swarm_envs.sim.platforms import PLATFORMS
from swarm_envs.sim.world import World
from swarm_envs.sim.spawning import spawn_positions
from swarm_envs.sim.arena import Arena
from swarm_envs.sim.geometry import wrap_angle


def _placed_worlds(platform, n_worlds: int, n_robots: int, arena, rng) -> list:
    """``n_worlds`` worlds of ``n_robots`` robots each, placed at random spawn positions and headings."""
    worlds = []
    for _ in range(n_worlds):
        world = World(platform, n_robots, arena)
        world.place(spawn_positions(rng, n_robots, platform.radius, arena), rng.uniform(-np.pi, np.pi, n_robots))
        worlds.append(world)
    return worlds


@pytest.mark.parametrize("platform", sorted(PLATFORMS))
@pytest.mark.parametrize("v_frac,w_frac", [(0.5, 0.3), (0.4, -0.5), (1.0, 0.0), (0.0, 0.8)])
def test_free_robot_follows_analytic_arc(platform, v_frac, w_frac):
    p = PLATFORMS[platform]
    world = World(p, 1, Arena("square", 4.0))
    world.place(np.array([[0.1, -0.2]]), np.array([0.7]))
    v, w = v_frac * p.max_speed, w_frac * p.max_angular_speed
    v, w = (x.item() for x in world.wheel_limited(np.array([v]), np.array([w])))
    for _ in range(10):  # 1 s
        world.step(np.array([v]), np.array([w]), 0.1)
    # the control velocities compensate pymunk's one-sub-step motor latency (swarm_envs.sim.world docstring):
    # a free robot ends every control step on the exact differential-drive arc
    t, h0 = 1.0, 0.7
    if abs(w) > 1e-12:
        expected = np.array([0.1, -0.2]) + v / w * np.array([np.sin(h0 + w * t) - np.sin(h0), -np.cos(h0 + w * t) + np.cos(h0)])
    else:
        expected = np.array([0.1, -0.2]) + v * t * np.array([np.cos(h0), np.sin(h0)])
    np.testing.assert_allclose(world.positions[0], expected, atol=1e-9)
    assert wrap_angle(world.headings[0] - (h0 + w * t)) == pytest.approx(0.0, abs=1e-6)


def test_wheel_limits_clip_combined_commands():
    p = PLATFORMS["epuck"]
    world = World(p, 1, Arena("square", 1.0))
    v, w = world.wheel_limited(np.array([p.max_speed]), np.array([p.max_angular_speed]))
    left, right = v - w * p.wheel_base / 2, v + w * p.wheel_base / 2
    assert max(abs(left[0]), abs(right[0])) <= p.max_speed + 1e-12


def test_zero_action_keeps_robots_still():
    p = PLATFORMS["epuck"]
    rng = np.random.default_rng(0)
    arena = Arena("square", 1.5)
    world = World(p, 20, arena)
    pos = spawn_positions(rng, 20, p.radius, arena)
    world.place(pos, rng.uniform(-np.pi, np.pi, 20))
    for _ in range(20):
        world.step(np.zeros(20), np.zeros(20), 0.1)
    np.testing.assert_allclose(world.positions, pos, atol=1e-12)


@pytest.mark.parametrize("shape", ["square", "circle"])
def test_dense_collisions_never_overlap_and_walls_hold(shape):
    p = PLATFORMS["epuck"]
    rng = np.random.default_rng(1)
    arena = Arena(shape, 0.8)
    n = 40
    world = World(p, n, arena)
    world.place(spawn_positions(rng, n, p.radius, arena), rng.uniform(-np.pi, np.pi, n))
    min_gap = np.inf
    for _ in range(150):
        # everyone drives at full speed towards the centre: a crush
        to_centre = np.arctan2(-world.positions[:, 1], -world.positions[:, 0]) - world.headings
        world.step(np.full(n, p.max_speed), 3 * wrap_angle(to_centre), 0.1)
        d = np.linalg.norm(world.positions[:, None] - world.positions[None], axis=-1)
        d[np.diag_indices(n)] = np.inf
        min_gap = min(min_gap, d.min() - 2 * p.radius)
        assert np.all(arena.contains(world.positions, p.radius - 2e-3)), "a robot went through a wall"
    # pymunk contacts are soft (iterative solver): allow 5% of a diameter under a full-force crush
    assert min_gap > -0.05 * p.diameter, f"robots overlapped by {-min_gap * 1e3:.2f} mm"
    assert world.bumps.any(), "a crush must trigger bump sensors"


def test_bump_sector_faces_the_contact():
    p = PLATFORMS["epuck"]
    world = World(p, 2, Arena("square", 1.0))
    # robot 0 faces +x towards robot 1; robot 1 faces +y, so robot 0 touches its left side (+90 deg)
    world.place(np.array([[0.0, 0.0], [2 * p.radius + 0.002, 0.0]]), np.array([0.0, np.pi / 2]))
    for _ in range(3):
        world.step(np.array([p.max_speed, 0.0]), np.zeros(2), 0.1)
    assert world.bumps[0, 0] and world.bumps[0].sum() == 1
    assert world.bumps[1, 2] and world.bumps[1].sum() == 1  # sector k is centred on k * 45 deg
    assert world.positions[1, 0] > 2 * p.radius + 0.002, "the pushed robot must move"


def test_spawn_is_seeded_and_feasible_or_clear_error():
    p = PLATFORMS["droplet"]
    arena = Arena("circle", 0.4)
    a = spawn_positions(np.random.default_rng(3), 50, p.radius, arena)
    b = spawn_positions(np.random.default_rng(3), 50, p.radius, arena)
    np.testing.assert_array_equal(a, b)
    d = np.linalg.norm(a[:, None] - a[None], axis=-1) + np.eye(50)
    assert d.min() >= 2 * p.radius
    assert np.all(arena.contains(a, p.radius))
    dense = spawn_positions(np.random.default_rng(3), 200, p.radius, Arena("square", 0.75))  # ~70% packing
    assert len(dense) == 200
    with pytest.raises(ValueError, match="cannot place 1000 robots"):
        spawn_positions(np.random.default_rng(3), 1000, p.radius, arena)


def test_place_rejects_overlap_and_outside():
    p = PLATFORMS["epuck"]
    world = World(p, 2, Arena("square", 1.0))
    with pytest.raises(ValueError, match="overlap"):
        world.place(np.array([[0.0, 0.0], [0.03, 0.0]]), np.zeros(2))
    with pytest.raises(ValueError, match="outside"):
        world.place(np.array([[0.0, 0.0], [0.49, 0.0]]), np.zeros(2))


def test_step_worlds_equals_stepping_each_world_alone():
    """Several worlds stepped together (the batched core's physics) move bit for bit as each alone."""
    from swarm_envs.sim.world import step_worlds

    p = PLATFORMS["epuck"]
    arena = Arena("square", 0.8)
    rng = np.random.default_rng(3)
    sizes = [12, 5, 30]
    starts = [(spawn_positions(rng, n, p.radius, arena), rng.uniform(-np.pi, np.pi, n)) for n in sizes]
    together = [World(p, n, arena) for n in sizes]
    alone = [World(p, n, arena) for n in sizes]
    for w, v, (pos, head) in zip(together, alone, starts):
        w.place(pos, head)
        v.place(pos, head)
    for _ in range(30):  # full speed towards the centre: contacts and bumps in every world
        lin = np.concatenate([np.full(n, p.max_speed) for n in sizes])
        ang = np.concatenate([3 * wrap_angle(np.arctan2(-w.positions[:, 1], -w.positions[:, 0]) - w.headings) for w in together])
        step_worlds(together, lin, ang, 0.1)
        start = 0
        for v, n in zip(alone, sizes):
            v.step(lin[start : start + n], ang[start : start + n], 0.1)
            start += n
        for w, v in zip(together, alone):
            for name in ("positions", "headings", "velocities", "angular_velocities", "bumps"):
                np.testing.assert_array_equal(getattr(w, name), getattr(v, name))
    assert any(w.bumps.any() for w in together)
    with pytest.raises(ValueError, match="commands"):
        step_worlds(together, np.zeros(3), np.zeros(3), 0.1)
    with pytest.raises(ValueError, match="platform"):
        step_worlds([together[0], World(PLATFORMS["droplet"], 2, arena)], np.zeros(14), np.zeros(14), 0.1)


class _PostSolveReference:
    """Bump flags from pymunk post-solve collision callbacks attached to a world's space (the docs/design.md#physics
    definition, and the reference for the batched contact read): every contact a sub-step's
    solver processed flags the sector of its normal seen from each robot it touches."""

    def __init__(self, world):
        from swarm_envs.sim.world import _ROBOT, _WALL

        self.world = world
        self.index = {body: i for i, body in enumerate(world.bodies)}
        self.contacts = []
        for other in (_ROBOT, _WALL):
            world.space.on_collision(_ROBOT, other, post_solve=self.on_contact)

    def on_contact(self, arbiter, space, data):
        normal = arbiter.normal  # from shape a to shape b
        for k, shape in enumerate(arbiter.shapes):
            idx = self.index.get(shape.body)
            if idx is not None:
                sign = 1.0 if k == 0 else -1.0
                self.contacts.append((idx, sign * normal.x, sign * normal.y))

    def flags(self):
        """Flags of the contacts since the last call, relative to the world's current headings."""
        from swarm_envs.sim.world import N_BUMP_SECTORS

        bumps = np.zeros((self.world.n, N_BUMP_SECTORS), dtype=bool)
        if self.contacts:
            c = np.array(self.contacts)
            idx = c[:, 0].astype(int)
            body_angle = wrap_angle(np.arctan2(c[:, 2], c[:, 1]) - self.world.headings[idx])
            sector = np.floor((body_angle + np.pi / N_BUMP_SECTORS) / (2 * np.pi / N_BUMP_SECTORS)).astype(int)
            bumps[idx, sector % N_BUMP_SECTORS] = True
        self.contacts.clear()
        return bumps


@pytest.mark.parametrize("substeps", [1, 2, 3, 8])
@pytest.mark.parametrize("shape", ["square", "circle"])
def test_bump_flags_equal_post_solve_callbacks_on_dense_scenes(substeps, shape):
    """The batched contact read gives, step by step, exactly the flags of post-solve callbacks, on
    aggregated robots (random commands, pushing each other and the walls) and under a crush; sub-step
    counts below and above chipmunk's collision persistence (3) never mix in an earlier step's contacts."""
    from swarm_envs.sim.world import step_worlds

    p = PLATFORMS["epuck"]
    rng = np.random.default_rng(11 + substeps)
    arena = Arena(shape, 0.45)
    sizes = [25, 12, 1]
    worlds = [World(p, n, arena, substeps=substeps) for n in sizes]
    for w in worlds:
        w.place(spawn_positions(rng, w.n, p.radius, arena), rng.uniform(-np.pi, np.pi, w.n))
    refs = [_PostSolveReference(w) for w in worlds]
    flagged, changed = 0, 0
    for step in range(60):
        if step < 30:  # random commands: contacts start and end
            lin = rng.uniform(-1, 1, sum(sizes)) * p.max_speed
            ang = rng.uniform(-1, 1, sum(sizes)) * p.max_angular_speed
        else:  # a crush towards the centre: many simultaneous contacts
            pos = np.concatenate([w.positions for w in worlds])
            head = np.concatenate([w.headings for w in worlds])
            lin = np.full(sum(sizes), p.max_speed)
            ang = 3 * wrap_angle(np.arctan2(-pos[:, 1], -pos[:, 0]) - head)
        before = [w.bumps.copy() for w in worlds]
        step_worlds(worlds, lin, ang, 0.1)
        for w, ref, old in zip(worlds, refs, before):
            np.testing.assert_array_equal(w.bumps, ref.flags())
            flagged += int(w.bumps.sum())
            changed += int((w.bumps != old).sum())
    assert flagged > 500 and changed > 50, "the scenes must make and break many contacts"


def test_contact_read_fallback_equals_direct_path():
    """The public-API fallback (pymunk.batch.get/set_space_bodies, Space.step, get_space_arbiters) moves
    and flags bit for bit as the direct chipmunk calls."""
    p = PLATFORMS["epuck"]
    rng = np.random.default_rng(5)
    arena = Arena("square", 0.4)
    pos, head = spawn_positions(rng, 20, p.radius, arena), rng.uniform(-np.pi, np.pi, 20)
    direct, public = World(p, 20, arena), World(p, 20, arena)
    direct.place(pos, head)
    public.place(pos, head)
    public._batched = None  # what a world has when pymunk's internals are not available
    flagged = 0
    for _ in range(20):
        lin, ang = rng.uniform(-1, 1, 20) * p.max_speed, rng.uniform(-1, 1, 20) * p.max_angular_speed
        direct.step(lin, ang, 0.1)
        public.step(lin, ang, 0.1)
        for name in ("positions", "headings", "velocities", "angular_velocities", "bumps"):
            np.testing.assert_array_equal(getattr(direct, name), getattr(public, name))
        flagged += int(direct.bumps.sum())
    assert flagged > 20, "the scene must make contacts"


@pytest.mark.parametrize("platform", ["epuck", "rone", "droplet"])
def test_compiled_substeps_equal_the_python_calls(platform):
    """The sub-steps run by the compiled loop (:func:`swarm_envs.sim.substep_kernel.substep_spaces`, chipmunk
    called without the GIL) move and flag bit for bit as the same chipmunk calls made from Python, alone
    and for several worlds on 1 and 2 threads, contacts included."""
    from swarm_envs.sim.world import _native_batch, _plain_space, step_worlds

    p = PLATFORMS[platform]
    rng = np.random.default_rng(8)
    arena = Arena("square", 7 * p.diameter)
    compiled, python = [World(p, 24, arena) for _ in range(3)], [World(p, 24, arena) for _ in range(3)]
    for a, b in zip(compiled, python):
        pos, head = spawn_positions(rng, 24, p.radius, arena), rng.uniform(-np.pi, np.pi, 24)
        a.place(pos, head)
        b.place(pos, head)
        b._native = None  # what a world has when pymunk's C functions are not available: the Python loop
    flagged = 0
    for step in range(15):
        if step == 1:  # pymunk's first step of a space checks its new bodies; from then on the compiled loop runs
            assert _native_batch(compiled) is not None and all(_plain_space(w.space) for w in compiled)
            assert _native_batch(python) is None
        lin, ang = rng.uniform(-1, 1, 72) * p.max_speed, rng.uniform(-1, 1, 72) * p.max_angular_speed
        step_worlds(compiled[:1], lin[:24], ang[:24], 0.1)
        step_worlds(compiled[1:], lin[24:], ang[24:], 0.1, threads=1 + step % 2)
        step_worlds(python, lin, ang, 0.1)
        for a, b in zip(compiled, python):
            for name in ("positions", "headings", "velocities", "angular_velocities", "bumps"):
                np.testing.assert_array_equal(getattr(a, name), getattr(b, name))
        flagged += sum(int(w.bumps.sum()) for w in compiled)
    assert flagged > 20, "the scene must make contacts"


def test_a_world_placed_again_mid_batch_steps_as_with_the_python_calls():
    """A world of a batch placed again (a new space: new C addresses) while the others keep stepping: the
    compiled batch picks up its new space (the cached addresses follow it) and moves and flags bit for bit
    as the same worlds stepped by the Python calls."""
    from swarm_envs.sim.world import _native_batch, step_worlds

    p = PLATFORMS["epuck"]
    rng = np.random.default_rng(21)
    arena = Arena("square", 6 * p.diameter)
    starts = [(spawn_positions(rng, 12, p.radius, arena), rng.uniform(-np.pi, np.pi, 12)) for _ in range(4)]
    compiled, python = [World(p, 12, arena) for _ in range(4)], [World(p, 12, arena) for _ in range(4)]
    for a, b, start in zip(compiled, python, starts):
        a.place(*start)
        b.place(*start)
        b._native = None
    for step in range(10):
        if step == 5:
            again = (spawn_positions(rng, 12, p.radius, arena), rng.uniform(-np.pi, np.pi, 12))
            before = _native_batch(compiled)
            compiled[2].place(*again)
            python[2].place(*again)
            assert _native_batch(compiled) is not before
        lin, ang = rng.uniform(0.5, 1, 48) * p.max_speed, rng.uniform(-1, 1, 48) * p.max_angular_speed
        step_worlds(compiled, lin, ang, 0.1)
        step_worlds(python, lin, ang, 0.1)
        for a, b in zip(compiled, python):
            for name in ("positions", "headings", "velocities", "angular_velocities", "bumps"):
                np.testing.assert_array_equal(getattr(a, name), getattr(b, name))


def test_contact_rows_read_what_the_buffers_hold():
    """:func:`swarm_envs.sim.substep_kernel.contact_rows` (the compiled read of every space's contacts) gives
    the rows of the buffers' own ``int_buf()`` and ``float_buf()``, world after world, and the kernel's
    read of the bodies gives what pymunk.batch reads."""
    from swarm_envs.sim.substep_kernel import contact_rows
    from swarm_envs.sim.world import _native_batch, step_worlds

    p = PLATFORMS["epuck"]
    rng = np.random.default_rng(5)
    arena = Arena("square", 6 * p.diameter)
    worlds = _placed_worlds(p, 6, 16, arena, rng)
    rows_seen = 0
    for _ in range(6):
        step_worlds(worlds, np.full(96, p.max_speed), rng.uniform(-1, 1, 96), 0.1)
        ints, normals = contact_rows(_native_batch(worlds).contacts)
        expected_ints = np.concatenate([np.frombuffer(w._contacts.int_buf(), dtype=np.uintp) for w in worlds]).reshape(-1, 3)
        expected_normals = np.concatenate([np.frombuffer(w._contacts.float_buf(), dtype=np.float64) for w in worlds]).reshape(-1, 2)
        np.testing.assert_array_equal(ints.view(np.uintp), expected_ints)
        np.testing.assert_array_equal(normals, expected_normals)
        rows_seen += len(ints)
        for w in worlds:
            read = np.array(w._read_motion())  # pymunk.batch's read of the bodies now
            np.testing.assert_array_equal(w.positions, read[:, :2])
            np.testing.assert_array_equal(w.headings, wrap_angle(read[:, 2]))
            np.testing.assert_array_equal(w._body_motion, read[:, 3:])
    assert rows_seen > 20, "the scene must make contacts"


@pytest.mark.parametrize("platform", ["epuck", "droplet"])
def test_step_worlds_threads_bit_identical(platform):
    """Stepping the spaces on threads (contiguous shares of the worlds) gives the sequential result bit for
    bit, for any thread count, contacts and bump flags included (robots crowded so they push each other)."""
    from swarm_envs.sim.world import step_worlds

    p = PLATFORMS[platform]
    arena = Arena("square", 12 * p.diameter)

    def run(threads):
        rng = np.random.default_rng(3)
        worlds = _placed_worlds(p, 40, 12, arena, rng)
        bumped = 0
        for _ in range(15):
            v = rng.uniform(-p.max_speed, p.max_speed, 480)
            w = rng.uniform(-p.max_angular_speed, p.max_angular_speed, 480)
            step_worlds(worlds, v, w, 0.1, threads=threads)
            bumped += sum(int(world.bumps.any()) for world in worlds)
        state = [np.concatenate([w.positions, w.headings[:, None], w.velocities, w._body_motion, w.bumps], 1) for w in worlds]
        return np.concatenate(state), bumped

    sequential, bumped = run(1)
    assert bumped > 0  # the case includes contacts
    for threads in (2, 3, 7):
        np.testing.assert_array_equal(run(threads)[0], sequential)


@pytest.mark.parametrize("platform", ["epuck", "rone", "droplet"])
def test_a_robot_driven_into_a_wall_pushes_with_the_bounded_motor_force(platform):
    """A robot driven at full speed into a wall for 2 s: in every sub-step after a step's first, the wall's
    contact impulse is the motors' push force bound (:func:`swarm_envs.sim.control.push_force` x h, the motor
    saturated and never more), in the first sub-step at most the full motor force x h; the robot stays
    within :data:`swarm_envs.sim.world.MAX_OVERLAP` of a diameter of the wall."""
    from swarm_envs.sim.control import motor_limits, push_force
    from swarm_envs.sim.world import _ROBOT, _WALL, MAX_OVERLAP

    p = PLATFORMS[platform]
    arena = Arena("square", 20 * p.diameter)
    world = World(p, 1, arena)
    world.place(np.array([[arena.half - p.radius - 0.25 * p.diameter, 0.0]]), np.zeros(1))
    world._native = None  # the Python sub-steps (bit-identical to the compiled ones) run the post-solve callback
    impulses: list[float] = []
    world.space.on_collision(_ROBOT, _WALL, post_solve=lambda arbiter, space, data: impulses.append(abs(arbiter.total_impulse.x)))
    h = 0.1 / world.substeps
    full, push = motor_limits(p, world.substeps)[0] * h, push_force(p, world.substeps) * h
    pressed = 0
    for _ in range(20):
        impulses.clear()
        world.step(np.array([p.max_speed]), np.zeros(1), 0.1)
        assert arena.wall_depth(world.positions, p.radius).max() <= MAX_OVERLAP * p.diameter
        if len(impulses) == world.substeps:  # in contact throughout the step
            pressed += 1
            assert impulses[0] <= full * (1 + 1e-9)
            np.testing.assert_allclose(impulses[1:], push, rtol=1e-6)
    assert pressed >= 10, "the robot must be pressed against the wall"


def test_the_motor_makes_the_bounded_velocity_change():
    """:func:`swarm_envs.sim.substep_kernel.motor_forces`: the force that changes a robot's velocity towards its
    control velocity within one sub-step, clipped in norm to the force bound (linear) and to the torque bound
    (angular), and zero for a robot at its control velocity."""
    from swarm_envs.sim.substep_kernel import motor_forces

    mass, moment, h, force, torque = 0.2, 1e-4, 0.01, 1.0, 0.002
    control = np.array([[0.03, 0.04, 0.5], [1.0, 0.0, -3.0], [0.2, 0.1, 0.0]])
    motion = np.array([0.0, 0.0, 0.4, 0.0, 0.0, 0.0, 0.2, 0.1, 0.0, 9.0, 9.0, 9.0])  # last row: the static body
    out = np.full(12, 7.0)
    motor_forces(control, motion, out, mass, moment, h, force, torque)
    np.testing.assert_allclose(out[0:3], [0.03 * mass / h, 0.04 * mass / h, 0.1 * moment / h])  # within the bounds
    np.testing.assert_allclose(out[3:6], [force, 0.0, -torque])  # clipped: |f| = force, |t| = torque
    np.testing.assert_array_equal(out[6:9], 0.0)  # at its control velocity
    np.testing.assert_array_equal(out[9:], 7.0)  # the static body's row is not written
