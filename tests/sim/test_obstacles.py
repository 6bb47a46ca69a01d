"""Task API extensions: static obstacle walls (physics, IR light, spawn, render), switched-off robots and the
static robots' firmware (Task.static_messages)."""

from __future__ import annotations

import numpy as np
import pytest

import swarm_envs
from swarm_envs.ir.layer import compute_links
from swarm_envs.ir.blocking import block_links, rays_blocked
from swarm_envs.ir.links import emitter_sums
from swarm_envs.sim.platforms import get_platform
from swarm_envs.tasks.task import Task, distance_to_segments, obstacle_points

WALL = np.array([[[0.0, -0.3], [0.0, 0.3]]])  # a vertical wall through the middle of the arena


def _segments_cross_reference(p, q, a, b) -> bool:
    """Plain reference: do segments pq and ab cross or touch (collinear overlaps excluded)?"""

    def orient(u, v, w):
        return (v[0] - u[0]) * (w[1] - u[1]) - (v[1] - u[1]) * (w[0] - u[0])

    d1, d2 = orient(a, b, p), orient(a, b, q)
    d3, d4 = orient(p, q, a), orient(p, q, b)
    if d1 == 0 and d2 == 0:
        return False
    return d1 * d2 <= 0 and d3 * d4 <= 0


def test_rays_blocked_matches_a_plain_reference():
    rng = np.random.default_rng(0)
    starts, ends = rng.uniform(-1, 1, (400, 2)), rng.uniform(-1, 1, (400, 2))
    segments = rng.uniform(-1, 1, (5, 2, 2))
    got = rays_blocked(starts, ends, segments)
    want = [any(_segments_cross_reference(p, q, a, b) for a, b in segments) for p, q in zip(starts, ends)]
    np.testing.assert_array_equal(got, want)
    assert 0 < got.sum() < len(got)
    # touching an end point blocks; a ray beside the segment does not
    seg = np.array([[[0.0, 0.0], [0.0, 1.0]]])
    assert rays_blocked(np.array([[-1.0, 1.0]]), np.array([[1.0, 1.0]]), seg)[0]
    assert not rays_blocked(np.array([[-1.0, 1.01]]), np.array([[1.0, 1.01]]), seg)[0]


def _reference_gains(links, positions, headings, platform, segments):
    """Per ray, in a plain loop: the gain, zero where the emitter-detector ray crosses a segment."""
    out = links.gains.copy()
    for p in range(len(links)):
        for i, d in enumerate(platform.detector_positions):
            h = headings[links.rx[p]]
            det = positions[links.rx[p]] + [np.cos(h) * d[0] - np.sin(h) * d[1], np.sin(h) * d[0] + np.cos(h) * d[1]]
            for j, e in enumerate(platform.emitter_positions):
                g = headings[links.tx[p]]
                em = positions[links.tx[p]] + [np.cos(g) * e[0] - np.sin(g) * e[1], np.sin(g) * e[0] + np.cos(g) * e[1]]
                if any(_segments_cross_reference(em, det, a, b) for a, b in segments):
                    out[p, i, j] = 0.0
    return out


@pytest.mark.parametrize("platform_name", ["epuck", "droplet", "rone"])
def test_block_links_zeroes_exactly_the_rays_crossing_a_wall(platform_name):
    platform = get_platform(platform_name)
    rng = np.random.default_rng(1)
    r = platform.ir_range
    # robots scattered around a short wall whose end lets some rays of a pair pass and blocks others
    positions = rng.uniform(-0.4 * r, 0.4 * r, (14, 2))
    positions[:, 0] += np.sign(positions[:, 0]) * 2 * platform.radius  # keep clear of the wall's line
    headings = rng.uniform(-np.pi, np.pi, 14)
    segments = np.array([[[0.0, -0.05 * r], [0.0, 0.5 * r]]])
    full = compute_links(positions, headings, platform, drop_zero=False)
    blocked = block_links(full, positions, headings, platform, segments, drop_zero=False)
    np.testing.assert_array_equal(blocked.gains, _reference_gains(full, positions, headings, platform, segments))
    np.testing.assert_array_equal(blocked.emitter_sums, emitter_sums(blocked.gains))
    changed = (blocked.gains != full.gains).reshape(len(full), -1).any(axis=1)
    assert changed.any() and not changed.all()
    assert np.array_equal(blocked.ray_clear(platform) & (full.gains > 0), blocked.gains > 0)
    # compute_links with the obstacles: the same links, dark ones dropped
    dropped = compute_links(positions, headings, platform, obstacles=segments)
    lit = blocked.gains.reshape(len(blocked), -1).max(axis=1) > 0
    np.testing.assert_array_equal(dropped.rx, blocked.rx[lit])
    np.testing.assert_array_equal(dropped.gains, blocked.gains[lit])
    # without obstacles or silent robots the links come back untouched
    assert block_links(full, positions, headings, platform, np.zeros((0, 2, 2))) is full


def test_silent_robots_are_in_no_link():
    platform = get_platform("epuck")
    rng = np.random.default_rng(2)
    positions, headings = rng.uniform(-0.3, 0.3, (12, 2)), rng.uniform(-np.pi, np.pi, 12)
    silent = np.zeros(12, bool)
    silent[[0, 5]] = True
    links = compute_links(positions, headings, platform, silent=silent)
    full = compute_links(positions, headings, platform)
    assert not np.isin(links.rx, [0, 5]).any() and not np.isin(links.tx, [0, 5]).any()
    keep = ~np.isin(full.rx, [0, 5]) & ~np.isin(full.tx, [0, 5])
    np.testing.assert_array_equal(links.gains, full.gains[keep])  # silent bodies still occlude the others


class Walled(Task):
    """Two halves of an arena split by a wall, rewards zero (for these tests)."""

    METRICS = {"zero": "mean"}

    def default_arena_size(self) -> float:
        return 1.0

    def obstacles(self) -> np.ndarray:
        return WALL

    def rewards(self, state, first):
        B = self.n_copies
        return np.zeros((B, self.n_agents)), {}, {"zero": np.zeros(B)}


@pytest.mark.parametrize("sensing", ["full", "ideal"])
@pytest.mark.parametrize("platform", ["epuck", "rone"])
def test_a_wall_hides_robots_from_each_other(sensing, platform):
    """Two robots 0.2 m apart, a wall between them: no reading and no message either way; without it, both."""
    positions = np.array([[-0.1, 0.0], [0.1, 0.0]])
    headings = np.array([0.0, np.pi])  # facing each other
    walled = swarm_envs.make(Walled, n_robots=2, sensing=sensing, platform=platform, message_bits=1, observe_ids=True)
    open_ = swarm_envs.make(type("Open", (Walled,), {"obstacles": lambda self: np.zeros((0, 2, 2))}), n_robots=2, sensing=sensing,
                            platform=platform, message_bits=1, observe_ids=True)
    seen = {}
    for name, env in (("walled", walled), ("open", open_)):
        env.reset(seed=0, options={"positions": positions, "headings": headings})
        rows = 0
        for _ in range(60):
            obs, *_ = env.step({a: np.array([0.0, 0.0, 1.0]) for a in env.agents})
            rows += sum(int(obs[a]["range_bearing"][:, 0].sum() + obs[a]["messages"][:, 0].sum()) for a in env.agents)
        seen[name] = rows
    assert seen["walled"] == 0 and seen["open"] > 0


def test_walls_stop_robots_and_bump_them():
    env = swarm_envs.make(Walled, n_robots=1, sensing="ideal", platform="epuck")
    env.reset(seed=0, options={"positions": np.array([[-0.2, 0.1]]), "headings": np.array([0.0])})
    bumped = False
    for _ in range(60):
        obs, *_ = env.step({"robot_0": np.array([1.0, 0.0])})
        bumped |= bool(obs["robot_0"]["proprio"][0] > 0.5)  # sector 0: straight ahead
    x = env.world.positions[0, 0]
    assert bumped and x < -env.platform.radius + 1e-3 and x > -env.platform.radius - 0.01


def test_spawns_and_placements_avoid_obstacles():
    env = swarm_envs.make(Walled, n_robots=25, sensing="ideal", platform="epuck")
    radius = env.platform.radius
    for seed in range(20):
        env.reset(seed=seed)
        assert distance_to_segments(env.world.positions, WALL).min() >= radius
    with pytest.raises(ValueError, match=r"robots \[0\] reach more than .* into an obstacle wall"):
        grid = np.stack(np.meshgrid(np.linspace(0.1, 0.4, 5), np.linspace(-0.4, 0.4, 5)), -1).reshape(-1, 2)[:24]
        env.reset(options={"positions": np.r_[[[0.01, 0.0]], grid]})
    points, distance = obstacle_points(WALL, radius)
    assert distance > radius and np.allclose(points[0], WALL[0, 0]) and np.allclose(points[-1], WALL[0, 1])


def test_bad_obstacles_are_refused_when_the_env_is_built():
    outside = type("Outside", (Walled,), {"obstacles": lambda self: np.array([[[0.0, 0.0], [5.0, 0.0]]])})
    with pytest.raises(ValueError, match=r"Outside.obstacles\(\): every end point must lie inside"):
        swarm_envs.make(outside, n_robots=2)
    shaped = type("Shaped", (Walled,), {"obstacles": lambda self: np.zeros((2, 3))})
    with pytest.raises(ValueError, match=r"shape \(S, 2, 2\)"):
        swarm_envs.make(shaped, n_robots=2)


def test_the_renderer_draws_the_walls():
    kwargs = dict(n_robots=1, sensing="ideal", render_mode="rgb_array")
    open_ = type("Open", (Walled,), {"obstacles": lambda self: np.zeros((0, 2, 2))})
    frames = []
    for cls in (Walled, open_):
        env = swarm_envs.make(cls, **kwargs)
        env.reset(seed=0, options={"positions": np.array([[0.3, 0.3]])})
        frames.append(env.render())
    diff = np.flatnonzero((frames[0] != frames[1]).any(axis=2).any(axis=0))  # columns that differ
    assert len(diff) and abs(diff.mean() - 240) < 5  # the wall is the vertical line through the middle


# -- switched-off robots -------------------------------------------------------------------------------------
class SwitchOff(Walled):
    """Robot 0 is switched off from step 5 on; no walls."""

    def obstacles(self) -> np.ndarray:
        return np.zeros((0, 2, 2))

    def switched_off(self, num_cycles):
        off = np.zeros((self.n_copies, self.n_world), bool)
        off[:, 0] = num_cycles >= 5
        return off


@pytest.mark.parametrize("sensing", ["full", "ideal"])
@pytest.mark.parametrize("platform", ["epuck", "rone"])
def test_a_switched_off_robot_stands_still_and_leaves_the_sensing(sensing, platform, monkeypatch):
    import swarm_envs.sensing.full as full

    links_of_step = []
    original = full.compute_links_with_rows

    def recording(*args, **kwargs):
        out = original(*args, **kwargs)
        links_of_step.append((out[0].rx.copy(), out[0].tx.copy()))
        return out

    monkeypatch.setattr(full, "compute_links_with_rows", recording)
    env = swarm_envs.make(SwitchOff, n_robots=5, sensing=sensing, platform=platform, observe_ids=True, message_bits=1, arena_size=0.6)
    env.reset(seed=1)
    stopped_at = None
    for t in range(1, 60):
        obs, *_ = env.step({a: np.array([0.5, 0.3, 1.0]) for a in env.agents})
        frame = env.core.frame
        if t >= 5:
            stopped_at = env.world.positions[0].copy() if stopped_at is None else stopped_at
            assert not env.core.last_actions[0].any()  # its commands are ignored; others may still push its body
            assert np.linalg.norm(env.world.positions[0] - stopped_at) < 0.02
            assert not np.isin(0, frame.neighbours.rx[frame.neighbours.age == 0])
            if sensing == "full":  # no IR link from or to robot 0 (a corrupted header may still name it)
                rx, tx = links_of_step[-1]
                assert not np.isin(0, rx).any() and not np.isin(0, tx).any()
            else:
                assert not np.isin(0, frame.messages.receiver) and not np.isin(0, frame.messages.sender)
                assert not np.isin(0, frame.neighbours.tx)
    assert env.core.switched_off.tolist() == [True, False, False, False, False]


def test_switched_off_must_be_a_bool_mask():
    bad = type("Bad", (Walled,), {"switched_off": lambda self, c: np.zeros((1, 3))})
    env = swarm_envs.make(bad, n_robots=3, sensing="ideal")
    with pytest.raises(TypeError, match=r"Bad.switched_off\(\) returned a float64 array of shape \(1, 3\), expected a \(1, 3\) bool array"):
        env.reset(seed=0)


# -- the static robots' firmware -----------------------------------------------------------------------------
class Beacons(Walled):
    """Three static robots broadcast their own id (2 bits) from their own_id observation."""

    def obstacles(self) -> np.ndarray:
        return np.zeros((0, 2, 2))

    def n_static_robots(self) -> int:
        return 3

    def static_messages(self, observations, first):
        own = np.rint(observations["own_id"][..., 0] * (self.n_world - 1)).astype(int)  # (B, 3)
        assert set(observations) >= {"message_ids", "range_bearing", "messages"}
        return ((own[..., None] >> np.arange(self.config["message_bits"])) & 1).astype(bool)


@pytest.mark.parametrize("sensing", ["full", "ideal"])
def test_static_robots_broadcast_what_their_firmware_computes(sensing):
    env = swarm_envs.make(Beacons, n_robots=2, sensing=sensing, platform="epuck", message_bits=2, observe_ids=True, arena_size=0.4)
    env.reset(seed=3)
    agree = disagree = 0
    for _ in range(80):
        obs, *_ = env.step({a: np.array([0.0, 0.0, -1.0, -1.0]) for a in env.agents})
        for a in env.agents:
            m, ids = obs[a]["messages"], obs[a]["message_ids"]
            for row in np.flatnonzero(m[:, 0] > 0.5):
                sender = int(np.rint(ids[row, 1] * (env.n_world - 1)))
                sent = sender if sender < 3 else 0  # static robots send their id, the agents zeros
                if int(m[row, 2] + 2 * m[row, 3]) == sent:
                    agree += 1
                else:
                    disagree += 1
    # the exact channel delivers every payload as sent; the modelled one (uncoded) corrupts a few frames
    assert agree > 15 and (disagree == 0 if sensing == "ideal" else disagree < 0.2 * agree)
    bad = type("BadFirmware", (Beacons,), {"static_messages": lambda self, obs, first: np.zeros((1, 3, 1), bool)})
    with pytest.raises(ValueError, match=r"BadFirmware.static_messages\(\) returned a bool array of shape \(1, 3, 1\), expected a \(1, 3, 2\) bool array"):
        swarm_envs.make(bad, n_robots=2, sensing="ideal", message_bits=2).reset(seed=0)
