"""Validation of the SwarmCom simulation against [T20] (SPEC 4.3).

``python -m swarm_envs.validate swarmcom [--json] [--experiment a|b|c|d|e|all] [--out DIR] [--quick] [--fit-response]``

(a) two static e-pucks facing each other, 310 bps, dynamic detector: communication range vs relative
    threshold m_tr (75, 25, 10 -> 21, 33, 45 cm [T20 Sec. 6.2.4, Fig. 12a]) and bit error probability vs
    distance (reliable, P_e < 0.01, up to 61 cm with m_tr = 5 [T20 Sec. 7, Fig. 11]);
(b) channels per robot n_C vs density: a centre robot, range 61 cm, 1..272 others at random in that disc
    (n_C bounded by ~15, 6 at hexagonal packing [T20 Sec. 6.2.6, Fig. 20a]) and the 72 x 72 cm arena
    with 10, 20, 30 robots (n_C = 4, 6, 9 in single snapshots [Fig. 21]; ours: the distribution over
    random-walk snapshots); per-ray line of sight (SPEC 2) beside the first version's centre-line rule,
    and the detection threshold m_tr swept over the paper's 61/45/33/21 cm settings;
(c) local broadcast vs flooding: 2..7 robots doing the random walk of [T20 Alg. 1] (t_m = 2 s) in the
    72 x 72 cm arena, 310 bps, m_tr = 10; message loss P_l (a message is lost for a robot that has not
    received it 2 s after it was queued) [T20 Sec. 6.2.2, Fig. 16b]; flooding is run with the network's
    default CRC-8 and without it (then corrupted copies are re-flooded as new messages);
(d) channel coding: measured 15-bit block (message) error with [15,11] and [15,1] vs the prediction
    1 - P_f of Eq. (34) from the P_e measured without coding [T20 Sec. 5.4, Fig. 13];
(e) reliable range (P_e < 0.01) and communication range vs bit rate, static facing pair, m_tr = 5: 61 cm
    at 310 bps, 14 cm at 1800 bps [T20 Sec. 7], the rates between (Figs. 10-12b, values not in the text),
    and the 21 cm setting of [T20 Sec. 6.2.5] at 310/1080/1670 bps. ``--fit-response`` refits the detector
    response's charge constant c to 14 cm at 1800 bps (:mod:`swarm_envs.comm.channel` docstring).

Everything runs the bit-level :class:`swarm_envs.comm.network.Network` over the IR links of
:func:`swarm_envs.ir.layer.compute_links`; independent static pairs (a, d) and independent arenas (c) are
simulated side by side in one network, 3 m apart (beyond the 1 m IR range), so they cannot interact
(the id field is then wider than for one pair: 8 bits instead of 6, a few more header bits).
The default run takes ~3-4 minutes on 2 cores (plus ~1 minute for (e)), ``--quick`` ~15 s.
"""

from __future__ import annotations

import json
import os
import time
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

from swarm_envs.comm.bch import error_free_probability
from swarm_envs.comm.channel import M_MAX, M_MIN, RESPONSE_BIAS, ADCModel, gain_to_intensity
from swarm_envs.comm.network import Network
from swarm_envs.ir.layer import compute_links, line_of_sight, occluder_width, pair_gains, pair_occluders, wrap_angle
from swarm_envs.platforms import get_platform
from swarm_envs.settings import Int, OneLineArgumentParser, cli_type

PLATFORM = "epuck"
SEP = 3.0  # m between independent scenes (> ir_range)
PAPER_RANGE = {75: 21.0, 25: 33.0, 10: 45.0}  # cm [T20 Sec. 6.2.4, Fig. 12a]
PAPER_RELIABLE_CM = 61.0  # [T20 Sec. 7]
PAPER_ARENA_NC = {10: 4, 20: 6, 30: 9}  # [T20 Fig. 21]
ARENA = 0.72  # m [T20 Sec. 6.1]
DISC_R = 0.61  # m, communication range used for Fig. 20a
OCC_RULES = ("ray", "centre")  # per-ray line of sight (SPEC 2, simulated) and the first version's centre line
PAPER_MTR = 5  # Fig. 20a: the 61 cm range of m_tr = 5 [T20 Sec. 6.2.6, Table 12a]
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
    links = compute_links(pos, head, PLATFORM)
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


def centre_amplitude(pos: np.ndarray, head: np.ndarray, max_range: float = DISC_R, occlusion: str = "ray") -> np.ndarray:
    """Noiseless received amplitude (ADC counts below ambient, m_max - min over detectors of m) at every
    robot when robot 0 transmits s1 with all emitters on; 0 for robots farther than ``max_range`` (m).

    Same physics as the simulator (:func:`swarm_envs.ir.layer.pair_gains` with the occluders of
    :func:`swarm_envs.ir.layer.pair_occluders`, [T20 Eqs. (7)-(22)] without noise), computed only for
    the pairs (receiver k, transmitter 0). ``occlusion``: ``"ray"`` (SPEC 2, per-ray line of sight, as
    simulated) or ``"centre"`` (the first version's centre-segment rule).
    """
    p = get_platform(PLATFORM)
    amp = np.zeros(pos.shape[0])
    others = np.arange(1, pos.shape[0])
    others = others[np.hypot(*(pos[others] - pos[0]).T) <= max_range + 1e-12]
    if others.size == 0:
        return amp
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
    g = pair_gains(rel, wrap_angle(head[0] - head[others]), p, occluders=occluders)
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


def experiment_b(rng: np.random.Generator, quick: bool) -> dict[str, Any]:
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
        for t in range(trials):
            pos = disc_configuration(n, rng)
            head = rng.uniform(-np.pi, np.pi, pos.shape[0])
            placed[t] = pos.shape[0] - 1
            for rule in OCC_RULES:
                amp = centre_amplitude(pos, head, DISC_R, rule)
                for m_tr in M_TR_SWEEP:
                    ncs[rule, m_tr][t] = (amp > m_tr).sum()
        row: dict[str, Any] = {"n_others": n, "n_placed": placed.mean(), "density_per_m2": (placed.mean() + 1) / area}
        for rule in OCC_RULES:
            for m_tr in M_TR_SWEEP:
                nc = ncs[rule, m_tr]
                row[f"{rule}_mtr{m_tr}"] = {"mean": nc.mean(), "max": float(nc.max()), "min": float(nc.min()), "std": nc.std()}
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
                    nc = (a > m_tr).sum(axis=1)
                    q = np.percentile(nc, [10, 25, 50, 75, 90])
                    arena[n][f"{placement}_{rule}_mtr{m_tr}"] = {
                        "mean": nc.mean(), "p10": q[0], "q25": q[1], "median": q[2], "q75": q[3], "p90": q[4],
                        "P(=paper)": float(np.mean(nc == PAPER_ARENA_NC[n])), "snapshots": int(nc.size),
                    }
    key = f"ray_mtr{PAPER_MTR}"
    return {
        "curve": curve,
        "trials_per_density": trials,
        "arena": arena,
        "arena_snapshots": {"uniform": arena_trials, "walk": replicas * snapshots},
        "rules": list(OCC_RULES),
        "m_tr_sweep": list(M_TR_SWEEP),
        "peak_mean": max(c[key]["mean"] for c in curve),
        "overall_max": max(c[key]["max"] for c in curve),
        "densest_mean": curve[-1][key]["mean"],
        "densest_max": curve[-1][key]["max"],
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
    """Fit the detector response's charge constant c (s) for a given bias b (SPEC 4.2, channel module
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
        fig, ax = plt.subplots(1, 2, figsize=(11, 4))
        x = [c["density_per_m2"] for c in b["curve"]]
        for rule, col in (("ray", "C0"), ("centre", "C1")):
            key = f"{rule}_mtr{PAPER_MTR}"
            ax[0].plot(x, [c[key]["mean"] for c in b["curve"]], "o-", color=col, label=f"{rule}: mean")
            ax[0].plot(x, [c[key]["max"] for c in b["curve"]], "s--", color=col, label=f"{rule}: max")
        ax[0].axhline(PAPER_FIG20A["bound"], color="gray", ls=":", label="paper bound ~15")
        ax[0].axhline(PAPER_FIG20A["densest"], color="gray", ls="--", label="paper densest 6")
        ax[0].set(xlabel="robot density (1/m^2)", ylabel="n_C", title=f"channels of the centre robot (61 cm disc, m_tr={PAPER_MTR})")
        ax[0].legend(fontsize=7)
        ns = sorted(b["arena"])
        for k, (m_tr, col) in enumerate(zip(M_TR_SWEEP, ("C0", "C1", "C2", "C3"))):
            st = [b["arena"][n][f"walk_ray_mtr{m_tr}"] for n in ns]
            xs = np.array(ns) + 0.6 * (k - 1.5)
            ax[1].errorbar(xs, [q["median"] for q in st], yerr=[[q["median"] - q["p10"] for q in st], [q["p90"] - q["median"] for q in st]], fmt="o", color=col, label=f"m_tr={m_tr}: median, 10-90%")
        ax[1].plot(ns, [b["arena"][n]["paper"] for n in ns], "r*", ms=10, label="paper Fig. 21 (one snapshot each)")
        ax[1].set(xlabel="robots in 72x72 cm", ylabel="n_C", title="arena, random-walk snapshots, per-ray occlusion")
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
        ax.set(xlabel="distance (cm)", ylabel="P_e (floored at 1e-5)", title="P_e vs distance and bit rate, m_tr=5 (paper: 61 / 14 cm dashed)")
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
        print(f"(b) channels n_C of the centre robot, 61 cm disc, {b['trials_per_density']} trials per density, m_tr = {PAPER_MTR}")
        print("  a channel: noiseless received amplitude above m_tr (m < m_t); 'ray' = per-ray line of sight (SPEC 2, as")
        print("  simulated), 'centre' = the first version's centre-segment rule")
        print(f"  {'others':>6} | {'placed':>6} | {'rho/m^2':>7} | {'ray mean':>8} | {'ray max':>7} | {'centre mean':>11} | {'centre max':>10}")
        k = f"mtr{PAPER_MTR}"
        for c in b["curve"]:
            print(f"  {c['n_others']:>6} | {c['n_placed']:6.0f} | {c['density_per_m2']:7.1f} | {c['ray_' + k]['mean']:8.2f} | {c['ray_' + k]['max']:7.0f} | {c['centre_' + k]['mean']:11.2f} | {c['centre_' + k]['max']:10.0f}")
        print(f"  Fig. 20a, bound: paper ~{PAPER_FIG20A['bound']} (its curve; the text reads as a per-density average, see README)")
        for rule in OCC_RULES:
            key = f"{rule}_{k}"
            print(
                f"    {rule:>6}: peak of the mean curve {max(c[key]['mean'] for c in b['curve']):.1f}, max over all trials "
                f"{max(c[key]['max'] for c in b['curve']):.0f}; densest: mean {b['curve'][-1][key]['mean']:.1f}, max {b['curve'][-1][key]['max']:.0f} (paper 6)"
            )
        print("  other detection thresholds (per ray): peak mean / densest mean, by m_tr: " + ", ".join(
            f"{m}: {max(c[f'ray_mtr{m}']['mean'] for c in b['curve']):.1f} / {b['curve'][-1][f'ray_mtr{m}']['mean']:.1f}" for m in M_TR_SWEEP
        ))
        sn = b["arena_snapshots"]
        print(f"  72 x 72 cm arena [Fig. 21]: the paper's values are single snapshots; ours = distribution over {sn['walk']} random-walk")
        print(f"  snapshots [Alg. 1, one per 30 s] and {sn['uniform']} uniform static placements: median [10%, 90%] (mean)")
        print(f"  {'robots':>6} | {'paper':>5} | " + " | ".join(f"{f'{pl} {rule} m_tr={m}':>24}" for pl in ("walk", "uniform") for rule in OCC_RULES for m in (PAPER_MTR,)))
        for n, r in b["arena"].items():
            cells = []
            for pl in ("walk", "uniform"):
                for rule in OCC_RULES:
                    q = r[f"{pl}_{rule}_mtr{PAPER_MTR}"]
                    cells.append(f"{q['median']:4.0f} [{q['p10']:.0f}, {q['p90']:.0f}] ({q['mean']:.1f})")
            print(f"  {n:>6} | {r['paper']:>5} | " + " | ".join(f"{c:>24}" for c in cells))
        print("  detection threshold sweep, walk snapshots, per ray: median [10%, 90%] (mean) by m_tr (paper ranges 61/45/33/21 cm)")
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
    print("  fitted: the response's c to 14 cm at 1800 bps (b: smallest value keeping 61 cm at 310 bps); other rates: predictions")
    print(f"  {'bps':>5} | {'ours P_e<0.01':>13} | {'paper P_e<0.01':>14} | {'ours P_l<=0.5':>13} | {'max P_e within P_l<=0.5':>23}")
    for br, r in e["ranges"].items():
        pp = e["paper"].get(br)
        paper = f"{pp:.0f} cm" if pp is not None else ("between" if 310 < br < 1800 else "")
        print(f"  {br:>5} | {r['reliable_cm_Pe<0.01']:>10.0f} cm | {paper:>14} | {r['range_cm_Pl<=0.5']:>10.0f} cm | {r['max_Pe_within_range']:>23.3f}")
    print("  [T20 Fig. 10] (fixed thresholds, 310/650/1160 bps) and Fig. 12b (minimum m_tr for P_e < 0.01 per bit rate) give")
    print("  no numbers in the text: only the trend (higher bit rate, shorter reliable range) is compared.")
    print("  range restricted to 21 cm (m_tr = 75) [T20 Sec. 6.2.5: bit rate matters little for P_e then]:")
    print("  " + ", ".join(f"{br} bps: range {r['range_cm_Pl<=0.5']:.0f} cm, max P_e {r['max_Pe_within_range']:.3f}" for br, r in e["restricted_mtr75"].items()))


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
    ap.add_argument("--seed", type=cli_type(Int(2020, low=0, high=2**63 - 1)), default=2020)
    args = ap.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    if args.fit_response:
        fit = fit_response_c()
        print(json.dumps(fit) if args.json else f"detector response fit (b = {fit['bias']}): 14 cm at 1800 bps for c in [{fit['c_low']:.3e}, {fit['c_high']:.3e}] s; c = {fit['c_fit']:.3e} s")
        return 0
    which = ["a", "b", "c", "d", "e"] if args.experiment == "all" else [args.experiment]
    fns = {"a": experiment_a, "b": experiment_b, "c": experiment_c, "d": experiment_d, "e": experiment_e}
    results: dict[str, Any] = {}
    timing = {}
    for w in which:
        t0 = time.perf_counter()
        results[w] = fns[w](np.random.default_rng(rng.integers(2**63)), args.quick)
        timing[w] = time.perf_counter() - t0
    files = _plots(results, args.out)
    if args.json:
        print(json.dumps(_jsonable({"results": results, "plots": files, "seconds": timing}), indent=1))
    else:
        _print(results)
        print("plots: " + ", ".join(files))
        print("seconds: " + ", ".join(f"{k}={v:.1f}" for k, v in timing.items()))
    return 0
