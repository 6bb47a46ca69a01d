"""The range & bearing firing schedule (docs/design.md#range-and-bearing): each robot fires on its own timer,
as the Droplet firmware, and reads no link; the contention oracle is an ablation."""

from __future__ import annotations

import numpy as np
import pytest

import swarm_envs
from swarm_envs.sim.copies import CopyRandom
from swarm_envs.ir.layer import compute_links
from swarm_envs.ir.links import IRLinks
from swarm_envs.sensing.range_bearing import TIMER_JITTER, TIMER_PERIOD, RangeBearingSensor
from swarm_envs.validate.envs import scene_core


def _clique(n=5, radius=0.07, seed=0):
    """n Droplets on a circle (radius m): every robot sees every other."""
    ang = np.arange(n) * 2 * np.pi / n
    pos = radius * np.stack([np.cos(ang), np.sin(ang)], -1)
    hd = np.random.default_rng(seed).uniform(-np.pi, np.pi, n)
    links = compute_links(pos, hd, "droplet")
    assert len(links) == n * (n - 1)
    return pos, hd, links


class _NoGraph(IRLinks):
    """Links whose graph (rx, tx) cannot be read."""

    def __getattribute__(self, name):
        if name in ("rx", "tx"):
            raise AssertionError(f"the schedule read links.{name}")
        return super().__getattribute__(name)


def _no_graph(links):
    return _NoGraph(links.rx, links.tx, links.distance, links.rel_position, links.rel_heading, links.gains, links.n_robots)


def test_the_timer_schedule_reads_no_link_and_the_oracle_does():
    *_, links = _clique()
    hidden = _no_graph(links)
    with pytest.raises(AssertionError):
        hidden.rx
    timer = RangeBearingSensor("droplet", 5, np.random.default_rng(1))
    assert timer.schedule == "timer"
    fired = np.array([timer.fire_mask(hidden) for _ in range(40)])
    assert fired.any(axis=0).all()  # every robot fires at some step, without the link graph
    with pytest.raises(AssertionError, match="links.rx"):
        RangeBearingSensor("droplet", 5, np.random.default_rng(1), schedule="contention").fire_mask(hidden)


def test_each_robot_fires_once_per_period_plus_its_late_start_from_a_random_phase():
    n, steps = 40, 400
    links = compute_links(np.array([[0.0, 0.0], [5.0, 5.0]]), np.zeros(2), "droplet")  # unused by the timer
    s = RangeBearingSensor("droplet", n, np.random.default_rng(3))
    fired = np.array([s.fire_mask(links) for _ in range(steps)])
    first = fired.argmax(axis=0)
    assert first.max() < round(TIMER_PERIOD / 0.1) and len(np.unique(first)) > 5  # phases spread over one period
    gaps = np.concatenate([np.diff(np.flatnonzero(fired[:, k])) for k in range(n)])
    lo, hi = round(TIMER_PERIOD / 0.1), int(np.ceil((TIMER_PERIOD + TIMER_JITTER) / 0.1))
    assert gaps.min() >= lo - 1 and gaps.max() <= hi
    assert len(np.unique(gaps)) > 1  # the late starts vary the intervals
    np.testing.assert_allclose(gaps.mean(), (TIMER_PERIOD + TIMER_JITTER / 2) / 0.1, rtol=0.05)
    # without late starts a robot fires every period exactly
    s0 = RangeBearingSensor("droplet", n, np.random.default_rng(3), period=0.5, jitter=0.0)
    fired0 = np.array([s0.fire_mask(links) for _ in range(100)])
    assert {int(g) for k in range(n) for g in np.diff(np.flatnonzero(fired0[:, k]))} <= {4, 5, 6}
    assert fired0.sum() == pytest.approx(n * 100 / 5, rel=0.05)


def test_two_robots_that_see_each_other_can_fire_together_and_a_shared_neighbour_sees_the_collision():
    """Robots 0 and 1 see each other and robot 2 sees both. Their timers expire in the same step: both fire
    (no carrier sense, as the firmware's rnb_r), neither measures the other (it is firing), and robot 2's
    matrix holds both lights, so it gets no clean reading of either. The contention oracle never lets two
    linked robots fire in the same step."""
    *_, links = _clique(3)
    alone = RangeBearingSensor("droplet", 3, np.random.default_rng(4), noise_sigma=0.0)
    alone.countdown[:] = [0.03, 0.5, 0.5]  # robot 0 fires alone: robots 1 and 2 read it cleanly
    r = alone.step(links)
    np.testing.assert_array_equal(r.rx, [1, 2])
    np.testing.assert_array_equal(r.tx, [0, 0])
    assert np.all(r.n_overlap == 1)
    s = RangeBearingSensor("droplet", 3, np.random.default_rng(4), noise_sigma=0.0)
    s.countdown[:] = [0.03, 0.07, 0.5]
    r = s.step(links)
    np.testing.assert_array_equal(s.last_fired, [True, True, False])
    fresh = r.age == 0
    assert not np.any(np.isin(r.rx[fresh], [0, 1]))  # the firing robots measured nothing
    at2 = fresh & (r.rx == 2)
    assert not np.any(at2 & (r.n_overlap == 1))  # no clean reading at the shared neighbour
    assert np.all(r.n_overlap[at2] == 2)  # whatever it kept (if anything) is the superposed light

    oracle = RangeBearingSensor("droplet", 3, np.random.default_rng(4), schedule="contention")
    for _ in range(200):
        oracle.step(links)
        assert oracle.last_fired.sum() == 1  # a clique: exactly one robot per step


@pytest.mark.parametrize("schedule, together", [("timer", True), ("contention", False)])
def test_in_the_env_linked_robots_collide_under_the_default_schedule(schedule, together):
    """Five static Droplets that all see each other, in the env: with the default schedule two of them fire in
    one step in some steps and a neighbour's fresh reading superposes both lights (ground truth in the
    stats); the contention oracle never lets that happen."""
    pos, hd, _ = _clique(5)
    kwargs = dict(platform="droplet", n_robots=5, sensing="full", max_cycles=200, arena_size=1.0)
    if schedule != "timer":
        kwargs["rb_schedule"] = schedule
    core = scene_core("swarm_envs/Aggregation-v0", [pos], [hd], [7], **kwargs)
    still = np.zeros((core.n_total, core.layout.action_size))
    pairs = overlapped = 0
    for _ in range(120):
        core.step(still)
        stats = core.frame.stats
        pairs += int(stats["rb_fired"].sum() >= 2)
        overlapped += int(stats["rb_overlapped"].sum())
    assert (pairs > 0) == together and (overlapped > 0) == together


def test_copies_draw_their_own_timers_and_equal_single_sensors():
    """Two copies of the timer schedule fire exactly as two single sensors seeded the same, and a reset of
    one copy gives it new phases from its new stream, as a single sensor reset with that stream."""
    n = 8
    links = compute_links(np.array([[0.0, 0.0], [5.0, 5.0]]), np.zeros(2), "droplet")
    vec = RangeBearingSensor("droplet", n, CopyRandom([np.random.default_rng(s) for s in (5, 6)]))
    singles = [RangeBearingSensor("droplet", n, np.random.default_rng(s)) for s in (5, 6)]
    for _ in range(30):
        f = vec.fire_mask(links)
        np.testing.assert_array_equal(f, np.concatenate([s.fire_mask(links) for s in singles]))
    vec.reset(np.array([1]), [np.random.default_rng(9)])
    singles[1].reset(np.array([0]), [np.random.default_rng(9)])
    np.testing.assert_array_equal(vec.countdown[n:], singles[1].countdown)
    assert not np.array_equal(vec.countdown[:n], vec.countdown[n:])
    for _ in range(30):
        np.testing.assert_array_equal(vec.fire_mask(links), np.concatenate([s.fire_mask(links) for s in singles]))


def test_readings_persist_until_the_next_timer_firing_by_default():
    from swarm_envs.sensing.full import RB_MAX_AGE, rb_max_age

    cfg = {"rb_max_age": None, "rb_schedule": "timer", "rb_period": 1.0, "rb_jitter": 0.2}
    assert rb_max_age(cfg) == 13  # 12 steps until the latest next firing, plus the step it lands in
    assert rb_max_age({**cfg, "rb_period": 3.0, "rb_jitter": 0.0}) == 31
    assert rb_max_age({**cfg, "rb_schedule": "contention"}) == rb_max_age({**cfg, "rb_schedule": "every_step"}) == RB_MAX_AGE
    assert rb_max_age({**cfg, "rb_max_age": 4}) == 4
    env = swarm_envs.make("swarm_envs/Aggregation-v0", n_robots=2, platform="droplet", rb_period=2.0)
    assert env.layout.max_age == 23 and env.core.sensing.rb.max_age == 23
