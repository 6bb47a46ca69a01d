"""r-ones at contact range hear each other (issue #34): the transmitters light their outward half-plane
[L Sec. 3.2.1, "a radially uniform energy pattern"; swarm_envs.ir.models.RoneIR], so a neighbour 11-18 cm
away (centre distance; the body is 11 cm across) is heard, its messages arrive, and its sector bearing and
transmitter-index orientation are right to the sector."""

import numpy as np
import pytest

from swarm_envs.comm.network import Network
from swarm_envs.ir.layer import compute_links
from swarm_envs.sensing.bearing_sensor import MessageBearings, cover_mask, sense_bearings

RONE = "rone"


def _wrap_deg(a):
    return np.rad2deg(np.angle(np.exp(1j * np.asarray(a))))


def _pair(d_m: float, bearing: float, h0: float, h1: float):
    """Robot 0 at the origin heading h0, robot 1 at world angle ``bearing + h0`` (so at ``bearing`` in 0's
    frame), heading h1 (rad)."""
    a = bearing + h0
    pos = np.array([[0.0, 0.0], [d_m * np.cos(a), d_m * np.sin(a)]])
    return compute_links(pos, np.array([h0, h1]), RONE)


# (bearing of 1 in 0's frame, heading of 0, heading of 1) in degrees; true heading of 1 in 0's frame = h1 - h0
ORIENTATIONS = [(0.0, 0.0, 180.0), (0.0, 90.0, 270.0), (-22.5, 22.5, 180.0), (0.0, 0.0, 202.5), (0.0, 90.0, 90.0), (45.0, 0.0, 225.0)]


@pytest.mark.parametrize("d_cm", [11, 12, 14, 16, 18])
@pytest.mark.parametrize("b, h0, h1", ORIENTATIONS)
def test_close_neighbours_are_heard_with_sector_bearing_and_orientation(d_cm, b, h0, h1):
    links = _pair(d_cm / 100.0, *np.deg2rad([b, h0, h1]))
    rd = sense_bearings(links, RONE)
    k = np.flatnonzero((links.rx == 0) & (links.tx == 1))
    assert k.size == 1 and rd.valid[k[0]]
    g = np.asarray(links.gains).reshape(-1, 8, 8)[k[0]]
    assert g.sum() >= 1
    # bearing within half a receiver sector (22.5 deg / 2) of the truth, orientation within half an
    # orientation sector (45 deg / 2) plus the bearing's share
    assert abs(_wrap_deg(rd.bearing[k[0]] - np.deg2rad(b))) <= 11.25 + 1e-9
    assert abs(_wrap_deg(rd.heading[k[0]] - np.deg2rad(h1 - h0))) <= 22.5 + 11.25 + 1e-9


def test_every_orientation_from_13_to_18_cm_is_heard_and_right_to_a_sector():
    """A grid of neighbour bearings (7.5 deg) and headings (15 deg) at 13-18 cm: every pair links, the
    bearing is never more than one receiver sector (22.5 deg) off and the orientation never more than one
    orientation sector (45 deg) off."""
    eb, eh = [], []
    for d_cm in (13, 15, 18):
        for b in np.arange(0.0, 360.0, 7.5):
            for h1 in np.arange(0.0, 360.0, 15.0):
                links = _pair(d_cm / 100.0, np.deg2rad(b), 0.0, np.deg2rad(h1))
                k = np.flatnonzero((links.rx == 0) & (links.tx == 1))
                assert k.size == 1, (d_cm, b, h1)
                rd = sense_bearings(links, RONE)
                assert rd.valid[k[0]], (d_cm, b, h1)
                eb.append(_wrap_deg(rd.bearing[k[0]] - np.deg2rad(b)))
                eh.append(_wrap_deg(rd.heading[k[0]] - np.deg2rad(h1)))
    assert np.abs(eb).max() <= 22.5 + 1e-9 and np.abs(eh).max() <= 45.0 + 1e-9


@pytest.mark.parametrize("d_cm", [12, 15, 18])
@pytest.mark.parametrize("b, h0, h1", ORIENTATIONS[:4])
def test_close_neighbours_messages_arrive_and_measure_the_sector(d_cm, b, h0, h1):
    """Back-to-back beacons of robot 1 over SwarmCom for 200 steps: robot 0 decodes them and measures the
    bearing of each on its receivers."""
    links = _pair(d_cm / 100.0, *np.deg2rad([b, h0, h1]))
    net = Network(RONE, 2, np.random.default_rng(0))
    mb = MessageBearings(RONE, 2, np.random.default_rng(1))
    got, bearings = 0, []
    for _ in range(200):
        if net.q_count[1] == 0:
            net.queue_system(1, np.zeros((1, 0), bool), "beacon")
        d = net.step(links)
        mb.step(d, links)
        got += int(((d.receiver == 0) & (d.origin == 1)).sum())
        f = mb.fresh
        bearings += f.bearing[(f.rx == 0) & (f.tx == 1)].tolist()
    assert got > 50 and len(bearings) == got
    assert np.abs(_wrap_deg(np.asarray(bearings) - np.deg2rad(b))).max() <= 11.25 + 1e-9


def test_transmitter_rule_takes_the_smallest_run_covering_the_heard_transmitters():
    assert cover_mask(0b10000010) == 0b10000011  # transmitters 1 and 7 -> 7, 0, 1
    assert cover_mask(0b00000110) == 0b00000110
    assert cover_mask(0) == 0 and cover_mask(0xFF) == 0xFF
