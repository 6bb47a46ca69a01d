"""Validation of the SwarmCom simulation against [T20] (Secs. 5-7).

``python -m swarm_envs.validate swarmcom [--json] [--experiment a|b|c|d|e|all] [--out DIR] [--no-plots] [--quick]
[--fig21-mtr M ...] [--seed S] [--fit-response]``; each experiment draws from its own stream of the seed, so
``--experiment x`` gives the numbers of x in a full run.

(a) two static e-pucks facing each other, 310 bps, dynamic detector: communication range vs relative
    threshold m_tr (75, 25, 10 -> 21, 33, 45 cm [T20 Sec. 6.2.4, Fig. 12a]) and bit error probability vs
    distance (reliable, P_e < 0.01, up to 61 cm with m_tr = 5 [T20 Sec. 7, Fig. 11]);
(b) channels per robot n_C vs density: a centre robot, range 61 cm, 1..272 others at random in that disc
    (n_C bounded by ~15, 6 at hexagonal packing [T20 Sec. 6.2.6, Fig. 20a], m_tr = 5) and the 72 x 72 cm
    arena with 10, 20, 30 robots (n_C = 4, 6, 9 in single snapshots [Fig. 21]; ours: the distribution over
    random-walk snapshots; m_tr = 10, the mobile experiments' [Sec. 6.2.2], and 5). A robot is a channel
    when it can distinguish the centre's s_0 from s_1 [Sec. 6.2.6]: counted through the simulated receiver
    (:func:`detector_channels`: ADC noise, detector response, min over detectors, start detection and
    dynamic threshold; it must receive at least half of the centre's frames intact) and, as a second row,
    as a noiseless amplitude above m_tr (:func:`centre_amplitude`) for per-ray line of sight (as
    simulated) and for a centre-line rule, with m_tr swept over the paper's 61/45/33/21 cm settings;
(c) local broadcast vs flooding: 2..7 robots doing the random walk of [T20 Alg. 1] (t_m = 2 s) in the
    72 x 72 cm arena, 310 bps, m_tr = 10; message loss P_l (a message is lost for a robot that has not
    received it 2 s after it was queued) [T20 Sec. 6.2.2, Fig. 16b]; flooding is run with the network's
    default CRC-8 and without it (then corrupted copies are re-flooded as new messages);
(d) channel coding: measured 15-bit block (message) error with [15,11] and [15,1] vs the prediction
    1 - P_f of Eq. (34) from the P_e measured without coding [T20 Sec. 5.4, Fig. 13];
(e) reliable range (P_e < 0.01) and communication range vs bit rate, static facing pair, m_tr = 5: 61 cm
    at 310 bps, 14 cm at 1800 bps [T20 Sec. 7] -- a two-parameter fit (the detector response's c to 14 cm at
    1800 bps, b to 61 cm at 310 bps), so these two agree by construction -- and the rates between, the
    model's predictions (Figs. 10-12b, values not in the text),
    and the 21 cm setting of [T20 Sec. 6.2.5] at 310/1080/1670 bps. ``--fit-response`` refits the detector
    response's charge constant c to 14 cm at 1800 bps (:mod:`swarm_envs.comm.channel` docstring).

Everything runs the bit-level :class:`swarm_envs.comm.network.Network` over the IR links of
:func:`swarm_envs.ir.layer.compute_links`; independent static pairs (a, d) and independent arenas (c) are
simulated side by side in one network, 3 m apart (beyond the 1 m IR range), so they cannot interact
(the id field is then wider than for one pair: 8 bits instead of 6, a few more header bits).
Run times are printed at the end of each run.
"""

from __future__ import annotations

import functools
import json
import os
import time
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

from swarm_envs.comm.bch import error_free_probability
from swarm_envs.comm.channel import M_MAX, M_MIN, RESPONSE_BIAS, ADCModel, gain_to_intensity
from swarm_envs.comm.network import Network
from swarm_envs.sim.copies import CopyRandom
from swarm_envs.sim.geometry import wrap_angle
from swarm_envs.ir.layer import compute_links, pair_gains
from swarm_envs.ir.occlusion import line_of_sight, occluder_width, pair_occluders
from swarm_envs.sim.platforms import get_platform
from swarm_envs.validate.report import Row, print_rows, rows_json
from swarm_envs.tasks.settings import Int, OneLineArgumentParser, cli_type

PLATFORM = "epuck"
SEP = 3.0  # m between independent scenes (> ir_range)
PAPER_RANGE = {75: 21.0, 25: 33.0, 10: 45.0}  # cm [T20 Sec. 6.2.4, Fig. 12a]
PAPER_RELIABLE_CM = 61.0  # [T20 Sec. 7]
PAPER_ARENA_NC = {10: 4, 20: 6, 30: 9}  # [T20 Fig. 21]
ARENA = 0.72  # m [T20 Sec. 6.1]
DISC_R = 0.61  # m, communication range used for Fig. 20a
OCC_RULES = ("ray", "centre")  # per-ray line of sight (as simulated) and a centre-line rule (a pair cut by any robot on the segment)
PAPER_MTR = 5  # Fig. 20a: the 61 cm range of m_tr = 5 [T20 Sec. 6.2.6 ("see Table 12a"), Sec. 7]
#: Fig. 21's m_tr is not stated in [T20 Sec. 6.2.6]; the mobile experiments of Sec. 6.2.2 (and 6.2.3, configured
#: "as in the flooding experiment") use m_tr = 10 (45 cm). Both that and Fig. 20a's m_tr = 5 are measured.
FIG21_MTR = 10
FIG21_MTRS = (FIG21_MTR, PAPER_MTR)
M_TR_SWEEP = (5, 10, 25, 75)  # relative thresholds of the paper's ranges 61, 45, 33, 21 cm [Sec. 6.2.4, 7]
PAPER_FIG20A = {"bound": 15, "densest": 6}  # [T20 Sec. 6.2.6]
PAPER_BITRATE_RELIABLE = {310: 61.0, 1800: 14.0}  # cm, P_e < 0.01, m_tr = 5 [T20 Sec. 7]
BITRATE_SWEEP = (310, 650, 1080, 1160, 1670, 1800)  # the e-puck's rates [T20 Sec. 5]; Fig. 10: 310, 650, 1160


# ---------------------------------------------------------------------------------------------- (a), (d)
def run_pairs(
    distances_m: np.ndarray,
    rng: np.random.Generator,
    steps: int,
    relative_threshold: float = 5,
    code: tuple[int, int] = (15, 15),
    bitrate: float = 310,
    payload_range: tuple[int, int] = (1, 40),
    adc_model: ADCModel | None = None,
) -> dict[str, np.ndarray]:
    """Static facing pairs (transmitter 2i at distance d_i from receiver 2i+1), one network.

    The transmitter queues a new random message (payload length uniform in ``payload_range`` bits, i.e. 2-5
    blocks like the paper's 1-5 random blocks) whenever it is idle; the last 10% of steps only drain.
    Returns per distance: P_e (raw bit errors / bits of aligned frames), P_l (1 - delivered / sent),
    block error rate, counts.
    """
    d = np.asarray(distances_m, dtype=float)
    K = d.size
    pos = np.zeros((2 * K, 2))
    pos[0::2, 0] = SEP * np.arange(K) + d  # transmitters
    pos[1::2, 0] = SEP * np.arange(K)  # receivers at the origin of their scene
    head = np.zeros(2 * K)
    head[0::2] = np.pi  # transmitters face the receivers
    # the one-way pair of [T20 Fig. 12a]: the receivers' emitters are off (receive-only robots, as
    # Task.transmit_off makes them in the env), so no light goes from a receiver to its transmitter
    receivers = np.zeros(2 * K, dtype=bool)
    receivers[1::2] = True
    links = compute_links(pos, head, PLATFORM, emit_off=receivers)
    net = Network(PLATFORM, 2 * K, rng, bitrate=bitrate, relative_threshold=relative_threshold, code=code, adc_model=adc_model)
    txs = np.arange(0, 2 * K, 2)
    lo, hi = payload_range
    drain = max(10, steps // 10)
    for k in range(steps):
        if k < steps - drain:
            idle = txs[(net.q_count[txs] == 0) & ~net.sending[txs]]
            if idle.size:
                L = rng.integers(lo, hi + 1, size=idle.size)
                pay = rng.integers(0, 2, size=(idle.size, hi)).astype(bool)
                net.send_many(idle, pay, lengths=L)
        net.step(links)
    s = net.stats
    rxs = txs + 1
    sent = s["tx_started_per_robot"][txs].astype(float)
    dlv = s["rx_delivered_per_robot"][rxs].astype(float)
    bc = s["bits_checked_per_robot"][rxs].astype(float)
    be = s["bit_errors_per_robot"][rxs].astype(float)
    kc = s["blocks_checked_per_robot"][rxs].astype(float)
    ke = s["block_errors_per_robot"][rxs].astype(float)
    with np.errstate(invalid="ignore", divide="ignore"):
        return {
            "distance_cm": 100 * d,
            "sent": sent,
            "delivered": dlv,
            "P_l": np.clip(1.0 - dlv / np.maximum(sent, 1), 0, 1),
            "P_e": np.where(bc > 0, be / bc, np.nan),
            "bits": bc,
            "block_error": np.where(kc > 0, ke / kc, np.nan),
            "blocks": kc,
        }


def comm_range_cm(res: dict[str, np.ndarray], max_loss: float = 0.5) -> float:
    """Largest distance (cm) up to which every tested distance delivers at least (1 - max_loss) of the
    messages (the paper moves the receiver away 1 cm at a time until messages are lost [T20 Sec. 5.1])."""
    bad = np.flatnonzero(res["P_l"] > max_loss)
    if bad.size == 0:
        return float(res["distance_cm"][-1])
    if bad[0] == 0:
        return float("nan")
    return float(res["distance_cm"][bad[0] - 1])


def reliable_range_cm(res: dict[str, np.ndarray], max_pe: float = 0.01) -> float:
    """Largest distance (cm) up to which P_e < max_pe at every tested distance (NaN P_e = no frames)."""
    pe = np.where(np.isnan(res["P_e"]), 1.0, res["P_e"])
    bad = np.flatnonzero(pe >= max_pe)
    if bad.size == 0:
        return float(res["distance_cm"][-1])
    return float(res["distance_cm"][bad[0] - 1]) if bad[0] > 0 else float("nan")


def experiment_a(rng: np.random.Generator, quick: bool) -> dict[str, Any]:
    step_cm = 2.0 if quick else 1.0
    steps = 120 if quick else 600
    dist = np.arange(7.0, 100.0 + 1e-9, step_cm) / 100.0
    out: dict[str, Any] = {"ranges": {}, "curves": {}}
    for m_tr in (75, 25, 10, 5):
        res = run_pairs(dist, rng, steps, relative_threshold=m_tr)
        out["curves"][m_tr] = {k: v.tolist() for k, v in res.items()}
        out["ranges"][m_tr] = {
            "range_cm_Pl<=0.5": comm_range_cm(res, 0.5),
            "range_cm_Pl<=0.1": comm_range_cm(res, 0.1),
            "reliable_cm_Pe<0.01": reliable_range_cm(res, 0.01),
            "paper_range_cm": PAPER_RANGE.get(m_tr, float("nan")),
        }
    out["reliable_cm"] = out["ranges"][5]["reliable_cm_Pe<0.01"]
    out["paper_reliable_cm"] = PAPER_RELIABLE_CM
    return out


# ---------------------------------------------------------------------------------------------- (b)
def _rsa(n: int, rng: np.random.Generator, inside, sample, min_dist: float, fixed: np.ndarray, max_tries: int = 20000) -> np.ndarray:
    """Random sequential addition of n discs (centres at least min_dist apart) after the ``fixed`` ones."""
    pts = [p for p in fixed]
    arr = np.array(pts).reshape(-1, 2)
    tries = 0
    while len(pts) < len(fixed) + n:
        cand = sample(64)
        cand = cand[inside(cand)]
        for c in cand:
            if arr.size == 0 or np.min(np.sum((arr - c) ** 2, axis=1)) >= min_dist**2:
                pts.append(c)
                arr = np.array(pts)
                if len(pts) == len(fixed) + n:
                    break
        tries += 1
        if tries > max_tries:
            raise RuntimeError("random sequential addition failed; density too high")
    return np.array(pts)


def _hex_disc(n_others: int, rng: np.random.Generator, radius: float, spacing: float, sweeps: int) -> np.ndarray:
    """Dense random configuration: centre robot at the origin, others on a randomly rotated hexagonal
    lattice cut to the disc (random sites kept), then hard-disk Monte Carlo shaking (conservative
    simultaneous moves: a move is accepted only if clear of every other robot's old and new position)."""
    a = spacing * 1.0005
    rot = rng.uniform(0, np.pi / 3)
    k = int(np.ceil(radius / a)) + 2
    i, j = np.meshgrid(np.arange(-k, k + 1), np.arange(-k, k + 1))
    lat = np.stack([a * (i + 0.5 * j), a * (np.sqrt(3) / 2) * j], -1).reshape(-1, 2)
    c, s = np.cos(rot), np.sin(rot)
    lat = lat @ np.array([[c, s], [-s, c]])
    r = np.hypot(lat[:, 0], lat[:, 1])
    sites = lat[(r <= radius) & (r > 1e-9)]
    n_others = min(n_others, sites.shape[0])  # the lattice holds ~270 others within 61 cm (caller reports it)
    pts = np.vstack([[0.0, 0.0], sites[rng.choice(sites.shape[0], n_others, replace=False)]])
    step = 0.5 * spacing
    for _ in range(sweeps):
        prop = pts + rng.uniform(-step, step, pts.shape)
        prop[0] = 0.0
        ok = np.hypot(prop[:, 0], prop[:, 1]) <= radius
        n = pts.shape[0]
        dd, ii = cKDTree(np.vstack([pts, prop])).query(prop, k=4)
        own = (ii == np.arange(n)[:, None]) | (ii == n + np.arange(n)[:, None])
        ok &= np.where(own, np.inf, dd).min(axis=1) >= spacing
        ok[0] = False
        pts[ok] = prop[ok]
        rate = ok[1:].mean()
        step = float(np.clip(step * (1.2 if rate > 0.4 else 0.8), 1e-4, 0.5 * spacing))
    return pts


def disc_configuration(n_others: int, rng: np.random.Generator, radius: float = DISC_R) -> np.ndarray:
    """Centre robot at the origin plus ``n_others`` non-overlapping robots with centres within ``radius``."""
    p = get_platform(PLATFORM)
    dmin = 2 * p.radius
    phi = (n_others + 1) * p.radius**2 / (radius + p.radius) ** 2
    if phi < 0.3:
        def sample(m):
            rr = radius * np.sqrt(rng.random(m))
            th = rng.uniform(-np.pi, np.pi, m)
            return np.stack([rr * np.cos(th), rr * np.sin(th)], -1)

        return _rsa(n_others, rng, lambda c: np.ones(len(c), bool), sample, dmin, np.zeros((1, 2)))
    return _hex_disc(n_others, rng, radius, dmin, sweeps=60)


def centre_links(pos: np.ndarray, head: np.ndarray, max_range: float = DISC_R, occlusion: str = "ray") -> tuple[np.ndarray, np.ndarray]:
    """The links (receiver k, transmitter 0) of every robot within ``max_range`` (m) of robot 0: the
    receivers (P,) and their noiseless gains (P, n_detectors, n_emitters) with robot 0 lit on all
    emitters, from the simulator's physics (:func:`swarm_envs.ir.layer.pair_gains` with the occluders of
    :func:`swarm_envs.ir.occlusion.pair_occluders`, [T20 Eqs. (7)-(14)]). ``occlusion``: ``"ray"`` (per-ray
    line of sight, as simulated) or ``"centre"`` (a pair is cut when a third robot crosses the segment
    between the two centres)."""
    p = get_platform(PLATFORM)
    others = np.arange(1, pos.shape[0])
    others = others[np.hypot(*(pos[others] - pos[0]).T) <= max_range + 1e-12]
    if others.size == 0:
        return others, np.zeros((0, p.n_detectors, p.n_emitters))
    tx = np.zeros(others.size, dtype=np.intp)
    occluders = None
    if occlusion == "centre":
        others = others[line_of_sight(pos, p.radius, tx, others)]
        tx = tx[: others.size]
    elif occlusion == "ray":
        off, _, xy = pair_occluders(pos, head, others, tx, occluder_width(p))
        occluders = (off, xy)
    else:
        raise ValueError(f"occlusion must be 'ray' or 'centre', got {occlusion!r}")
    d = pos[0] - pos[others]
    c, s = np.cos(head[others]), np.sin(head[others])
    rel = np.stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]], axis=-1)
    return others, pair_gains(rel, wrap_angle(head[0] - head[others]), p, occluders=occluders)


def centre_amplitude(pos: np.ndarray, head: np.ndarray, max_range: float = DISC_R, occlusion: str = "ray") -> np.ndarray:
    """Noiseless received amplitude (ADC counts below ambient, m_max - min over detectors of m) at every
    robot when robot 0 transmits s1 with all emitters on; 0 for robots farther than ``max_range`` (m).

    The links of :func:`centre_links`, turned into counts by the measurement model without noise
    [T20 Eqs. (15)-(22)]; no detector response, no start detection.
    """
    p = get_platform(PLATFORM)
    amp = np.zeros(pos.shape[0])
    others, g = centre_links(pos, head, max_range, occlusion)
    if others.size == 0:
        return amp
    y = gain_to_intensity(g.sum(axis=-1), p)
    m = np.floor((M_MAX - M_MIN) * (1.0 - y) + M_MIN).min(axis=1)
    amp[others] = M_MAX - m
    return amp


def channels_of_centre(
    pos: np.ndarray, head: np.ndarray, relative_threshold: float = 5, max_range: float = DISC_R, occlusion: str = "ray"
) -> int:
    """n_C: robots that can tell s1 from s0 when robot 0 transmits [T20 Sec. 6.2.6]: centre distance within
    ``max_range`` and noiseless min-over-detectors ADC value below m_t = m_max - m_tr (i.e. received
    amplitude above m_tr; with one transmitter the dynamic threshold of Eq. (36) lies halfway between m_t
    and the signal, so "below m_t,dyn" is the same test)."""
    return int((centre_amplitude(pos, head, max_range, occlusion) > relative_threshold).sum())


#: frames the centre robot sends per scene in the detector count, and the share of them a robot must receive
#: intact to count as a channel (the same P_l <= 0.5 rule as the communication range of experiment (a))
CHANNEL_FRAMES = 10
CHANNEL_MIN_SHARE = 0.5


def detector_channels(
    scenes: list[tuple[np.ndarray, np.ndarray]],
    relative_threshold: float,
    rng: np.random.Generator,
    frames: int = CHANNEL_FRAMES,
    min_share: float = CHANNEL_MIN_SHARE,
    max_range: float = DISC_R,
    occlusion: str = "ray",
) -> dict[str, np.ndarray]:
    """n_C of each scene through the simulated receiver [T20 Sec. 6.2.6]: a robot is a channel when its
    detector distinguishes the centre's s_0 from s_1, i.e. receives at least ``min_share`` of the centre's
    ``frames`` frames intact.

    Each scene ``(positions (n, 2) m, headings (n,) rad)`` with the centre as robot 0 is one env copy of a
    bit-level :class:`swarm_envs.comm.network.Network` (310 bps, uncoded, m_tr = ``relative_threshold``).
    Only the centre transmits (a random 8-bit payload whenever its queue is empty; the last steps drain),
    over the links of :func:`swarm_envs.ir.layer.compute_links` with the centre transmit-only and the
    others receive-only (``emit_off`` / ``detect_off``; the links of :func:`centre_links`); every other robot receives with the full detector model: ADC
    noise, the detector response, the minimum over its 8 detectors, start detection below
    m_t = m_max - m_tr and the dynamic threshold of [T20 Eq. (36)]. "Intact" compares the decoded frame
    with the one sent (ground truth, used for counting only). Scenes may differ in size; smaller ones are
    padded with unlinked robots.

    Returns ``n_c`` (S,) channels per scene, ``sent`` (S,) frames the centre put on air and, per scene, the
    receivers' ``intact`` counts as a list of (n_s,) arrays (index 0, the centre, is 0).
    """
    S = len(scenes)
    size = max(q.shape[0] for q, _ in scenes)
    # Fig. 21's set-up: one sender among listeners. The centre's detectors are off (transmit-only), every
    # other robot's emitters are off (receive-only), as Task.transmit_off / receive_off make them in the env;
    # padding robots sit far outside their scene with both off. All pairs within max_range are kept
    # (drop_zero=False): a listener with no light still runs its detector on noise.
    pos = np.zeros((S * size, 2))
    head = np.zeros(S * size)
    pos[:] = 1000.0 + 10.0 * np.arange(S * size)[:, None] * np.array([1.0, 0.0])
    for b, (q, h) in enumerate(scenes):
        pos[b * size : b * size + q.shape[0]] = q
        head[b * size : b * size + q.shape[0]] = h
    centre = np.arange(S * size) % size == 0
    links = compute_links(pos, head, PLATFORM, max_range=max_range, drop_zero=False, occlusion=occlusion,
                          copy=np.arange(S * size) // size, emit_off=~centre, detect_off=centre)
    streams = CopyRandom(list(rng.spawn(S)))
    net = Network(PLATFORM, size, streams, bitrate=310, relative_threshold=relative_threshold, n_copies=S)
    centres = np.arange(S) * size
    steps_per_frame = int(np.ceil(net.frame_slots(8) / net.slots_per_step)) + 1
    drain = 2 * steps_per_frame + 2
    intact = np.zeros(S * size, dtype=np.int64)
    payload_rng = rng.spawn(1)[0]
    k = 0
    while True:
        sent = net.stats["tx_started_per_robot"][centres]
        if sent.min() >= frames and not net.sending[centres].any():
            break
        wanted = centres[(sent + net.q_count[centres] < frames) & (net.q_count[centres] == 0)]
        if wanted.size:
            net.send_many(wanted, payload_rng.integers(0, 2, (wanted.size, 8)).astype(bool))
        d = net.step(links)
        if len(d):
            ok = (d.origin == centres[d.receiver // size]) & ~d.corrupt & (d.kind == "app")
            np.add.at(intact, d.receiver[ok], 1)
        k += 1
        if k > frames * steps_per_frame * 20 + drain:
            raise RuntimeError("the centre robots did not get their frames on air")
    sent = net.stats["tx_started_per_robot"][centres].astype(float)
    per_scene = [intact[b * size : b * size + q.shape[0]] for b, (q, _) in enumerate(scenes)]
    n_c = np.array([(c[1:] >= min_share * sent[b]).sum() for b, c in enumerate(per_scene)])
    return {"n_c": n_c, "sent": sent, "intact": per_scene}


def arena_configuration(n: int, rng: np.random.Generator, side: float = ARENA) -> np.ndarray:
    """Robot 0 static at the arena centre, n-1 others uniform non-overlapping inside the walls."""
    p = get_platform(PLATFORM)
    r = p.radius
    c = np.array([[side / 2, side / 2]])
    return _rsa(n - 1, rng, lambda q: np.ones(len(q), bool), lambda m: rng.uniform(r, side - r, (m, 2)), 2 * r, c)


def arena_walk_snapshots(n: int, rng: np.random.Generator, replicas: int, snapshots: int, period_s: float = 30.0) -> list[tuple[np.ndarray, np.ndarray]]:
    """Snapshots like [T20 Fig. 21]: robot 0 static at the centre of the 72 x 72 cm arena, the others doing
    the random walk of [T20 Alg. 1]; ``replicas`` arenas side by side, one snapshot of each every
    ``period_s`` (the paper counts lit robots every 30 s), after a first ``period_s`` of walking."""
    p = get_platform(PLATFORM)
    scene = np.repeat(np.arange(replicas), n)
    origin = np.stack([SEP * np.arange(replicas), np.zeros(replicas)], -1)
    pos = np.vstack([arena_configuration(n, rng) for _ in range(replicas)]) + origin[scene]
    head = rng.uniform(-np.pi, np.pi, n * replicas)
    static = np.zeros(n * replicas, dtype=bool)
    static[::n] = True
    walk = RandomWalk(n * replicas, rng)
    out = []
    steps = int(round(period_s / walk.dt))
    for _ in range(snapshots):
        for _ in range(steps):
            walk.step(pos, head, scene, origin, ARENA, p.radius, static)
        for r in range(replicas):
            out.append((pos[r * n : (r + 1) * n] - origin[r], head[r * n : (r + 1) * n].copy()))
    return out


def _spread(nc: np.ndarray, paper: float | None = None) -> dict[str, float]:
    """Mean, max, min, std and the 10/25/50/75/90 % points of a sample of channel counts."""
    q = np.percentile(nc, [10, 25, 50, 75, 90])
    out = {"mean": float(nc.mean()), "max": float(nc.max()), "min": float(nc.min()), "std": float(nc.std()),
           "p10": q[0], "q25": q[1], "median": q[2], "q75": q[3], "p90": q[4], "samples": int(nc.size)}
    if paper is not None:
        out["P(=paper)"] = float(np.mean(nc == paper))
    return out


def _detector_counts(scenes: list, m_tr: float, rng: np.random.Generator, max_range: float, chunk: int = 100) -> dict[str, np.ndarray]:
    """:func:`detector_channels` over many scenes, ``chunk`` scenes per network: channels with at least half
    of the frames intact (``n_c``) and with at least one (``n_c_any``)."""
    n_c, n_any = [], []
    for k in range(0, len(scenes), chunk):
        r = detector_channels(scenes[k : k + chunk], m_tr, rng, max_range=max_range)
        n_c.append(r["n_c"])
        n_any.append(np.array([(c[1:] >= 1).sum() for c in r["intact"]]))
    return {"n_c": np.concatenate(n_c), "n_c_any": np.concatenate(n_any)}


def experiment_b(rng: np.random.Generator, quick: bool, fig21_mtrs: tuple[float, ...] = FIG21_MTRS) -> dict[str, Any]:
    """Channels per robot [T20 Sec. 6.2.6, Figs. 20a, 21]: the noiseless amplitude count for both occlusion
    rules and every m_tr of ``M_TR_SWEEP``, and the detector count (:func:`detector_channels`, per-ray
    occlusion) at each figure's m_tr (Fig. 20a: ``PAPER_MTR``; Fig. 21: ``fig21_mtrs``, default ``FIG21_MTR`` and
    ``PAPER_MTR``)."""
    det_rng = rng.spawn(1)[0]  # the detector's draws: the scenes are the same with or without them
    if quick:
        counts = [1, 5, 10, 20, 40, 80, 120, 160, 200, 240, 272]
        trials = 20
        arena_trials, replicas, snapshots = 100, 25, 4
    else:
        counts = [1, 2, 5, 10, 15, 20, 30, 40, 50, 60, 70, 80, 90, 100, 110, 120, 140, 160, 180, 200, 220, 240, 255, 265, 272]
        trials = 300
        arena_trials, replicas, snapshots = 1000, 100, 10
    area = np.pi * DISC_R**2
    curve = []
    for n in counts:
        ncs = {(rule, m_tr): np.empty(trials) for rule in OCC_RULES for m_tr in M_TR_SWEEP}
        placed = np.empty(trials)
        scenes = []
        for t in range(trials):
            pos = disc_configuration(n, rng)
            head = rng.uniform(-np.pi, np.pi, pos.shape[0])
            scenes.append((pos, head))
            placed[t] = pos.shape[0] - 1
            for rule in OCC_RULES:
                amp = centre_amplitude(pos, head, DISC_R, rule)
                for m_tr in M_TR_SWEEP:
                    ncs[rule, m_tr][t] = (amp > m_tr).sum()
        row: dict[str, Any] = {"n_others": n, "n_placed": placed.mean(), "density_per_m2": (placed.mean() + 1) / area}
        for rule in OCC_RULES:
            for m_tr in M_TR_SWEEP:
                row[f"{rule}_mtr{m_tr}"] = _spread(ncs[rule, m_tr])
        det = _detector_counts(scenes, PAPER_MTR, det_rng, DISC_R)
        row[f"detector_mtr{PAPER_MTR}"] = _spread(det["n_c"].astype(float))
        row[f"detector_any_mtr{PAPER_MTR}"] = _spread(det["n_c_any"].astype(float))
        curve.append(row)
    arena: dict[int, Any] = {}
    kmax = get_platform(PLATFORM).ir_range
    for n in (10, 20, 30):
        scenes = {
            "uniform": [(q, rng.uniform(-np.pi, np.pi, n)) for q in (arena_configuration(n, rng) for _ in range(arena_trials))],
            "walk": arena_walk_snapshots(n, rng, replicas, snapshots),
        }
        arena[n] = {"paper": PAPER_ARENA_NC[n], "density_per_m2": n / ARENA**2}
        for placement, sc in scenes.items():
            for rule in OCC_RULES:
                a = np.array([centre_amplitude(q, h, kmax, rule) for q, h in sc])
                for m_tr in M_TR_SWEEP:
                    arena[n][f"{placement}_{rule}_mtr{m_tr}"] = _spread((a > m_tr).sum(axis=1).astype(float), PAPER_ARENA_NC[n])
        for m_tr in fig21_mtrs:
            det = _detector_counts(scenes["walk"], m_tr, det_rng, kmax)
            arena[n][f"walk_detector_mtr{m_tr}"] = _spread(det["n_c"].astype(float), PAPER_ARENA_NC[n])
            arena[n][f"walk_detector_any_mtr{m_tr}"] = _spread(det["n_c_any"].astype(float), PAPER_ARENA_NC[n])
    key = f"ray_mtr{PAPER_MTR}"
    dkey = f"detector_mtr{PAPER_MTR}"
    return {
        "curve": curve,
        "trials_per_density": trials,
        "arena": arena,
        "arena_snapshots": {"uniform": arena_trials, "walk": replicas * snapshots},
        "rules": list(OCC_RULES),
        "m_tr_sweep": list(M_TR_SWEEP),
        "fig21_m_tr": list(fig21_mtrs),
        "channel_rule": {"frames": CHANNEL_FRAMES, "min_share": CHANNEL_MIN_SHARE},
        "peak_mean": max(c[key]["mean"] for c in curve),
        "overall_max": max(c[key]["max"] for c in curve),
        "densest_mean": curve[-1][key]["mean"],
        "densest_max": curve[-1][key]["max"],
        "detector_peak_mean": max(c[dkey]["mean"] for c in curve),
        "detector_overall_max": max(c[dkey]["max"] for c in curve),
        "detector_densest_mean": curve[-1][dkey]["mean"],
        "detector_densest_max": curve[-1][dkey]["max"],
    }


# ---------------------------------------------------------------------------------------------- (c)
class RandomWalk:
    """[T20 Alg. 1] for many robots, kinematic: rotate by a random angle in (-pi, pi] at the maximum
    angular speed, then drive at a random v in [-128, 128] mm/s for t_m; a move that would overlap another
    robot or leave the arena is not made (the robot stays put for that step)."""

    def __init__(self, n: int, rng: np.random.Generator, t_m: float = 2.0, dt: float = 0.1) -> None:
        p = get_platform(PLATFORM)
        self.rng, self.t_m, self.dt = rng, t_m, dt
        self.v_max, self.w_max = p.max_speed, p.max_angular_speed
        self.turn_left = np.zeros(n)
        self.move_left = np.zeros(n)
        self.v = np.zeros(n)
        self.n = n

    def _new(self, idx: np.ndarray) -> None:
        self.turn_left[idx] = self.rng.uniform(-np.pi, np.pi, idx.size)
        self.v[idx] = self.rng.uniform(-self.v_max, self.v_max, idx.size)
        self.move_left[idx] = self.t_m

    def step(self, pos: np.ndarray, head: np.ndarray, scene: np.ndarray, origin: np.ndarray, side: float, radius: float, static: np.ndarray) -> None:
        done = np.flatnonzero((np.abs(self.turn_left) < 1e-12) & (self.move_left <= 1e-12))
        if done.size:
            self._new(done)
        turning = np.abs(self.turn_left) > 1e-12
        dth = np.clip(self.turn_left, -self.w_max * self.dt, self.w_max * self.dt) * turning
        head += np.where(static, 0.0, dth)
        self.turn_left -= dth
        moving = ~turning & (self.move_left > 1e-12)
        self.move_left[moving] -= self.dt
        v = np.where(moving & ~static, self.v, 0.0)
        prop = pos + (v * self.dt)[:, None] * np.stack([np.cos(head), np.sin(head)], -1)
        loc = prop - origin[scene]
        ok = np.all((loc >= radius) & (loc <= side - radius), axis=1)
        n = pos.shape[0]
        pairs = cKDTree(np.vstack([pos, prop])).query_pairs(2 * radius - 1e-9, output_type="ndarray")
        pairs = pairs[pairs[:, 0] % n != pairs[:, 1] % n]
        for col in (0, 1):  # a proposed position touching any other robot (old or new place) is refused
            ok[pairs[pairs[:, col] >= n, col] - n] = False
        pos[ok] = prop[ok]


def experiment_c(rng: np.random.Generator, quick: bool) -> dict[str, Any]:
    messages = 60 if quick else 600
    replicas = 12 if quick else 30
    p = get_platform(PLATFORM)
    out = {}
    for label, mode, crc in (("broadcast", "broadcast", 0), ("flooding", "flooding", 8), ("flooding_no_crc", "flooding", 0)):
        out[label] = {}
        for n in range(2, 8):
            out[label][n] = _flood_run(n, mode, rng, messages, replicas, p, crc)
    return out


def _flood_run(n: int, mode: str, rng: np.random.Generator, messages: int, replicas: int, p, crc_bits: int = 0) -> dict[str, float]:
    N = n * replicas
    scene = np.repeat(np.arange(replicas), n)
    origin = np.stack([SEP * np.arange(replicas), np.zeros(replicas)], -1)
    pos = np.vstack([arena_configuration(n, rng) for _ in range(replicas)])
    pos = pos + origin[scene]
    head = rng.uniform(-np.pi, np.pi, N)
    walk = RandomWalk(N, rng)
    net = Network(PLATFORM, N, rng, relative_threshold=10, comm_mode=mode, crc_bits=crc_bits)
    period = 20  # steps: one message every 2 s per arena, declared lost after 2 s
    rounds = int(np.ceil(messages / replicas))
    pending: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    reached = []
    static = np.zeros(N, dtype=bool)
    for r in range(rounds):
        src = np.arange(replicas) * n + rng.integers(0, n, replicas)
        seq = net.send_many(src, rng.integers(0, 2, (replicas, 8)).astype(bool))
        got = np.zeros((replicas, n), dtype=bool)
        for k in range(period):
            walk.step(pos, head, scene, origin, ARENA, p.radius, static)
            links = compute_links(pos, head, PLATFORM)
            d = net.step(links)
            if len(d):
                sc = d.receiver // n
                hit = (d.origin == src[sc]) & (d.seq == seq[sc]) & (d.kind == "app")
                got[sc[hit], d.receiver[hit] % n] = True
        got[np.arange(replicas), src % n] = False
        reached.append(got.sum(axis=1) / (n - 1))
    reach = np.concatenate(reached)[:messages]
    st = net.stats
    return {
        "P_l": float(1.0 - reach.mean()),
        "reach": float(reach.mean()),
        "all_reached": float((reach == 1.0).mean()),
        "messages": int(reach.size),
        "bit_error_rate": net.summary()["bit_error_rate"],
        "frames_per_message": st["tx_started"] / max(1, int(reach.size)),
        "corrupt_delivered": st["rx_corrupt_delivered"] / max(1, st["rx_delivered"]),
    }


# ---------------------------------------------------------------------------------------------- (d)
def message_error_probability(p_e: np.ndarray, n: int, t: int) -> np.ndarray:
    """1 - P_f of [T20 Eq. (34)], summed as ``sum_{i>t} C(n,i) p^i (1-p)^(n-i)`` (no cancellation);
    equals ``1 - error_free_probability(p_e, n, t)``."""
    from math import comb

    p = np.asarray(p_e, dtype=float)
    return sum(comb(n, i) * p**i * (1.0 - p) ** (n - i) for i in range(t + 1, n + 1))


def experiment_d(rng: np.random.Generator, quick: bool) -> dict[str, Any]:
    step_cm = 4.0 if quick else 2.0
    steps = 200 if quick else 1500
    dist = np.arange(7.0, 75.0 + 1e-9, step_cm) / 100.0
    res = {}
    for code, steps_c in (((15, 15), steps), ((15, 11), steps), ((15, 1), 3 * steps)):
        r = run_pairs(dist, rng, steps_c, relative_threshold=5, code=code)
        res[code] = r
    pe = res[(15, 15)]["P_e"]
    out = {"distance_cm": (100 * dist).tolist(), "P_e_uncoded": pe.tolist()}
    for code, t in (((15, 15), 0), ((15, 11), 1), ((15, 1), 7)):
        pred = message_error_probability(np.nan_to_num(pe, nan=0.5), 15, t)
        out[f"{code[0]},{code[1]}"] = {
            "measured_block_error": res[code]["block_error"].tolist(),
            "blocks": res[code]["blocks"].tolist(),
            "predicted_1-P_f": np.asarray(pred).tolist(),
            "P_e_raw": res[code]["P_e"].tolist(),
        }
    return out


# ---------------------------------------------------------------------------------------------- (e)
def bitrate_ranges(
    rng: np.random.Generator, bitrates: tuple[float, ...], steps: int, step_cm: float, relative_threshold: float = 5,
    adc_model: ADCModel | None = None, max_cm: float = 80.0,
) -> dict[float, dict[str, Any]]:
    """Reliable range (P_e < 0.01) and communication range (P_l <= 0.5) of a static facing pair per bit rate."""
    dist = np.arange(7.0, max_cm + 1e-9, step_cm) / 100.0
    out = {}
    for br in bitrates:
        res = run_pairs(dist, rng, steps, relative_threshold=relative_threshold, bitrate=br, adc_model=adc_model)
        pe = np.array(res["P_e"])
        out[br] = {
            "reliable_cm_Pe<0.01": reliable_range_cm(res, 0.01),
            "range_cm_Pl<=0.5": comm_range_cm(res, 0.5),
            "max_Pe_within_range": float(np.nanmax(pe[res["P_l"] <= 0.5])) if (res["P_l"] <= 0.5).any() else float("nan"),
            "curve": {k: v.tolist() for k, v in res.items()},
        }
    return out


def fit_response_c(bias: float = RESPONSE_BIAS, target_cm: float = PAPER_BITRATE_RELIABLE[1800], steps: int = 300, seed: int = 11) -> dict[str, float]:
    """Fit the detector response's charge constant c (s) for a given bias b ([T20 Sec. 7], channel module
    docstring): bisection in log c, on a static facing pair at 1800 bps (7..30 cm, 1 cm steps, ``steps``
    control steps per distance, fixed seed), for the two edges of the plateau where the reliable range
    equals ``target_cm`` (14 cm [T20 Sec. 7]); returns both edges and their geometric mean (the fit)."""
    dist = np.arange(7.0, 30.0 + 1e-9, 1.0) / 100.0

    def rel(c: float) -> float:
        r = run_pairs(dist, np.random.default_rng(seed), steps, bitrate=1800, adc_model=ADCModel(response_c=c, response_bias=bias))
        v = reliable_range_cm(r, 0.01)
        return 0.0 if np.isnan(v) else v

    def edge(level: float) -> float:  # sup{c : reliable(c) >= level}, reliable range falls as c grows
        lo, hi = 1e-7, 1e-3
        for _ in range(12):
            mid = np.sqrt(lo * hi)
            lo, hi = (mid, hi) if rel(mid) >= level else (lo, mid)
        return float(np.sqrt(lo * hi))

    c_hi = edge(target_cm)  # largest c still reaching target_cm
    c_lo = edge(target_cm + 1)  # largest c still reaching target_cm + 1
    return {"bias": bias, "c_low": c_lo, "c_high": c_hi, "c_fit": float(np.sqrt(c_lo * c_hi))}


def experiment_e(rng: np.random.Generator, quick: bool) -> dict[str, Any]:
    steps = 60 if quick else 300
    step_cm = 2.0 if quick else 1.0
    ranges = bitrate_ranges(rng, BITRATE_SWEEP, steps, step_cm)
    # [T20 Sec. 6.2.5]: with the range restricted to 21 cm (m_tr = 75) the bit rate matters little for P_e
    restricted = bitrate_ranges(rng, (310, 1080, 1670), steps, step_cm, relative_threshold=75, max_cm=30.0)
    return {"ranges": ranges, "restricted_mtr75": restricted, "paper": PAPER_BITRATE_RELIABLE, "steps": steps, "step_cm": step_cm}


# ---------------------------------------------------------------------------------------------- output
def _save(fig, out_dir: str, name: str) -> str:
    """Lay out, write and close a matplotlib figure; returns its path."""
    import matplotlib.pyplot as plt

    fig.tight_layout()
    path = os.path.join(out_dir, name)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def _plots(results: dict[str, Any], out_dir: str) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    os.makedirs(out_dir, exist_ok=True)
    files = []
    if "a" in results:
        a = results["a"]
        fig, ax = plt.subplots(1, 2, figsize=(11, 4))
        for m_tr, c in a["curves"].items():
            ax[0].semilogy(c["distance_cm"], np.maximum(np.array(c["P_e"], float), 1e-5), label=f"m_tr={m_tr}")
            ax[1].plot(c["distance_cm"], c["P_l"], label=f"m_tr={m_tr}")
        ax[0].axhline(0.01, color="k", ls=":")
        ax[0].axvline(PAPER_RELIABLE_CM, color="k", ls="--", label="paper: reliable to 61 cm")
        ax[0].set(xlabel="distance (cm)", ylabel="P_e (floored at 1e-5)", title="bit error probability, 310 bps")
        for m_tr, r in PAPER_RANGE.items():
            ax[1].axvline(r, ls="--", lw=0.8, color="gray")
        ax[1].set(xlabel="distance (cm)", ylabel="P_l", title="message loss (paper ranges dashed)")
        ax[0].legend(fontsize=7)
        ax[1].legend(fontsize=7)
        files.append(_save(fig, out_dir, "swarmcom_a_range_pe.png"))
    if "b" in results:
        b = results["b"]
        fig, ax = plt.subplots(1, 2, figsize=(12, 4.5))
        x = [c["density_per_m2"] for c in b["curve"]]
        for key, label, col in ((f"detector_mtr{PAPER_MTR}", "detector", "k"), (f"ray_mtr{PAPER_MTR}", "noiseless, per ray", "C0"),
                                (f"centre_mtr{PAPER_MTR}", "noiseless, centre line", "C1")):
            ax[0].plot(x, [c[key]["mean"] for c in b["curve"]], "o-", color=col, label=f"{label}: mean")
            ax[0].plot(x, [c[key]["max"] for c in b["curve"]], "s--", color=col, lw=0.8, label=f"{label}: max")
        ax[0].axhline(PAPER_FIG20A["bound"], color="gray", ls=":", label="paper bound ~15")
        ax[0].axhline(PAPER_FIG20A["densest"], color="gray", ls="--", label="paper densest 6")
        ax[0].set(xlabel="robot density (1/m^2)", ylabel="n_C", title=f"[T20 Fig. 20a]: 61 cm disc, m_tr={PAPER_MTR}")
        ax[0].legend(fontsize=7)
        ns = np.array(sorted(b["arena"]))
        series = [(f"walk_detector_mtr{m}", f"detector m_tr={m:g}") for m in b["fig21_m_tr"]] + [(f"walk_ray_mtr{m}", f"noiseless m_tr={m}") for m in M_TR_SWEEP]
        colours = [str(g) for g in np.linspace(0.0, 0.6, len(b["fig21_m_tr"]))] + ["C0", "C1", "C2", "C3"]
        for k, ((key, label), col) in enumerate(zip(series, colours)):
            st = [b["arena"][n][key] for n in ns]
            xs = ns + 0.5 * (k - (len(series) - 1) / 2)
            ax[1].errorbar(xs, [q["median"] for q in st], yerr=[[q["median"] - q["p10"] for q in st], [q["p90"] - q["median"] for q in st]], fmt="o", color=col, label=label)
        ax[1].plot(ns, [b["arena"][n]["paper"] for n in ns], "r*", ms=11, label="paper (one snapshot each)")
        ax[1].set(xlabel="robots in 72 x 72 cm", ylabel="n_C (median, 10-90 %)", title="[T20 Fig. 21]: random-walk snapshots")
        ax[1].legend(fontsize=7)
        files.append(_save(fig, out_dir, "swarmcom_b_channels.png"))
    if "c" in results:
        c = results["c"]
        fig, ax = plt.subplots(figsize=(5.5, 4))
        for mode, mk in (("broadcast", "o-"), ("flooding", "s-"), ("flooding_no_crc", "x--")):
            ns = sorted(c[mode])
            ax.plot(ns, [c[mode][n]["P_l"] for n in ns], mk, label=mode.replace("_", " "))
        ax.set(xlabel="robots", ylabel="P_l", title="message loss, random walk, 310 bps, m_tr=10")
        ax.legend()
        files.append(_save(fig, out_dir, "swarmcom_c_flooding.png"))
    if "e" in results:
        e = results["e"]
        fig, ax = plt.subplots(figsize=(6, 4))
        for br, r in e["ranges"].items():
            c = r["curve"]
            ax.semilogy(c["distance_cm"], np.maximum(np.array(c["P_e"], float), 1e-5), label=f"{br} bps")
        ax.axhline(0.01, color="k", ls=":")
        for br, x in PAPER_BITRATE_RELIABLE.items():
            ax.axvline(x, color="gray", ls="--", lw=0.8)
        ax.set(xlabel="distance (cm)", ylabel="P_e (floored at 1e-5)",
               title="P_e vs distance and bit rate, m_tr=5\n(paper 61 / 14 cm dashed: fitted with two parameters; rates between predicted)")
        ax.legend(fontsize=7)
        files.append(_save(fig, out_dir, "swarmcom_e_bitrate.png"))
    if "d" in results:
        d = results["d"]
        fig, ax = plt.subplots(figsize=(6, 4))
        x = d["distance_cm"]
        for key, col in (("15,15", "C0"), ("15,11", "C1"), ("15,1", "C2")):
            ax.semilogy(x, np.maximum(np.array(d[key]["measured_block_error"], float), 1e-6), "o", color=col, label=f"[{key}] measured")
            ax.semilogy(x, np.maximum(np.array(d[key]["predicted_1-P_f"], float), 1e-6), "-", color=col, label=f"[{key}] Eq. (34)")
        ax.set(xlabel="distance (cm)", ylabel="1 - P_f (floored at 1e-6)", title="15-bit message error, 310 bps")
        ax.legend(fontsize=7)
        files.append(_save(fig, out_dir, "swarmcom_d_coding.png"))
    return files


def _print(results: dict[str, Any]) -> None:
    if "a" in results:
        a = results["a"]
        print("(a) communication range vs relative threshold m_tr, 310 bps, static facing pair")
        print(f"  {'m_tr':>5} | {'ours P_l<=0.5':>13} | {'ours P_l<=0.1':>13} | {'ours P_e<0.01':>13} | {'paper':>6}")
        for m_tr, r in a["ranges"].items():
            pr = r["paper_range_cm"]
            print(f"  {m_tr:>5} | {r['range_cm_Pl<=0.5']:>10.0f} cm | {r['range_cm_Pl<=0.1']:>10.0f} cm | {r['reliable_cm_Pe<0.01']:>10.0f} cm | {'' if np.isnan(pr) else f'{pr:.0f} cm':>6}")
        print(f"  reliable (P_e < 0.01) range, m_tr = 5: ours {a['reliable_cm']:.0f} cm, paper {a['paper_reliable_cm']:.0f} cm")
        c5 = a["curves"][5]
        dc = np.array(c5["distance_cm"])
        sel = sorted({int(np.argmin(np.abs(dc - x))) for x in (7, 20, 30, 40, 50, 55, 61, 65, 70, 80, 90, 100)})
        print("  P_e / P_l vs distance (m_tr = 5): " + ", ".join(f"{c5['distance_cm'][i]:.0f}cm {c5['P_e'][i]:.1e}/{c5['P_l'][i]:.2f}" for i in sel))
    if "b" in results:
        b = results["b"]
        k = f"mtr{PAPER_MTR}"
        print(f"(b) channels n_C of the centre robot, 61 cm disc, {b['trials_per_density']} trials per density, m_tr = {PAPER_MTR}")
        print(f"  detector: the receiver's simulated detector gets >= {CHANNEL_MIN_SHARE:.0%} of the centre's {CHANNEL_FRAMES} frames intact")
        print("  (ADC noise, detector response, min over detectors, start detection, dynamic threshold; per-ray line of")
        print("  sight); 'any' = at least one intact frame. noiseless: received amplitude above m_tr without noise or")
        print("  detector ('ray' per-ray line of sight as simulated, 'centre' a pair cut by any robot on the centre line)")
        print(f"  {'others':>6} | {'placed':>6} | {'rho/m^2':>7} | {'detector mean':>13} | {'max':>4} | {'any mean':>8} | {'ray mean':>8} | {'max':>4} | {'centre mean':>11} | {'max':>4}")
        for c in b["curve"]:
            d, da, r, ce = c["detector_" + k], c["detector_any_" + k], c["ray_" + k], c["centre_" + k]
            print(f"  {c['n_others']:>6} | {c['n_placed']:6.0f} | {c['density_per_m2']:7.1f} | {d['mean']:13.2f} | {d['max']:4.0f} | {da['mean']:8.2f} | "
                  f"{r['mean']:8.2f} | {r['max']:4.0f} | {ce['mean']:11.2f} | {ce['max']:4.0f}")
        for label, key in (("detector", "detector_" + k), ("detector, any frame", "detector_any_" + k), ("noiseless ray", "ray_" + k), ("noiseless centre", "centre_" + k)):
            print(f"  {label:>20}: peak of the mean curve {max(c[key]['mean'] for c in b['curve']):.1f}, max over all trials "
                  f"{max(c[key]['max'] for c in b['curve']):.0f}; densest: mean {b['curve'][-1][key]['mean']:.1f}, max {b['curve'][-1][key]['max']:.0f}")
        print(f"  paper [Fig. 20a]: bounded by ~{PAPER_FIG20A['bound']}, {PAPER_FIG20A['densest']} at the densest packing")
        print("  noiseless, other detection thresholds (per ray): peak mean / densest mean, by m_tr: " + ", ".join(
            f"{m}: {max(c[f'ray_mtr{m}']['mean'] for c in b['curve']):.1f} / {b['curve'][-1][f'ray_mtr{m}']['mean']:.1f}" for m in M_TR_SWEEP
        ))
        sn = b["arena_snapshots"]
        print(f"  72 x 72 cm arena [Fig. 21]: the paper's values are single snapshots; ours = distribution over {sn['walk']} random-walk")
        print(f"  snapshots [Alg. 1, one per 30 s; the detector count holds each snapshot still while the centre sends {CHANNEL_FRAMES} frames]")
        print(f"  and {sn['uniform']} uniform static placements (noiseless only): median [10%, 90%] (mean)")
        cols = [(f"walk detector m_tr={m:g}", f"walk_detector_mtr{m}") for m in b["fig21_m_tr"]]
        cols += [(f"walk any m_tr={m:g}", f"walk_detector_any_mtr{m}") for m in b["fig21_m_tr"]]
        cols += [(f"walk noiseless m_tr={m}", f"walk_ray_mtr{m}") for m in FIG21_MTRS]
        cols += [(f"uniform noiseless m_tr={PAPER_MTR}", f"uniform_ray_mtr{PAPER_MTR}")]
        print(f"  {'robots':>6} | {'paper':>5} | " + " | ".join(f"{name:>25}" for name, _ in cols))
        for n, r in b["arena"].items():
            cells = [f"{r[key]['median']:4.0f} [{r[key]['p10']:.0f}, {r[key]['p90']:.0f}] ({r[key]['mean']:.1f})" for _, key in cols]
            print(f"  {n:>6} | {r['paper']:>5} | " + " | ".join(f"{c:>25}" for c in cells))
        print("  noiseless threshold sweep, walk snapshots, per ray: median [10%, 90%] (mean) by m_tr (paper ranges 61/45/33/21 cm)")
        for n, r in b["arena"].items():
            print(f"  {n:>6} | {r['paper']:>5} | " + " | ".join(
                f"m_tr={m}: {r[f'walk_ray_mtr{m}']['median']:.0f} [{r[f'walk_ray_mtr{m}']['p10']:.0f}, {r[f'walk_ray_mtr{m}']['p90']:.0f}] ({r[f'walk_ray_mtr{m}']['mean']:.1f})" for m in M_TR_SWEEP
            ))
    if "c" in results:
        c = results["c"]
        print("(c) message loss P_l, 2..7 robots, random walk [Alg. 1], 72 x 72 cm, 310 bps, m_tr = 10")
        print(f"  {c['broadcast'][2]['messages']} messages per point; frames/msg = frames put on air per message; corrupt = delivered but wrong")
        print("  robots | broadcast P_l | flooding (CRC-8) P_l  frames/msg | flooding no CRC P_l  frames/msg  corrupt | flooding < broadcast?")
        for n in sorted(c["broadcast"]):
            b_, f_, g_ = c["broadcast"][n], c["flooding"][n], c["flooding_no_crc"][n]
            print(
                f"  {n:>6} | {b_['P_l']:13.3f} | {f_['P_l']:20.3f} {f_['frames_per_message']:10.1f} | "
                f"{g_['P_l']:19.3f} {g_['frames_per_message']:10.1f} {g_['corrupt_delivered']:8.2f} | {'yes' if f_['P_l'] < b_['P_l'] else 'no'}"
            )
        print("  paper [Fig. 16b]: flooding loses fewer messages than local broadcast as the group grows (values not in the text)")
    if "d" in results:
        d = results["d"]
        print("(d) 15-bit message error, 310 bps, m_tr = 5: measured vs Eq. (34) prediction from uncoded P_e")
        print(f"  {'d cm':>5} | {'P_e':>8} | {'[15,15] meas':>12} | {'[15,15] pred':>12} | {'[15,11] meas':>12} | {'[15,11] pred':>12} | {'[15,1] meas':>11} | {'[15,1] pred':>11}")
        for i, x in enumerate(d["distance_cm"]):
            print(
                f"  {x:5.0f} | {d['P_e_uncoded'][i]:8.1e} | {d['15,15']['measured_block_error'][i]:12.2e} | {d['15,15']['predicted_1-P_f'][i]:12.2e} | {d['15,11']['measured_block_error'][i]:12.2e} | "
                f"{d['15,11']['predicted_1-P_f'][i]:12.2e} | {d['15,1']['measured_block_error'][i]:11.2e} | {d['15,1']['predicted_1-P_f'][i]:11.2e}"
            )
        print("  paper: [15,1] predicted 1 - P_f <= 1e-16 up to ~50 cm (Sec. 5.4); coding lowers the error by orders of magnitude")
        blocks = d["15,1"]["blocks"]
        print(f"  ([15,1] blocks checked per distance: {int(min(blocks))}..{int(max(blocks))}; a measured 0 means < ~1/blocks)")
    if "e" in results:
        _print_e(results["e"])


def _print_e(e: dict[str, Any]) -> None:
    print(f"(e) reliable range vs bit rate, static facing pair, m_tr = 5, dynamic detector ({e['steps']} steps per distance, {e['step_cm']:.0f} cm grid)")
    print("  a two-parameter fit: the detector response's c is fitted to 14 cm at 1800 bps and its b to 61 cm at 310 bps")
    print("  (the smallest b keeping 61 cm), so 310 and 1800 bps agree by construction; the rates between are the model's predictions")
    print(f"  {'bps':>5} | {'ours P_e<0.01':>13} | {'paper P_e<0.01':>14} | {'ours P_l<=0.5':>13} | {'max P_e within P_l<=0.5':>23}")
    for br, r in e["ranges"].items():
        pp = e["paper"].get(br)
        paper = f"{pp:.0f} cm" if pp is not None else ("between" if 310 < br < 1800 else "")
        print(f"  {br:>5} | {r['reliable_cm_Pe<0.01']:>10.0f} cm | {paper:>14} | {r['range_cm_Pl<=0.5']:>10.0f} cm | {r['max_Pe_within_range']:>23.3f}")
    print("  [T20 Fig. 10] (fixed thresholds, 310/650/1160 bps) and Fig. 12b (minimum m_tr for P_e < 0.01 per bit rate) give")
    print("  no numbers in the text: only the trend (higher bit rate, shorter reliable range) is compared.")
    print("  range restricted to 21 cm (m_tr = 75) [T20 Sec. 6.2.5: bit rate matters little for P_e then]:")
    print("  " + ", ".join(f"{br} bps: range {r['range_cm_Pl<=0.5']:.0f} cm, max P_e {r['max_Pe_within_range']:.3f}" for br, r in e["restricted_mtr75"].items()))


def _cm(values: list[float]) -> str:
    return " / ".join("-" if v is None or np.isnan(v) else f"{v:.0f}" for v in values) + " cm"


def rows(results: dict[str, Any]) -> list[Row]:
    """The compared figures of the experiments in ``results``, one :class:`Row` each."""
    out: list[Row] = []
    pair = "2 static e-pucks facing each other, 310 bps, dynamic detector; receiver moved away 1 cm at a time, 100 messages per distance [Sec. 5.1]"
    if "a" in results:
        r = results["a"]["ranges"]
        out.append(Row("[T20 Fig. 12a, Sec. 6.2.4]", "communication range at m_tr = 75 / 25 / 10",
                       _cm([r[m]["range_cm_Pl<=0.5"] for m in (75, 25, 10)]) + " (P_l <= 0.5); "
                       + _cm([r[m]["reliable_cm_Pe<0.01"] for m in (75, 25, 10)]) + " (P_e < 0.01)", "21 / 33 / 45 cm",
                       pair + "; range = the farthest distance at which 100 messages were received",
                       "static facing pair, 1 cm grid; range = farthest distance up to which every distance has P_l <= 0.5 (or P_e < 0.01)"))
        out.append(Row("[T20 Sec. 7, Fig. 11]", "reliable range (P_e < 0.01), m_tr = 5", _cm([r[5]["reliable_cm_Pe<0.01"]]), "61 cm", pair,
                       "static facing pair, P_e on aligned frames"))
    if "b" in results:
        b = results["b"]
        k = f"mtr{PAPER_MTR}"
        disc = (f"simulation: centre + 1..272 static e-pucks at random in its 61 cm range, 10000 trials per density, m_tr = {PAPER_MTR} (61 cm); "
                "a channel: the receiver distinguishes s_0 from s_1 (signal below m_t,dyn) [Sec. 6.2.6]")
        det = f"{b['trials_per_density']} trials per density; detector: >= {CHANNEL_MIN_SHARE:.0%} of {CHANNEL_FRAMES} frames intact"
        curve = b["curve"]
        for label, key, how in (("detector", "detector_" + k, det),
                                ("noiseless count", "ray_" + k, f"{b['trials_per_density']} trials per density; noiseless amplitude > m_tr, no detector")):
            out.append(Row("[T20 Fig. 20a]", f"n_C, peak of the mean over trials ({label})", f"{max(c[key]['mean'] for c in curve):.1f}", "~15", disc, how))
            out.append(Row("[T20 Fig. 20a]", f"n_C at the densest packing, mean / max ({label})",
                           f"{curve[-1][key]['mean']:.1f} / {curve[-1][key]['max']:.0f}", "6", disc, how))
        arena = b["arena"]
        ns = sorted(arena)
        fig21 = ("real e-pucks: centre static sending s_1, 10 / 20 / 30 robots doing the random walk [Alg. 1] in 72 x 72 cm light their LEDs "
                 "on detecting it, counted every 30 s, 30 times per size; m_tr not stated (the mobile experiments of Sec. 6.2.2: 10)")
        snaps = b["arena_snapshots"]["walk"]
        for m in b["fig21_m_tr"]:
            for label, key, how in (("detector", f"walk_detector_mtr{m}", f"median [10 %, 90 %] of {snaps} random-walk snapshots, each held still; detector: >= {CHANNEL_MIN_SHARE:.0%} of {CHANNEL_FRAMES} frames intact"),
                                    ("noiseless count", f"walk_ray_mtr{m}", f"median [10 %, 90 %] of {snaps} random-walk snapshots; noiseless amplitude > m_tr")):
                if key not in arena[ns[0]]:
                    continue  # the noiseless sweep covers M_TR_SWEEP only
                cells = " / ".join(f"{arena[n][key]['median']:.0f} [{arena[n][key]['p10']:.0f}, {arena[n][key]['p90']:.0f}]" for n in ns)
                out.append(Row("[T20 Fig. 21]", f"n_C with 10 / 20 / 30 robots, m_tr = {m} ({label})", cells,
                               " / ".join(str(arena[n]["paper"]) for n in ns), fig21, how))
    if "c" in results:
        c = results["c"]
        ns = sorted(c["broadcast"])
        fewer = [n for n in ns if c["flooding"][n]["P_l"] < c["broadcast"][n]["P_l"]]
        out.append(Row("[T20 Fig. 16b]", "P_l broadcast / flooding with 2 .. 7 robots",
                       ", ".join(f"{c['broadcast'][n]['P_l']:.2f}/{c['flooding'][n]['P_l']:.2f}" for n in ns) + f" (flooding lower for n = {fewer})",
                       "flooding below broadcast as the group grows (values in the figure only)",
                       "2-7 e-pucks, random walk [Alg. 1, t_m = 2 s] in 72 x 72 cm, 310 bps, m_tr = 10, 1000 messages, lost after 2 s [Secs. 6.1, 6.2.2]",
                       f"{c['broadcast'][ns[0]]['messages']} messages per point; flooding with a CRC-8 (ours)"))
    if "d" in results:
        d = results["d"]
        x = np.array(d["distance_cm"])
        near = x <= 50
        worst = {code: np.nanmax(np.array(d[code]["measured_block_error"], float)[near]) for code in ("15,15", "15,11", "15,1")}
        out.append(Row("[T20 Fig. 13, Sec. 5.4]", "largest 15-bit block error within 50 cm, [15,15] / [15,11] / [15,1]",
                       " / ".join(f"{worst[k]:.1e}" for k in ("15,15", "15,11", "15,1")), "[15,1] predicted <= 1e-16 up to 50 cm (Eq. (34))",
                       "2 static facing e-pucks, 310 and 1800 bps, measured uncoded error and the Eq. (34) prediction for c = 1, 7",
                       "static facing pair, 310 bps, the codes run in the simulator (a measured 0 means below ~1 / blocks)"))
    if "e" in results:
        e = results["e"]["ranges"]
        fit = "a two-parameter fit: c fitted to 14 cm at 1800 bps, b to 61 cm at 310 bps; agreement at these two rates is by construction"
        out.append(Row("[T20 Sec. 7]", "reliable range (P_e < 0.01) at 310 / 1800 bps, m_tr = 5",
                       _cm([e[310]["reliable_cm_Pe<0.01"], e[1800]["reliable_cm_Pe<0.01"]]), "61 / 14 cm", pair.replace("310 bps", "310 and 1800 bps"), fit))
        mid = [br for br in e if 310 < br < 1800]
        out.append(Row("[T20 Figs. 10-12b]", f"reliable range at {' / '.join(str(br) for br in mid)} bps, m_tr = 5",
                       _cm([e[br]["reliable_cm_Pe<0.01"] for br in mid]), "- (figures only)", pair.replace("310 bps", "each bit rate"),
                       "the model's prediction between the two fitted rates"))
    return out


def _jsonable(x: Any) -> Any:
    if isinstance(x, dict):
        return {str(k): _jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_jsonable(v) for v in x]
    if isinstance(x, (np.floating, float)):
        return None if np.isnan(x) else float(x)
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, np.ndarray):
        return _jsonable(x.tolist())
    return x


def main(argv: list[str]) -> int:
    ap = OneLineArgumentParser(prog="python -m swarm_envs.validate swarmcom", description=__doc__.split("\n\n")[0])
    ap.add_argument("--experiment", default="all", choices=["a", "b", "c", "d", "e", "all"])
    ap.add_argument("--fit-response", action="store_true", help="refit the detector response's charge constant c (channel module docstring) and exit")
    ap.add_argument("--quick", action="store_true", help="fewer trials/distances (well under a minute)")
    ap.add_argument("--json", action="store_true", help="print results as JSON")
    ap.add_argument("--out", default="validation_output", help="directory for plots")
    ap.add_argument("--no-plots", action="store_true")
    ap.add_argument("--fig21-mtr", type=float, nargs="+", default=list(FIG21_MTRS), metavar="M_TR",
                    help=f"(b) detection thresholds of the detector count in the 72 cm arena (default {' '.join(str(m) for m in FIG21_MTRS)})")
    ap.add_argument("--seed", type=cli_type(Int(2020, low=0, high=2**63 - 1)), default=2020)
    args = ap.parse_args(argv)
    bad = [m for m in args.fig21_mtr if not 0 < m <= M_MAX - M_MIN]
    if bad:
        ap.error(f"--fig21-mtr values must be in (0, {M_MAX - M_MIN:g}] ADC counts, got {bad[0]}")
    if args.fit_response:
        fit = fit_response_c()
        print(json.dumps(fit) if args.json else f"detector response fit (b = {fit['bias']}): 14 cm at 1800 bps for c in [{fit['c_low']:.3e}, {fit['c_high']:.3e}] s; c = {fit['c_fit']:.3e} s")
        return 0
    which = ["a", "b", "c", "d", "e"] if args.experiment == "all" else [args.experiment]
    fns = {"a": experiment_a, "b": functools.partial(experiment_b, fig21_mtrs=tuple(int(m) if float(m).is_integer() else m for m in args.fig21_mtr)), "c": experiment_c, "d": experiment_d, "e": experiment_e}
    results: dict[str, Any] = {}
    timing = {}
    for w in which:
        t0 = time.perf_counter()
        # each experiment its own stream of the seed: --experiment x gives the same numbers as x in a full run
        results[w] = fns[w](np.random.default_rng([args.seed, "abcde".index(w)]), args.quick)
        timing[w] = time.perf_counter() - t0
    files = [] if args.no_plots else _plots(results, args.out)
    if args.json:
        print(json.dumps(_jsonable({"results": results, "rows": rows_json(rows(results)), "plots": files, "seconds": timing}), indent=1))
    else:
        _print(results)
        print_rows("SwarmCom [T20]", rows(results))
        if files:
            print("plots: " + ", ".join(files))
        print("seconds: " + ", ".join(f"{k}={v:.1f}" for k, v in timing.items()))
    return 0
