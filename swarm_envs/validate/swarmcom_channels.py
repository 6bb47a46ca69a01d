"""Channel count of the SwarmCom validation [T20 Sec. 6.2.6, Figs. 20a, 21]: how many robots can tell a
centre robot's s_0 from s_1, as a noiseless received amplitude above m_tr (per-ray or centre-line occlusion)
and through the simulated receiver (:func:`detector_channels`), over random placements in the 61 cm disc
and random-walk snapshots in the 72 x 72 cm arena, and with the robots moving in the env
(:func:`swarm_envs.validate.swarmcom_moving.moving_channels`) (experiment b)."""

from __future__ import annotations

from typing import Any

import numpy as np

from swarm_envs.comm.channel import M_MAX, M_MIN, gain_to_intensity
from swarm_envs.comm.network import Network
from swarm_envs.ir.layer import compute_links, pair_gains
from swarm_envs.ir.occlusion import line_of_sight, occluder_width, pair_occluders
from swarm_envs.sim.copies import CopyRandom
from swarm_envs.sim.geometry import wrap_angle
from swarm_envs.sim.platforms import get_platform
from swarm_envs.validate.swarmcom_moving import (
    COUNT_PERIOD_S,
    LIT_WINDOW_S,
    WINDOWS_S,
    moving_channels,
)
from swarm_envs.validate.swarmcom_setup import (
    ARENA,
    DISC_R,
    FIG21_MTRS,
    M_TR_SWEEP,
    OCC_RULES,
    PAPER_ARENA_NC,
    PAPER_MTR,
    PLATFORM,
    arena_configuration,
    arena_walk_snapshots,
    disc_configuration,
)


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
    ``PAPER_MTR``), and the moving count in the env at each of ``fig21_mtrs``
    (:func:`swarm_envs.validate.swarmcom_moving.moving_channels`: ``moving_trials`` trials, each an env copy
    started at random and counted once after 30 s of walking, as the paper's 30 trials per size)."""
    det_rng = rng.spawn(1)[0]  # the detector's draws: the scenes are the same with or without them
    moving_rng = rng.spawn(1)[0]  # the moving count's env seeds: the other draws are the same with or without it
    if quick:
        counts = [1, 5, 10, 20, 40, 80, 120, 160, 200, 240, 272]
        trials = 20
        arena_trials, replicas, snapshots = 100, 25, 4
        moving_trials = 4
    else:
        counts = [1, 2, 5, 10, 15, 20, 30, 40, 50, 60, 70, 80, 90, 100, 110, 120, 140, 160, 180, 200, 220, 240, 255, 265, 272]
        trials = 300
        arena_trials, replicas, snapshots = 1000, 100, 10
        moving_trials = 100
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
    env_seeds = [int(s) for s in moving_rng.integers(0, 2**31, moving_trials)]
    for n in (10, 20, 30):
        for m_tr in fig21_mtrs:
            mv = moving_channels(n, m_tr, env_seeds)
            for window, lit in mv["lit"].items():
                key = f"moving_mtr{m_tr}" if window == LIT_WINDOW_S else f"moving_mtr{m_tr}_window{window:g}s"
                arena[n][key] = _spread(lit.ravel().astype(float), PAPER_ARENA_NC[n])
            arena[n][f"moving_centre_drift_cm_mtr{m_tr}"] = _spread(100.0 * mv["centre_drift_m"])
    key = f"ray_mtr{PAPER_MTR}"
    dkey = f"detector_mtr{PAPER_MTR}"
    return {
        "curve": curve,
        "trials_per_density": trials,
        "arena": arena,
        "arena_snapshots": {"uniform": arena_trials, "walk": replicas * snapshots},
        "moving": {"trials": moving_trials, "seeds": env_seeds, "count_at_s": COUNT_PERIOD_S, "window_s": LIT_WINDOW_S, "windows_s": list(WINDOWS_S)},
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
