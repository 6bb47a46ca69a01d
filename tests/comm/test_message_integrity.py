"""Message integrity of the SwarmCom frames (docs/design.md#swarmcom-messaging): the platforms' frame CRC
(CRC-16 on the r-one [L Sec. 3.2.1, Table 3.3] and the Droplet, none on the e-puck [T20]) and the
rejection of frames whose decoded header names the receiver itself."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import swarm_envs
from swarm_envs.comm.channel import recommended_relative_threshold
from swarm_envs.comm.network import BACKENDS, Network
from swarm_envs.ir.layer import compute_links
from swarm_envs.sim.platforms import get_platform
from swarm_envs.tasks.task import Task


def test_frame_crc_per_platform():
    """CRC-16 on the r-one and the Droplet in every mode; none on the e-puck in broadcast (as [T20]), our
    CRC-8 when it floods; an explicit crc_bits wins."""
    rng = np.random.default_rng(0)
    want = {("rone", "broadcast"): 16, ("rone", "flooding"): 16, ("droplet", "broadcast"): 16,
            ("droplet", "flooding"): 16, ("epuck", "broadcast"): 0, ("epuck", "flooding"): 8}  # fmt: skip
    for (platform, mode), bits in want.items():
        net = Network(platform, 4, rng, comm_mode=mode)
        assert net.crc_bits == net.fmt.crc_bits == bits, (platform, mode)
    plain = Network("rone", 4, rng, crc_bits=0)
    checked = Network("rone", 4, rng)
    # [15,15]: the CRC costs its 16 bits on air, rounded up to whole 15-bit blocks
    blocks = lambda bits: -(-bits // 15)  # noqa: E731
    h = plain.fmt.header_bits
    assert checked.frame_slots(24) - plain.frame_slots(24) == 15 * (blocks(h + 24 + 16) - blocks(h + 24))
    assert Network("epuck", 4, rng, crc_bits=16).crc_bits == 16
    with pytest.raises(ValueError, match="frame_crc_bits"):
        dataclasses.replace(get_platform("rone"), frame_crc_bits=12)


def _pair(platform: str, backend: str, n: int = 3, **kw) -> tuple[object, Network]:
    """Robots 0 and 1 facing each other 0.2 m apart; robot 2 (if any) out of IR range, never transmitting."""
    pos = np.array([[0.0, 0.0], [0.2, 0.0], [5.0, 5.0]])[:n]
    links = compute_links(pos, np.array([0.0, np.pi, 0.0])[:n], platform)
    kw.setdefault("relative_threshold", recommended_relative_threshold(platform))
    net = Network(platform, n, np.random.default_rng(1), backend=backend, **kw)
    for kind in ("bearing", "bearing_beacon"):  # system kinds 2 and 3
        net.kinds.code(kind)
    return links, net


def _queue_crafted(net: Network, robot: int, origin: int, sender: int, flip: int | None = None, kind: str = "app") -> None:
    """Queue at ``robot`` one frame (8-bit payload) whose header names ``origin`` / ``sender``, with the on-air
    bit of information bit ``flip`` inverted after the frame (and its CRC) was built ([15,15]: bit i on air is
    information bit i, after the start symbol)."""
    assert net.code.k == net.code.n
    payload = np.array([[1, 0, 1, 1, 0, 0, 1, 0]], bool)
    bits, slots = net._build(np.array([net.kinds.code(kind)]), np.array([5]), np.array([origin]), np.array([sender]), payload, np.array([8]))
    if flip is not None:
        bits[0, 1 + flip] ^= True
    net._enqueue(np.array([robot]), bits, slots, np.array([0]))


def _run(net: Network, links, steps: int = 8) -> list:
    out = []
    for _ in range(steps):
        d = net.step(links)
        out += list(zip(d.receiver.tolist(), d.origin.tolist(), d.sender.tolist(), d.kind.tolist(), d.payloads()))
    return out


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("platform", ["rone", "droplet"])
@pytest.mark.parametrize("where", ["origin", "type", "payload"])
def test_a_frame_with_one_flipped_bit_is_dropped(platform, backend, where):
    """Robot 0 sends a frame whose origin, type or payload bit flipped on the way (built, then one on-air bit
    inverted). Without a CRC robot 1 takes it: a message from robot 2, which sent nothing, or a wrong
    payload. With the platform's CRC-16 it is dropped and counted; the same frame unflipped is delivered."""
    links, net = _pair(platform, backend)
    id_bits, h = net.fmt.id_bits, net.fmt.header_bits
    flip = {"origin": 19 + id_bits - 2, "type": 2, "payload": h + 2}[where]  # origin 0 -> 2; type 1 (app) -> 3
    _queue_crafted(net, 0, 0, 0)
    got = _run(net, links)
    assert [(r, o) for r, o, *_ in got] == [(1, 0)]  # the clean frame arrives
    _queue_crafted(net, 0, 0, 0, flip=flip)
    got = _run(net, links)
    assert got == [], f"a frame with a flipped {where} bit was delivered: {got}"
    assert net.stats["rx_crc_failed"] == 1 and net.stats["rx_decode_failed"] == 1
    # the control: without a CRC the corrupted frame is taken as a valid message
    links, plain = _pair(platform, backend, crc_bits=0)
    _queue_crafted(plain, 0, 0, 0, flip=flip)
    got = _run(plain, links)
    assert len(got) == 1 and got[0][0] == 1
    if where == "origin":
        assert got[0][1] == 2  # named for robot 2
    elif where == "type":
        assert got[0][3] == "bearing_beacon"
    else:
        assert not np.array_equal(got[0][4], [1, 0, 1, 1, 0, 0, 1, 0])


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("mode,field", [("broadcast", "origin"), ("flooding", "origin"), ("flooding", "sender")])
@pytest.mark.parametrize("kind", ["app", "bearing"])
def test_a_frame_naming_the_receiver_itself_is_not_delivered(backend, mode, field, kind):
    """A frame whose decoded origin (or, flooding, last hop; broadcast headers carry no separate sender) is
    the receiver itself is rejected in every mode and for every kind (the Droplet firmware rejects
    ``selfSender``); a robot never hears its own frames."""
    links, net = _pair("epuck", backend, n=2, comm_mode=mode, relative_threshold=15)  # few noise starts
    origin, sender = (1, 0) if field == "origin" else (0, 1)
    if mode == "broadcast":
        sender = origin
    _queue_crafted(net, 0, origin, sender, kind=kind)
    got = _run(net, links)
    assert got == [], f"robot 1 accepted a frame naming itself: {got}"
    assert net.stats["rx_self_named"] == 1 and net.stats["rx_decoded"] == 1
    assert net.stats["tx_relays"] == 0  # and did not flood it on
    _queue_crafted(net, 0, 0, 0, kind=kind)  # the control: robot 0's own frame reaches robot 1
    assert [(r, o) for r, o, *_ in _run(net, links)] == [(1, 0)]


class _SwitchOff(Task):
    """Robots 0 and 1 switched off from step 5 on; rewards zero."""

    METRICS = {"zero": "mean"}

    def default_arena_size(self) -> float:
        return 0.8

    def rewards(self, state, first):
        return np.zeros((self.n_copies, self.n_agents)), {}, {"zero": np.zeros(self.n_copies)}

    def switched_off(self, num_cycles):
        off = np.zeros((self.n_copies, self.n_world), bool)
        off[:, :2] = num_cycles >= 5
        return off


def test_rone_keeps_no_readings_of_robots_that_went_silent():
    """The phantom-reading scenario: on the r-one, once robots 0 and 1 are switched off (in no IR link), no
    other robot decodes a frame naming them, so no reading or message is named for them after the last
    real reading expired (36 steps). With an uncoded, unchecked header corrupted frames keep naming them
    (hundreds of readings in this run); the CRC-16 drops those frames."""
    env = swarm_envs.make(_SwitchOff, n_robots=10, sensing="full", platform="rone", message_bits=8, observe_ids=True)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    phantom_readings = phantom_messages = 0
    for t in range(1, 250):
        env.step({a: rng.uniform(-1, 1, env.action_space(a).shape).astype(np.float32) for a in env.agents})
        frame = env.core.frame
        if t > 5 + 36 + 1:
            phantom_readings += int(np.isin(frame.neighbours.tx, [0, 1]).sum())
        if t > 5:
            phantom_messages += int(np.isin(frame.messages.sender, [0, 1]).sum())
    assert phantom_readings == 0 and phantom_messages == 0, (phantom_readings, phantom_messages)
    stats = env.core.sensing.network.stats
    assert stats["rx_crc_failed"] > 0  # corrupted frames arrived and were dropped
    assert stats["rx_corrupt_delivered"] == 0


def test_epuck_messages_never_name_their_receiver():
    """e-puck, uncoded [T20] frames in a dense group: corrupted headers do name the receiver itself (counted),
    and none of them reaches the messages observation."""
    env = swarm_envs.make("swarm_envs/Aggregation-v0", n_robots=20, sensing="full", platform="epuck", message_bits=8, arena_size=0.6)
    env.reset(seed=0)
    rng = np.random.default_rng(0)
    for _ in range(300):
        env.step({a: rng.uniform(-1, 1, env.action_space(a).shape).astype(np.float32) for a in env.agents})
        m = env.core.frame.messages
        assert not (m.sender == m.receiver).any()
    assert env.core.sensing.network.stats["rx_self_named"] > 0
