"""Per-robot infrared switches (Task.transmit_off / Task.receive_off): a receive-only robot and a single
sender among listeners through the public API ([T20] Fig. 12a's one-way pair, Fig. 21's static sender)."""

import numpy as np
import pytest

import swarm_envs
from swarm_envs.tasks.aggregation_v0 import AggregationTask
from swarm_envs.ir.layer import compute_links


class OneWay(AggregationTask):
    """Robot 0 transmits only (detectors off), every other robot receives only (emitters off)."""

    def transmit_off(self, num_cycles):
        off = np.ones((self.n_copies, self.n_world), bool)
        off[:, 0] = False
        return off

    def receive_off(self, num_cycles):
        off = np.zeros((self.n_copies, self.n_world), bool)
        off[:, 0] = True
        return off


POS = np.array([[0.0, 0.0], [0.3, 0.0], [-0.3, 0.0], [0.0, 0.3]])


@pytest.mark.parametrize("sensing", ["full", "ideal"])
@pytest.mark.parametrize("platform", ["epuck", "rone"])
def test_single_sender_among_listeners(sensing, platform):
    env = swarm_envs.make(OneWay, n_robots=4, sensing=sensing, platform=platform, message_bits=2, arena_size=1.0)
    env.reset(seed=0, options={"positions": POS, "headings": np.array([0.0, np.pi, 0.0, -np.pi / 2])})
    heard = np.zeros(4, int)
    for _ in range(60):
        env.step({a: np.array([0.0, 0.0, 1.0, -1.0], np.float32) for a in env.agents})
        frame = env.core.frame
        assert not np.isin(0, frame.neighbours.rx) and np.all(frame.neighbours.tx == 0)
        assert not np.isin(0, frame.messages.receiver) and np.all(frame.messages.sender == 0)
        heard += np.bincount(frame.messages.receiver, minlength=4)
    assert heard[0] == 0 and np.all(heard[1:] > 0), heard


def test_compute_links_switches_drop_one_direction():
    head = np.array([0.0, np.pi])
    pos = np.array([[0.0, 0.0], [0.1, 0.0]])
    both = compute_links(pos, head, "epuck")
    assert sorted(zip(both.rx.tolist(), both.tx.tolist())) == [(0, 1), (1, 0)]
    one = compute_links(pos, head, "epuck", emit_off=np.array([False, True]))
    assert list(zip(one.rx.tolist(), one.tx.tolist())) == [(1, 0)]
    np.testing.assert_array_equal(one.gains[0], both.gains[both.rx == 1][0])
    deaf = compute_links(pos, head, "epuck", detect_off=np.array([False, True]))
    assert list(zip(deaf.rx.tolist(), deaf.tx.tolist())) == [(0, 1)]


def test_switch_hook_must_be_a_bool_mask():
    bad = type("Bad", (AggregationTask,), {"transmit_off": lambda self, c: np.zeros((1, 3))})
    env = swarm_envs.make(bad, n_robots=3, sensing="ideal")
    with pytest.raises(TypeError, match=r"Bad.transmit_off\(\) returned"):
        env.reset(seed=0)
