"""sensing="full": observations come from the modelled IR stack, with errors of the expected size."""

import numpy as np
import pytest

import swarm_envs
from swarm_envs.sensing.full import BEACON_PERIOD
from swarm_envs.sensing.observation import wrapped_difference
from tests.conftest import assert_tree_equal


def relative_pose(positions, headings, rx, tx):
    """Exact pose of robot ``tx`` seen by ``rx`` (ground truth): distance (m), bearing of tx in rx's frame
    and tx's heading in rx's frame (rad)."""
    delta = positions[tx] - positions[rx]
    distance = np.hypot(delta[:, 0], delta[:, 1])
    bearing = wrapped_difference(np.arctan2(delta[:, 1], delta[:, 0]), headings[rx])
    return distance, bearing, wrapped_difference(headings[tx], headings[rx])


def fresh_readings(env):
    nb = env._frame.neighbours
    fresh = nb.age == 0
    rx, tx = nb.rx[fresh], nb.tx[fresh]
    dist, bearing, heading = relative_pose(env.world.positions, env.world.headings, rx, tx)
    return nb.range[fresh], nb.bearing[fresh], nb.heading[fresh], dist, bearing, heading


def wrap(a):
    return (a + np.pi) % (2 * np.pi) - np.pi


def collect(platform, steps=30, **kwargs):
    env = swarm_envs.make("swarm_envs/Aggregation-v0", n_robots=12, platform=platform, sensing="full", **kwargs)
    env.reset(seed=0)
    rows = []
    for _ in range(steps):
        env.step({a: np.array([0.3, 0.2], np.float32) for a in env.agents})
        rows.append(fresh_readings(env))
    return env, [np.concatenate(c) for c in zip(*rows)]


def test_droplet_range_bearing_errors_have_the_papers_size():
    env, (r, b, h, r_true, b_true, h_true) = collect("droplet", rb_schedule="every_step")
    near = r_true < 0.20  # the paper's gantry sweep: up to 4.5 diameters
    assert near.sum() > 50
    range_err = r[near] - r_true[near]
    # [F14 Sec. V]: range error within one robot diameter (|mean| + 1 std < 4.4 cm)
    assert abs(range_err.mean()) + range_err.std() < env.platform.diameter
    bearing_err = np.degrees(np.abs(wrap(b - b_true)))
    assert np.median(bearing_err) < 10.0
    heading_err = np.degrees(np.abs(wrap(h - h_true)))
    assert np.median(heading_err) < 30.0
    # noisy: not exact (observations are not ground truth)
    assert np.abs(range_err).max() > 1e-4


def test_full_observation_differs_from_ideal_but_tracks_it():
    kwargs = dict(n_robots=8, platform="epuck", rb_schedule="every_step", max_cycles=50)
    full = swarm_envs.make("swarm_envs/Aggregation-v0", sensing="full", **kwargs)
    ideal = swarm_envs.make("swarm_envs/Aggregation-v0", sensing="ideal", **kwargs)
    of, _ = full.reset(seed=1)
    oi, _ = ideal.reset(seed=1)
    np.testing.assert_array_equal(full.world.positions, ideal.world.positions)
    for _ in range(3):
        act = {a: np.array([0.0, 0.0], np.float32) for a in full.agents}
        of, *_ = full.step(act)
        oi, *_ = ideal.step(act)
    a = "robot_0"
    assert not np.array_equal(of[a]["range_bearing"], oi[a]["range_bearing"])
    # the nearest neighbour's estimated range is close to the true one
    nearest_true = oi[a]["range_bearing"][0, 1]
    nearest_est = of[a]["range_bearing"][0, 1]
    assert of[a]["range_bearing"][0, 0] == 1.0
    assert abs(nearest_est - nearest_true) < 0.5 * nearest_true


def test_rone_reports_sector_bearings_without_range():
    env = swarm_envs.make("swarm_envs/Flocking-v0", n_robots=6, platform="rone", sensing="full")
    obs, _ = env.reset(seed=2)
    # readings are measured on decoded frames (one broadcast per robot per beacon period), not every step
    for _ in range(BEACON_PERIOD + 5):
        obs, *_ = env.step({a: np.zeros(2, np.float32) for a in env.agents})
    rb = obs["robot_0"]["range_bearing"]
    valid = rb[:, 0] > 0
    assert valid.any()
    assert np.all(rb[valid, 1] == 0.0)  # bearing-only platform
    angles = np.degrees(np.arctan2(rb[valid, 3], rb[valid, 2]))
    # 16 sectors of 22.5 degrees [L Sec. 3.2.1]
    np.testing.assert_allclose((angles / 22.5) - np.round(angles / 22.5), 0.0, atol=1e-3)


@pytest.mark.parametrize("exchange", ["ideal", "network"])
def test_scale_free_observation_is_scaled_and_sane(exchange):
    env = swarm_envs.make("swarm_envs/Aggregation-v0", n_robots=10, platform="rone", sensing="full", exchange=exchange)
    env.reset(seed=3)
    rigid_seen = 0
    for _ in range(40):
        obs, *_ = env.step({a: np.zeros(2, np.float32) for a in env.agents})
        for o in obs.values():
            sf = o["scale_free"]
            assert np.all(np.isfinite(sf))
            rigid_seen += int(o["rigid"][0])
    assert rigid_seen > 0


def test_messages_travel_over_the_channel():
    env = swarm_envs.make("swarm_envs/Aggregation-v0", n_robots=4, platform="epuck", sensing="full", message_bits=6, arena_size=1.0)
    pos = np.array([[-0.1, 0.0], [0.1, 0.0], [0.0, 0.15], [0.0, -0.15]])
    env.reset(seed=0, options={"positions": pos, "headings": np.array([0.0, np.pi, -np.pi / 2, np.pi / 2])})
    pattern = np.array([1, -1, 1, 1, -1, 1], np.float32)
    got = []
    for _ in range(30):
        obs, _, _, _, infos = env.step({a: np.concatenate([[0.0, 0.0], pattern]) for a in env.agents})
        for o in obs.values():
            m = o["messages"]
            got.extend(m[m[:, 0] > 0, 2:].tolist())
    assert len(got) > 5, "facing robots 20 cm apart must exchange messages"
    # most decoded payloads are exactly what was sent (bit errors are possible, not the rule)
    exact = np.mean([np.array_equal(np.array(g) > 0.5, pattern > 0) for g in got])
    assert exact > 0.7
    assert "tx_started" in infos["robot_0"]["sensing"]


def test_droplet_near_model_in_the_env():
    env, (r, b, h, r_true, b_true, h_true) = collect("droplet", steps=10, rb_schedule="every_step", rb_near_model=True)
    near = r_true < 0.20
    err = r[near] - r_true[near]
    assert near.sum() > 20 and abs(err.mean()) + err.std() < env.platform.diameter
    with pytest.raises(ValueError, match="rb_near_model"):
        swarm_envs.make("swarm_envs/Aggregation-v0", platform="epuck", rb_near_model=True)


@pytest.mark.parametrize("platform", ["droplet", "epuck"])
def test_range_bearing_on_the_worker_thread_gives_the_same_steps(platform, monkeypatch):
    """Range & bearing on the worker thread, alongside SwarmCom, the channel's random numbers drawn there
    while the physics runs, and the rewards alongside the sensing (large single scenes) give the same
    observations, rewards and infos bit for bit as on the calling thread."""
    import swarm_envs.sensing.full as full

    def run(on_worker):
        monkeypatch.setattr(full, "rb_on_worker_thread", lambda n_links: on_worker)
        env = swarm_envs.make("swarm_envs/Aggregation-v0", n_robots=40, sensing="full", platform=platform)
        obs, _ = env.reset(seed=11)
        rng = np.random.default_rng(3)
        trace = []
        for _ in range(25):
            actions = {a: rng.uniform(-1, 1, env.action_space(a).shape).astype(np.float32) for a in env.agents}
            obs, rewards, _, _, infos = env.step(actions)
            a = env.agents[0]
            trace.append((obs[a], rewards[a], infos[a]))
        return trace

    on_worker, here = run(True), run(False)
    for (o1, r1, i1), (o2, r2, i2) in zip(on_worker, here):
        assert r1 == r2
        for k in o1:
            np.testing.assert_array_equal(o1[k], o2[k])
        assert_tree_equal(i1, i2)


@pytest.mark.parametrize("platform", ["droplet", "epuck", "rone"])
def test_gain_rows_left_in_the_chunks_give_the_same_steps(platform, monkeypatch):
    """With the gain kernel on two threads, range & bearing reads the firing links' rows where the chunks
    left them (no gather; the sector bearings gather first): the same observations, rewards and infos bit
    for bit as one thread and the worker thread off."""
    import swarm_envs.ir.layer as layer
    import swarm_envs.sensing.full as full

    def run(threads):
        monkeypatch.setattr(layer, "gain_threads", lambda n_pairs: threads)
        monkeypatch.setattr(full, "rb_on_worker_thread", lambda n_links: threads > 1)
        env = swarm_envs.make("swarm_envs/Flocking-v0", n_robots=30, sensing="full", platform=platform)
        obs, _ = env.reset(seed=4)
        rng = np.random.default_rng(6)
        trace = []
        for _ in range(12):
            actions = {a: rng.uniform(-1, 1, env.action_space(a).shape).astype(np.float32) for a in env.agents}
            obs, rewards, _, _, infos = env.step(actions)
            trace.append((obs, rewards, infos))
        return trace

    for (o1, r1, i1), (o2, r2, i2) in zip(run(2), run(1)):
        assert r1 == r2
        for a in o1:
            for k in o1[a]:
                np.testing.assert_array_equal(o1[a][k], o2[a][k])
            assert_tree_equal(i1[a], i2[a])


def test_an_error_on_the_worker_thread_reaches_the_caller(monkeypatch):
    import swarm_envs.sensing.full as full

    monkeypatch.setattr(full, "rb_on_worker_thread", lambda n_links: True)
    env = swarm_envs.make("swarm_envs/Aggregation-v0", n_robots=10, sensing="full", platform="epuck")
    env.reset(seed=0)

    def broken(links, fired=None, gain_rows=None):
        raise RuntimeError("range & bearing failed")

    monkeypatch.setattr(env.unwrapped.core.sensing.rb, "step", broken)
    with pytest.raises(RuntimeError, match="range & bearing failed"):
        env.step({a: np.zeros(env.action_space(a).shape, np.float32) for a in env.agents})


def test_an_error_building_the_observation_rows_on_the_worker_reaches_the_caller(monkeypatch):
    """The readings' observation rows are built on the worker while the exchange runs here; their error is
    raised by the step (after the step's own work, which it does not mask)."""
    import swarm_envs.sensing.full as full

    monkeypatch.setattr(full, "rb_on_worker_thread", lambda n_links: True)
    env = swarm_envs.make("swarm_envs/Aggregation-v0", n_robots=10, sensing="full", platform="epuck")
    env.reset(seed=0)

    def broken(neighbours, n, k):
        raise RuntimeError("observation rows failed")

    monkeypatch.setattr(full, "_observation_rows", broken)
    with pytest.raises(RuntimeError, match="observation rows failed"):
        env.step({a: np.zeros(env.action_space(a).shape, np.float32) for a in env.agents})


def test_an_error_drawing_ahead_on_the_worker_reaches_the_caller(monkeypatch):
    import swarm_envs.sensing.full as full

    monkeypatch.setattr(full, "rb_on_worker_thread", lambda n_links: True)
    env = swarm_envs.make("swarm_envs/Aggregation-v0", n_robots=10, sensing="full", platform="epuck")
    env.reset(seed=0)
    zeros = {a: np.zeros(env.action_space(a).shape, np.float32) for a in env.agents}
    env.step(zeros)  # the sensing now calls the scene large: the next step draws ahead on the worker

    def broken(payloads, sending):
        raise RuntimeError("drawing ahead failed")

    monkeypatch.setattr(env.unwrapped.core.sensing, "prepare_step", broken)
    with pytest.raises(RuntimeError, match="drawing ahead failed"):
        env.step(zeros)


def test_a_prepared_step_takes_no_payloads_and_equals_the_inline_step():
    """FullSensing.prepare_step (queue and draw ahead) then step(prepared=...) gives the frame step(payloads)
    gives; payloads given twice are refused before anything is sensed."""
    import swarm_envs.sensing.full as full

    def stack():
        env = swarm_envs.make("swarm_envs/Flocking-v0", n_robots=12, sensing="full", platform="epuck", message_bits=4)
        env.reset(seed=5)
        return env.unwrapped.core

    a, b = stack(), stack()
    rng = np.random.default_rng(1)
    delivered = 0
    for _ in range(6):
        payloads = rng.random((12, 4)) > 0.5
        ahead = b.sensing.prepare_step(payloads)
        fa = a.sensing.step(a.positions, a.headings, payloads)
        fb = b.sensing.step(b.positions, b.headings, prepared=ahead)
        np.testing.assert_array_equal(fa.messages.receiver, fb.messages.receiver)
        np.testing.assert_array_equal(fa.messages.payload, fb.messages.payload)
        np.testing.assert_array_equal(fa.neighbours.range, fb.neighbours.range)
        delivered += len(fa.messages.receiver)
    assert delivered > 0  # application messages did go through the queues
    assert isinstance(b.sensing, full.FullSensing)
    with pytest.raises(ValueError, match="either payloads or prepared"):
        b.sensing.step(b.positions, b.headings, payloads, prepared=b.sensing.prepare_step(None))


@pytest.mark.parametrize("platform", ["droplet", "rone", "epuck"])
def test_message_bearing_is_the_detector_axis_wrapped_to_minus_pi_pi(platform):
    """A message's bearing column is its detector's axis / pi in (-1, 1]: detectors whose axis lies past pi
    (Droplet, r-one axes run over [0, 2 pi)) stay distinct instead of clipping to 1."""
    env = swarm_envs.make("swarm_envs/Aggregation-v0", n_robots=10, platform=platform, sensing="full", message_bits=1)
    env.reset(seed=0)
    axes = np.angle(np.exp(1j * env.platform.detector_directions)) / np.pi
    axes[np.isclose(axes, -1.0)] = 1.0
    rng = np.random.default_rng(0)
    seen = []
    for _ in range(40):
        obs, *_ = env.step({a: rng.uniform(-1, 1, env.action_space(a).shape).astype(np.float32) for a in env.agents})
        for a in env.agents:
            m = obs[a]["messages"]
            seen.extend(m[m[:, 0] > 0, 1].tolist())
    seen = np.asarray(seen)
    assert seen.size > 0
    assert np.all(np.min(np.abs(seen[:, None] - axes[None, :]), axis=1) < 1e-6)  # every value is one detector's axis
    assert np.unique(np.round(seen, 5)).size > len(axes) // 2  # not clipped onto a few values
