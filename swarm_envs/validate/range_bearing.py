"""Range & bearing error sweep like [F14]'s gantry (Sec. V, Figs. 5-7), printed beside the paper's claims.

``python -m swarm_envs.validate range-bearing [--json] [--noise S] [--platform P] [--out DIR]``

Two robots (RX at the origin facing +x, TX at centre distance R, bearing b, relative heading h):
R from one radius of gap (6.6 cm) to 4.5 diameters (~20 cm) on the Droplet (scaled by the diameter on
other platforms), every bearing and heading on a grid, noisy measurement with power selection
(:func:`swarm_envs.sensing.range_bearing_model.measure`) then the [F14] estimator. Errors are estimate - truth
(range in cm, angles wrapped, in degrees). The paper gives its results as plots; the claims compared
are those of its text:

- range error bounded within one robot diameter (|mean| + std < diameter) and roughly constant with
  distance up to 4.5 diameters [F14 Sec. V, Fig. 5];
- bearing error a few degrees [Fig. 6];
- heading error larger than the bearing error, periodic with the 60-degree channel spacing [Fig. 7];
- usable down to one robot radius of gap.

The sweep compares each estimate with the brightness model the estimator itself inverts, plus ADC noise: it
checks the estimator and the noise model, not how well the model matches real Droplets, which differ from
each other and from their calibration [F14 Sec. VI]. So the same sweep is also run in the env
(:func:`env_sweep`: static pairs placed with reset options, the env's own firing schedule, noise and
collisions), with the env's default settings (each robot's channels drawn at reset,
docs/design.md#hardware-variation), with ``hw_variation=False`` (the nominal channels the estimator
inverts), and, with ``--variation KEY=VALUE``, with further env settings such as other spreads; a setting
this version of the package does not have skips that run with a message.

Then the collision rows (:func:`collisions`): fractions of clean, corrupted, misattributed and
lost readings (i) for two transmitters hidden from each other firing in the same step at a receiver that
sees both, and (ii) in a dense random swarm under the default timer schedule and under the contention
oracle, each beside the model without collisions (every firing measured alone and attributed to the true
transmitter).
"""

from __future__ import annotations

import json
import os
import time
from typing import Any

import numpy as np

from swarm_envs.sim.copies import CopyRandom
from swarm_envs.sim.geometry import wrap_angle
from swarm_envs.ir.layer import compute_links, pair_gains
from swarm_envs.ir.links import IRLinks
from swarm_envs.sim.platforms import get_platform
from swarm_envs.sensing.range_bearing import RangeBearingSensor
from swarm_envs.sensing.range_bearing_model import brightness, read
from swarm_envs.validate.report import Row, print_rows, rows_json
from swarm_envs.tasks.settings import Int, Real
from swarm_envs.tasks.settings_cli import OneLineArgumentParser, cli_type

DROPLET_DIAMETER_CM = 4.4


def _sweep(platform, R_cm, bearings, headings, sigma, repeats, rng, near_model=False):
    """Errors for every (distance, bearing, heading, repeat) on the grid. Returns dict of arrays."""
    B, H = np.meshgrid(bearings, headings, indexing="ij")
    B, H = B.ravel(), H.ravel()
    out = {k: [] for k in ("R", "b", "h", "er", "eb", "eh", "p")}
    for R in R_cm:
        rel = (R / 100.0) * np.stack([np.cos(B), np.sin(B)], -1)
        lam = brightness(rel, H, platform)
        lam = np.repeat(lam, repeats, axis=0)
        b = np.repeat(B, repeats)
        h = np.repeat(H, repeats)
        Re, be, he, p = read(lam, np.repeat(rel, repeats, axis=0), h, rng, sigma, platform, near_model=near_model)
        out["R"].append(np.full(b.size, R))
        out["b"].append(b)
        out["h"].append(h)
        out["er"].append(Re * 100.0 - R)
        out["eb"].append(np.degrees(wrap_angle(be - b)))
        out["eh"].append(np.degrees(wrap_angle(he - h)))
        out["p"].append(p)
    return {k: np.concatenate(v) for k, v in out.items()}


def _binned(x, y, edges):
    idx = np.clip(np.digitize(x, edges) - 1, 0, len(edges) - 2)
    rows = []
    for k in range(len(edges) - 1):
        v = y[idx == k]
        v = v[np.isfinite(v)]
        rows.append((float(v.mean()) if v.size else np.nan, float(v.std()) if v.size else np.nan,
                     float(np.abs(v).mean()) if v.size else np.nan, int(v.size)))
    return rows


def _harmonic(values, period_k=6):
    """Fourier analysis of a curve sampled uniformly over 360 degrees: the dominant non-constant harmonic
    k (k = 6: 60-degree period) and the share of the non-constant power in harmonics that are multiples
    of ``period_k`` (1.0 = the curve repeats exactly every 360/period_k degrees)."""
    v = np.asarray(values, dtype=float)
    v = v - np.nanmean(v)
    v = np.nan_to_num(v)
    spec = np.abs(np.fft.rfft(v)) ** 2
    spec[0] = 0.0
    k = int(np.argmax(spec))
    total = spec.sum()
    share = float(spec[period_k::period_k].sum() / total) if total > 0 else 0.0
    return k, share


def run(platform_name="droplet", sigma=None, repeats=2, seed=0, bearing_step=3.0, heading_step=5.0, near_model=False):
    platform = get_platform(platform_name)
    model = platform.ir_model
    sigma = float(model.default_noise_sigma if sigma is None else sigma)
    scale = platform.diameter * 100.0 / DROPLET_DIAMETER_CM
    R_cm = np.round(np.linspace(6.6, 20.0, 14) * scale, 2)
    bearings = np.radians(np.arange(0.0, 360.0, bearing_step))
    headings = np.radians(np.arange(0.0, 360.0, heading_step))
    rng = np.random.default_rng(seed)
    t0 = time.perf_counter()
    d = _sweep(platform, R_cm, bearings, headings, sigma, repeats, rng, near_model)
    diam = platform.diameter * 100.0

    # per distance
    per_dist = []
    for R in R_cm:
        m = d["R"] == R
        er = d["er"][m]
        ok = np.isfinite(er)
        e = er[ok]
        eb, eh = d["eb"][m][ok], d["eh"][m][ok]
        per_dist.append({
            "R_cm": float(R), "n": int(m.sum()), "no_reading": float(1 - ok.mean()),
            "power_median": float(np.median(d["p"][m])),  # NaN where the low-power near model was used
            "low_power_share": float(np.mean(np.isnan(d["p"][m]))),
            "range_mean": float(e.mean()), "range_std": float(e.std()),
            "range_bound": float(abs(e.mean()) + e.std()),
            "bearing_mean": float(eb.mean()), "bearing_std": float(eb.std()),
            "heading_mean": float(eh.mean()), "heading_std": float(eh.std()),
        })
    ok = np.isfinite(d["er"])
    b_edges = np.radians(np.arange(0.0, 360.0 + 1e-9, 15.0))
    by_bearing = _binned(d["b"][ok], d["eb"][ok], b_edges)
    by_heading = _binned(d["h"][ok], d["eh"][ok], b_edges)
    # Fig. 7-like gantry curve: TX rotating on the spot at bearing 0, every distance
    fine = headings
    m0 = ok & (np.abs(wrap_angle(d["b"])) < 1e-9)
    h_edges = np.append(headings - np.radians(heading_step) / 2, 2 * np.pi - np.radians(heading_step) / 2)
    by_heading_b0 = _binned(d["h"][m0], d["eh"][m0], h_edges)
    k_h, share_h = _harmonic([r[0] for r in by_heading_b0])
    k_habs, share_habs = _harmonic([r[2] for r in _binned(d["h"][ok], d["eh"][ok], np.append(headings, 2 * np.pi))])
    k_b, share_b = _harmonic([r[0] for r in _binned(d["b"][ok], d["eb"][ok], np.append(bearings, 2 * np.pi))])

    eb_all, eh_all = d["eb"][ok], d["eh"][ok]
    worst_bound = max(r["range_bound"] for r in per_dist)
    means = [r["range_mean"] for r in per_dist]
    claims = [
        ("range |mean|+std < 1 diameter at every distance [Fig. 5]",
         f"< {diam:.1f} cm", f"worst {worst_bound:.2f} cm", worst_bound < diam),
        ("range error roughly constant with distance [Fig. 5]",
         "no trend", f"mean spans {min(means):+.2f}..{max(means):+.2f} cm", max(means) - min(means) < 0.5 * diam),
        ("bearing error a few degrees [Fig. 6] (ours: |mean|+std < 10)",
         "a few deg", f"mean {eb_all.mean():+.2f}, std {eb_all.std():.2f}, |err| {np.abs(eb_all).mean():.2f} deg",
         abs(eb_all.mean()) + eb_all.std() < 10.0),
        ("heading error larger than bearing error [Fig. 7]",
         "larger", f"std {eh_all.std():.2f} vs {eb_all.std():.2f} deg", eh_all.std() > eb_all.std()),
        ("heading error periodic with 60-deg channel spacing [Fig. 7]",
         "period 60 deg", f"{100 * share_h:.0f}% (TX turning at bearing 0) / {100 * share_habs:.0f}% (all, |err|) "
         "of the curve's power repeats every 60 deg", min(share_h, share_habs) > 0.8),
        ("usable down to one radius of gap (R = 1.5 diameters) [Sec. V]",
         "works", f"no-reading {100 * per_dist[0]['no_reading']:.1f}%, |mean|+std {per_dist[0]['range_bound']:.2f} cm",
         per_dist[0]["no_reading"] < 0.01 and per_dist[0]["range_bound"] < diam),
    ]
    return {
        "platform": platform.name, "sigma_counts": sigma, "repeats": repeats, "seed": seed,
        "n_measurements": int(d["er"].size), "seconds": time.perf_counter() - t0,
        "bearing_std": float(eb_all.std()), "heading_std": float(eh_all.std()),
        "per_distance": per_dist,
        "by_bearing_deg": [{"bin": float(np.degrees(b_edges[k])), "mean": r[0], "std": r[1], "abs": r[2], "n": r[3]}
                           for k, r in enumerate(by_bearing)],
        "by_heading_deg": [{"bin": float(np.degrees(b_edges[k])), "mean": r[0], "std": r[1], "abs": r[2], "n": r[3]}
                           for k, r in enumerate(by_heading)],
        "heading_at_bearing0": [{"heading": float(np.degrees(fine[k])), "mean": r[0], "std": r[1], "n": r[3]}
                                for k, r in enumerate(by_heading_b0)],
        "harmonics": {"heading_mean_at_bearing0": [k_h, share_h], "heading_abs_all": [k_habs, share_habs],
                      "bearing_mean": [k_b, share_b]},
        "claims": [{"claim": c, "paper": p, "ours": o, "ok": bool(v)} for c, p, o, v in claims],
    }


def _sensitivity(platform_name, sigmas, seed, near_model=False):
    rows = []
    for s in sigmas:
        r = run(platform_name, s, repeats=1, seed=seed, bearing_step=6.0, heading_step=10.0, near_model=near_model)
        rows.append({
            "sigma": s,
            "worst_range_bound": max(x["range_bound"] for x in r["per_distance"]),
            "bearing_std": float(np.mean([x["bearing_std"] for x in r["per_distance"]])),
            "heading_std": float(np.mean([x["heading_std"] for x in r["per_distance"]])),
            "no_reading": float(np.mean([x["no_reading"] for x in r["per_distance"]])),
        })
    return rows


def _classify(r, links, n_expected):
    """Fresh readings (age 0) against ground truth: (clean, corrupted, misattributed, lost) fractions of
    ``n_expected`` readings. Misattributed: attributed to a robot other than the one whose light gave the
    matrix's brightest entry (``true_tx``). Corrupted: attributed right, but range error > 25 % of the
    distance or bearing error > 15 deg w.r.t. that robot. Lost: expected readings that did not arrive."""
    fresh = r.age == 0
    idx = {(int(u), int(w)): k for k, (u, w) in enumerate(zip(links.rx, links.tx))}
    clean = corrupted = mis = 0
    for u, w, t, R, b in zip(r.rx[fresh], r.tx[fresh], r.true_tx[fresh], r.range[fresh], r.bearing[fresh]):
        p = idx.get((int(u), int(w)))
        if w != t or p is None:
            mis += 1
        elif abs(R - links.distance[p]) > 0.25 * links.distance[p] or abs(wrap_angle(b - links.bearing[p])) > np.radians(15):
            corrupted += 1
        else:
            clean += 1
    n = max(int(n_expected), 1)
    return np.array([clean, corrupted, mis, max(n_expected - clean - corrupted - mis, 0)]) / n


def _hidden_pairs(platform, trials, sigma, seed, collisions, id_check, swarm=10):
    """Two TXs hidden from each other (no link between them, by construction: an obstacle or distance)
    fire in the same step; the RX (robot 0 of a swarm of ``swarm``) sees both with line of sight. Each
    trial is its own env copy; TX ids are random robots 1..swarm-1, other robots far away."""
    rng = np.random.default_rng(seed)
    scale = platform.diameter * 100.0 / DROPLET_DIAMETER_CM
    d = rng.uniform(6.6, 20.0, (trials, 2)) * scale / 100.0
    b = rng.uniform(-np.pi, np.pi, (trials, 2))
    h = rng.uniform(-np.pi, np.pi, (trials, 2))
    ids = np.stack([rng.choice(np.arange(1, swarm), 2, replace=False) for _ in range(trials)])
    rel = d[..., None] * np.stack([np.cos(b), np.sin(b)], -1)  # (T, 2, 2) TX centres in the RX frame
    apart = np.hypot(*(rel[:, 0] - rel[:, 1]).T) > platform.diameter
    rel, h, ids = rel[apart], h[apart], ids[apart]
    T = len(ids)
    base = np.arange(T)[:, None] * swarm
    rx = np.repeat(np.arange(T) * swarm, 2)
    tx = (base + ids).reshape(-1)
    order = np.lexsort((tx, rx))
    rx, tx = rx[order], tx[order]
    relp, relh = rel.reshape(-1, 2)[order], h.reshape(-1)[order]
    links = IRLinks(rx, tx, np.hypot(*relp.T), relp, relh, pair_gains(relp, relh, platform), T * swarm)
    fired = np.zeros(T * swarm, bool)
    fired[tx] = True
    sensor = RangeBearingSensor(platform, swarm, CopyRandom([np.random.default_rng([seed, k]) for k in range(T)]),
                                noise_sigma=sigma, collisions=collisions, id_check=id_check)
    r = sensor.step(links, fired=fired)
    return _classify(r, links, 2 * T), T


def _dense_swarm(platform, n, side, scenes, steps, sigma, seed, collisions, id_check, schedule="timer"):
    """Steps of ``schedule`` in random static scenes of ``n`` robots in a ``side`` x ``side`` square
    (per-ray occlusion). Expected readings per step: links from firing robots to robots that do not fire
    (a firing robot measures nothing) whose noiseless brightest entry reaches the no-reading floor."""
    rng = np.random.default_rng(seed)
    floor = platform.ir_model.no_reading_floor
    totals = np.zeros(4)
    n_expected = 0
    overlap = []
    for k in range(scenes):
        pos = []
        while len(pos) < n:
            p = rng.uniform(0, side, 2)
            if all(np.hypot(*(p - q)) > 1.05 * platform.diameter for q in pos):
                pos.append(p)
        hd = rng.uniform(-np.pi, np.pi, n)
        links = compute_links(np.array(pos), hd, platform)
        lit = links.gains.reshape(len(links), -1).max(axis=1) >= floor
        sensor = RangeBearingSensor(platform, n, np.random.default_rng([seed, k]), noise_sigma=sigma,
                                    collisions=collisions, id_check=id_check, schedule=schedule)
        for _ in range(steps):
            r = sensor.step(links)
            expected = int((lit & sensor.last_fired[links.tx] & ~sensor.last_fired[links.rx]).sum())
            totals += _classify(r, links, expected) * max(expected, 1)
            n_expected += expected
            overlap.append(r.n_overlap[r.age == 0])
    ov = np.concatenate(overlap)
    return totals / max(n_expected, 1), n_expected / (scenes * steps * n), float(np.mean(ov > 1)) if ov.size else 0.0


def collisions(platform_name="droplet", sigma=None, seed=0, trials=2000, n=50, side=0.45, scenes=4, steps=20):
    """Collision rows: hidden pair and dense swarm, with collisions (CRC on / off) beside the baseline, the
    dense swarm under the timer schedule (default) and the contention oracle."""
    platform = get_platform(platform_name)
    sigma = float(platform.ir_model.default_noise_sigma if sigma is None else sigma)
    scale = platform.diameter / (DROPLET_DIAMETER_CM / 100.0)
    rows = []
    for label, col, chk, schedule in (("no collisions (each firing alone)", False, True, "timer"),
                                      ("collisions, CRC id check", True, True, "timer"),
                                      ("collisions, id unchecked", True, False, "timer"),
                                      ("collisions, CRC, contention oracle", True, True, "contention")):
        hp, T = _hidden_pairs(platform, trials, sigma, seed, col, chk)
        ds, per_robot, ov = _dense_swarm(platform, n, side * scale, scenes, steps, sigma, seed + 1, col, chk, schedule)
        rows.append({"model": label, "schedule": schedule, "hidden_pair": dict(zip(("clean", "corrupted", "misattributed", "lost"), hp.tolist())),
                     "dense": dict(zip(("clean", "corrupted", "misattributed", "lost"), ds.tolist())),
                     "dense_expected_per_robot_step": per_robot, "dense_fresh_overlapped": ov, "hidden_trials": T})
    return {"platform": platform.name, "sigma_counts": sigma, "dense_n": n, "dense_side_m": side * scale, "rows": rows}


# ------------------------------------------------------------------------------- through the env's stack
ENV_TASK = "swarm_envs/Aggregation-v0"
#: the in-env runs: result key and label
ENV_RUNS = (
    ("env", "in the env, its default settings (each robot's channels drawn at reset)"),
    ("env_nominal", "in the env, hw_variation=False (the nominal channels the estimator inverts)"),
    ("env_variation", "in the env, default settings + the --variation settings"),
)
PAIR_SPACING = 1.0  # m between the pairs of one env copy: beyond the Droplet's and e-puck's IR range


def unknown_settings(settings: dict[str, Any], task: str = ENV_TASK) -> list[str]:
    """The keys of ``settings`` that ``task`` does not have (sorted)."""
    from swarm_envs.registry import task_class
    from swarm_envs.tasks.settings import COMMON_SETTINGS

    known = {**COMMON_SETTINGS, **task_class(task).settings()}
    return sorted(k for k in settings if k not in known)


def env_sweep(platform_name: str = "droplet", settings: dict[str, Any] | None = None, seed: int = 0, steps: int = 24,
              pairs_per_distance: int = 144, pairs_per_copy: int = 16) -> dict[str, Any]:
    """The gantry sweep [F14 Sec. V] run in the env: pairs of static robots (RX at the pair's origin facing +x,
    TX at centre distance R, bearing b, relative heading h; ``pairs_per_distance`` pairs at each of the
    sweep's 14 distances, b and h uniform at random), ``pairs_per_copy`` pairs per env copy
    ``PAIR_SPACING`` apart (``swarm_envs/Aggregation-v0``, zero actions, full sensing), ``steps`` control
    steps; every fresh reading of RX about TX (range & bearing's own firing schedule, noise and collision
    model, and whatever the env's ``settings`` add, e.g. per-robot hardware variation drawn at reset) is
    compared with the truth. Copy k is seeded ``seed + k``. Returns per-distance errors and totals."""
    from swarm_envs.validate.envs import scene_core

    platform = get_platform(platform_name)
    scale = platform.diameter * 100.0 / DROPLET_DIAMETER_CM
    R_cm = np.round(np.linspace(6.6, 20.0, 14) * scale, 2)
    rng = np.random.default_rng([seed, 24])
    angles = rng.uniform(-np.pi, np.pi, (len(R_cm) * pairs_per_distance, 2))
    grid = np.column_stack([np.repeat(R_cm / 100.0, pairs_per_distance), angles])
    side = int(np.ceil(np.sqrt(pairs_per_copy)))
    origins = PAIR_SPACING * np.stack(np.meshgrid(np.arange(side), np.arange(side), indexing="ij"), -1).reshape(-1, 2)[:pairs_per_copy]
    origins -= origins.mean(axis=0)
    n_copies = int(np.ceil(len(grid) / pairs_per_copy))
    grid = np.concatenate([grid, grid[: n_copies * pairs_per_copy - len(grid)]])  # fill the last copy
    rel = grid[:, :1] * np.stack([np.cos(grid[:, 1]), np.sin(grid[:, 1])], -1)
    positions, headings = [], []
    for c in range(n_copies):
        sl = slice(c * pairs_per_copy, (c + 1) * pairs_per_copy)
        positions.append(np.stack([origins, origins + rel[sl]], 1).reshape(-1, 2))
        headings.append(np.stack([np.zeros(pairs_per_copy), grid[sl, 2]], 1).reshape(-1))
    cfg = dict(n_robots=2 * pairs_per_copy, platform=platform_name, sensing="full",
               arena_size=PAIR_SPACING * side + 0.5, max_cycles=steps + 1)
    cfg.update(settings or {})
    t0 = time.perf_counter()
    core = scene_core(ENV_TASK, positions, headings, [seed + c for c in range(n_copies)], **cfg)
    still = np.zeros((core.n_total, core.layout.action_size))
    err_r, err_b, err_h, dist = [], [], [], []
    expected = 0
    for _ in range(steps):
        core.step(still)
        nb = core.frame.neighbours
        pair = nb.rx // 2
        fresh = (nb.age == 0) & (nb.rx % 2 == 0) & (nb.tx == nb.rx + 1)
        truth = grid[pair[fresh]]
        dist.append(truth[:, 0])
        err_r.append(100.0 * (nb.range[fresh] - truth[:, 0]))
        err_b.append(np.degrees(wrap_angle(nb.bearing[fresh] - truth[:, 1])))
        err_h.append(np.degrees(wrap_angle(nb.heading[fresh] - truth[:, 2])))
        expected += len(grid)
    d, er, eb, eh = (np.concatenate(x) for x in (dist, err_r, err_b, err_h))
    ok = np.isfinite(er)
    per_dist = []
    for R in R_cm:
        m = ok & np.isclose(d, R / 100.0)
        e = er[m]
        per_dist.append({"R_cm": float(R), "n": int(m.sum()), "range_mean": float(e.mean()) if e.size else float("nan"),
                         "range_std": float(e.std()) if e.size else float("nan"),
                         "range_bound": float(abs(e.mean()) + e.std()) if e.size else float("nan")})
    return {
        "platform": platform.name, "settings": {k: v for k, v in cfg.items() if k != "max_cycles"}, "copies": n_copies,
        "pairs": len(grid), "steps": steps, "readings": int(ok.sum()), "readings_per_pair_step": float(ok.sum() / max(expected, 1)),
        "per_distance": per_dist, "worst_range_bound": max((r["range_bound"] for r in per_dist if r["n"]), default=float("nan")),
        **{f"{name}_{stat}": float(getattr(e[ok], stat)()) if ok.any() else float("nan")
           for name, e in (("range", er), ("bearing", eb), ("heading", eh)) for stat in ("mean", "std")},
        "seconds": time.perf_counter() - t0,
    }


def parse_variation(items: list[str]) -> dict[str, Any]:
    """``["key=value", ...]`` -> settings; values read as Python literals (numbers, tuples, True/False,
    None), anything else as a string. ``ValueError`` naming the item without ``=``."""
    import ast

    out: dict[str, Any] = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            raise ValueError(f"--variation needs KEY=VALUE, got {item!r}")
        try:
            out[key.strip()] = ast.literal_eval(value.strip())
        except (ValueError, SyntaxError):
            out[key.strip()] = value.strip()
    return out


def rows(res: dict[str, Any]) -> list[Row]:
    """The compared figures of a ``range-bearing`` run, one :class:`Row` each."""
    diam = get_platform(res["platform"]).diameter * 100.0
    gantry = ("two Droplets on a calibrated gantry, 6.6-20 cm (one radius of gap to 4.5 diameters), swept over bearings and "
              "headings, >= 250 / ~150 / ~125 measurements per position for Figs. 5 / 6 / 7 [F14 Sec. V]")
    sweep = (f"model sweep, noise only: the brightness the estimator inverts plus ADC noise sigma = {res['sigma_counts']:.3g} counts "
             f"({res['n_measurements']} measurements); a check of the estimator and the noise, not of the model")
    out = [
        Row("[F14 Fig. 5]", "range error |mean| + std, worst distance", f"{max(r['range_bound'] for r in res['per_distance']):.2f} cm",
            f"< {diam:.1f} cm (within one diameter)", gantry, sweep),
        Row("[F14 Figs. 6, 7]", "bearing / heading error std", f"{res['bearing_std']:.1f} / {res['heading_std']:.1f} deg",
            "a few degrees / larger", gantry, sweep),
    ]
    shares = [100.0 * share for _, share in res["harmonics"].values()]
    out.append(Row("[F14 Fig. 7]", "heading error periodic with the 60-degree channel spacing",
                   f"{min(shares):.0f}-{max(shares):.0f} % of the error curve's power repeats every 60 deg", "periodic", gantry,
                   "model sweep: share of the non-constant power in harmonics that are multiples of 6 (heading error at "
                   "bearing 0, |heading error| over all, bearing error)"))
    for key, label in ENV_RUNS:
        e = res.get(key)
        if e is None:
            continue
        if "skipped" in e:
            out.append(Row("[F14 Figs. 5-7]", "range / bearing / heading error", f"not measured: {e['skipped']}", f"< {diam:.1f} cm / a few deg / larger",
                           gantry, label))
            continue
        how = (f"{label}: {e['pairs']} static pairs x {e['steps']} steps, {e['readings']} fresh readings; env settings "
               f"{ {k: v for k, v in e['settings'].items() if k not in ('n_robots', 'platform', 'sensing', 'arena_size')} }")
        out.append(Row("[F14 Fig. 5]", "range error |mean| + std, worst distance", f"{e['worst_range_bound']:.2f} cm",
                       f"< {diam:.1f} cm (within one diameter)", gantry, how))
        out.append(Row("[F14 Figs. 6, 7]", "bearing / heading error std", f"{e['bearing_std']:.1f} / {e['heading_std']:.1f} deg",
                       "a few degrees / larger", gantry, how))
        out.append(Row("[F14 Figs. 5-7]", "range error std", f"{e['range_std']:.2f} cm", "real Droplets differ (no numbers) [F14 Sec. VI]",
                       gantry, how))
    return out


def _plots(res, out_dir):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    os.makedirs(out_dir, exist_ok=True)
    name = res["platform"]
    paths = []
    pd = res["per_distance"]
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.errorbar([r["R_cm"] for r in pd], [r["range_mean"] for r in pd], yerr=[r["range_std"] for r in pd],
                fmt="o-", capsize=3, label="ours (mean +- std)")
    diam = get_platform(name).diameter * 100
    ax.axhline(diam, color="r", ls="--", lw=1, label="1 diameter (paper's bound)")
    ax.axhline(-diam, color="r", ls="--", lw=1)
    ax.set_xlabel("actual range R (cm)")
    ax.set_ylabel("range error (cm)")
    ax.set_title(f"{name}: range error vs range (cf. [F14] Fig. 5), sigma={res['sigma_counts']:.2g}")
    ax.legend()
    fig.tight_layout()
    paths.append(os.path.join(out_dir, f"range_bearing_{name}_range_error.png"))
    fig.savefig(paths[-1], dpi=100)
    plt.close(fig)
    for key, label, fig_no in (("by_bearing_deg", "bearing", 6), ("by_heading_deg", "heading", 7)):
        rows = res[key]
        fig, ax = plt.subplots(figsize=(6, 4))
        ax.errorbar([r["bin"] + 7.5 for r in rows], [r["mean"] for r in rows], yerr=[r["std"] for r in rows],
                    fmt="o-", capsize=3, label="all distances and orientations")
        if label == "heading":
            hb = res["heading_at_bearing0"]
            ax.plot([r["heading"] for r in hb], [r["mean"] for r in hb], "-", lw=1, label="TX turning at bearing 0")
        ax.axhline(0, color="k", lw=0.5)
        ax.set_xlabel(f"actual {label} (deg)")
        ax.set_ylabel(f"{label} error (deg)")
        ax.set_title(f"{name}: {label} error vs {label} (cf. [F14] Fig. {fig_no})")
        ax.legend(fontsize=8)
        fig.tight_layout()
        paths.append(os.path.join(out_dir, f"range_bearing_{name}_{label}_error.png"))
        fig.savefig(paths[-1], dpi=100)
        plt.close(fig)
    return paths


def main(argv: list[str]) -> int:
    ap = OneLineArgumentParser(prog="python -m swarm_envs.validate range-bearing", description=__doc__.split("\n")[0])
    ap.add_argument("--json", action="store_true", help="print the results as JSON")
    ap.add_argument("--noise", type=cli_type(Real(None, low=0.0, high=1000.0, unit="of ADC counts")), default=None,
                    help="ADC noise sigma in counts (default: the model's)")
    ap.add_argument("--platform", default="droplet", choices=["droplet", "epuck"])
    ap.add_argument("--out", default="validation_output", help="directory for the PNG plots")
    ap.add_argument("--repeats", type=cli_type(Int(2, low=1, high=10_000)), default=2, help="noisy measurements per grid point")
    ap.add_argument("--seed", type=cli_type(Int(0, low=0, high=2**63 - 1)), default=0)
    ap.add_argument("--no-plots", action="store_true")
    ap.add_argument("--near-model", action="store_true", help="Droplet: firmware low-power fit instead of the power ladder")
    ap.add_argument("--variation", action="append", default=[], metavar="KEY=VALUE",
                    help="env setting for the in-env run with per-robot hardware variation (repeat for several); "
                         "a setting this swarm_envs does not have skips that run with a message")
    ap.add_argument("--env-steps", type=cli_type(Int(24, low=1, high=1_000_000)), default=24,
                    help="control steps of the in-env runs (default 24: a robot fires about once per 11 steps)")
    ap.add_argument("--no-env", action="store_true", help="skip the in-env runs")
    args = ap.parse_args(argv)
    if args.near_model and args.platform != "droplet":
        ap.error("--near-model is the Droplet firmware's low-power fit; use --platform droplet")
    if args.env_steps < 1:
        ap.error(f"--env-steps must be >= 1, got {args.env_steps}")
    try:
        variation = parse_variation(args.variation)
    except ValueError as exc:
        ap.error(str(exc))

    res = run(args.platform, args.noise, args.repeats, args.seed, near_model=args.near_model)
    res["near_model"] = args.near_model
    res["sigma_sensitivity"] = _sensitivity(args.platform, [0.0, 1.0, 2.0, 4.0, 8.0], args.seed + 1, args.near_model)
    res["collisions"] = collisions(args.platform, args.noise, args.seed + 2)
    if not args.no_env:
        base = {"rb_noise": args.noise, "rb_near_model": args.near_model}
        res["env"] = env_sweep(args.platform, base, args.seed + 3, args.env_steps)
        res["env_nominal"] = env_sweep(args.platform, {**base, "hw_variation": False}, args.seed + 3, args.env_steps)
        unknown = unknown_settings(variation)
        if not variation:
            res["env_variation"] = {"skipped": "no --variation KEY=VALUE settings given"}
        elif unknown:
            res["env_variation"] = {"skipped": f"setting(s) {unknown} do not exist in this swarm_envs version"}
        else:
            try:
                res["env_variation"] = env_sweep(args.platform, {**base, **variation}, args.seed + 3, args.env_steps)
            except ValueError as exc:  # a bad value of a known setting (SettingsError names it)
                ap.error(f"--variation: {exc}")
    res["rows"] = rows_json(rows(res))
    if not args.no_plots:
        res["plots"] = _plots(res, args.out)
    if args.json:
        print(json.dumps(res, indent=1))
        return 0

    print(f"Range & bearing sweep [F14 Sec. V]: platform={res['platform']}, noise sigma={res['sigma_counts']:.3g} "
          f"counts, {res['n_measurements']} measurements ({res['seconds']:.1f} s)")
    print("\nclaims                                                        paper            ours")
    for c in res["claims"]:
        print(f"  [{'ok ' if c['ok'] else 'NO '}] {c['claim']:57s} {c['paper']:15s}  {c['ours']}")
    print("\nper distance (errors = estimate - truth; range in cm, angles in deg)")
    print("   R cm  no-read  p_med   range mean   std  |m|+std   bearing mean   std   heading mean   std")
    for r in res["per_distance"]:
        print(f"  {r['R_cm']:5.1f}  {100 * r['no_reading']:5.1f}%  {r['power_median']:6.4f}  {r['range_mean']:+9.2f} "
              f"{r['range_std']:6.2f}  {r['range_bound']:6.2f}   {r['bearing_mean']:+10.2f} {r['bearing_std']:6.2f}"
              f"   {r['heading_mean']:+10.2f} {r['heading_std']:6.2f}")
    print("\nper 15-deg bin      bearing error (by actual bearing)   heading error (by actual heading)")
    for rb, rh in zip(res["by_bearing_deg"], res["by_heading_deg"]):
        print(f"  {rb['bin']:5.0f}-{rb['bin'] + 15:3.0f}      {rb['mean']:+7.2f} +- {rb['std']:5.2f} (|e| {rb['abs']:5.2f})"
              f"          {rh['mean']:+7.2f} +- {rh['std']:5.2f} (|e| {rh['abs']:5.2f})")
    h = res["harmonics"]
    print(f"\nFourier: dominant harmonic k over 360 deg (share of power in multiples of 6, i.e. repeating every 60 deg):"
          f"\n  heading error at bearing 0: k={h['heading_mean_at_bearing0'][0]}"
          f" ({100 * h['heading_mean_at_bearing0'][1]:.0f}%), |heading error| all: k={h['heading_abs_all'][0]}"
          f" ({100 * h['heading_abs_all'][1]:.0f}%), bearing error: k={h['bearing_mean'][0]} ({100 * h['bearing_mean'][1]:.0f}%)")
    print("\nnoise sensitivity (sigma in counts)   worst |mean|+std (cm)   bearing std   heading std   no-reading")
    for r in res["sigma_sensitivity"]:
        print(f"  {r['sigma']:5.1f}                              {r['worst_range_bound']:7.2f}           "
              f"{r['bearing_std']:7.2f}      {r['heading_std']:7.2f}     {100 * r['no_reading']:5.1f}%")
    col = res["collisions"]
    print(f"\ncollisions: fractions of the readings a receiver would get if every firing were alone;"
          f"\n  hidden pair: 2 TXs hidden from each other fire in one step, RX sees both ({col['rows'][0]['hidden_trials']} trials);"
          f"\n  dense swarm: N={col['dense_n']} in a {100 * col['dense_side_m']:.0f} cm square, timer schedule (last row: contention oracle);"
          f"\n  corrupted = right id but |range err| > 25% of range or |bearing err| > 15 deg; lost = rejected or below floor"
          f"\n  (fractions of the readings expected from lit links: noise can add a reading of a link below the floor, so a"
          f"\n  row may sum past 100%; without collisions the dense swarm's corrupted readings come from per-ray partial occlusion)")
    print("  model                        scene         clean  corrupted  misattributed   lost   (dense: fresh readings overlapped)")
    for r in col["rows"]:
        for scene, key in (("hidden pair", "hidden_pair"), ("dense swarm", "dense")):
            f = r[key]
            extra = f"   ({100 * r['dense_fresh_overlapped']:.0f}%)" if key == "dense" else ""
            print(f"  {r['model']:36s} {scene:12s} {100 * f['clean']:5.1f}%    {100 * f['corrupted']:5.1f}%        "
                  f"{100 * f['misattributed']:5.2f}%   {100 * f['lost']:5.1f}%{extra}")
    for key, label in ENV_RUNS:
        e = res.get(key)
        if e is None:
            continue
        if "skipped" in e:
            print(f"\n{label}: skipped ({e['skipped']})")
            continue
        print(f"\n{label} (env settings {e['settings']}): {e['pairs']} static pairs, b and h uniform, {e['copies']} copies x "
              f"{e['steps']} steps, {e['readings']} fresh readings ({e['seconds']:.1f} s)")
        print(f"  range error mean {e['range_mean']:+.2f} cm, std {e['range_std']:.2f} cm, worst |mean|+std {e['worst_range_bound']:.2f} cm; "
              f"bearing error mean {e['bearing_mean']:+.2f}, std {e['bearing_std']:.2f} deg; heading error mean {e['heading_mean']:+.2f}, "
              f"std {e['heading_std']:.2f} deg")
    if "plots" in res:
        print("\nplots: " + ", ".join(res["plots"]))
    print("\nThe model sweep compares the estimate with the brightness model the estimator inverts, plus ADC noise: it")
    print("checks the estimator and the noise, not how well the model matches real Droplets (which differ from each")
    print("other and from the calibration). The in-env rows add the env's own firing schedule and collisions, with each")
    print("robot's channels drawn at reset (default) and without (hw_variation=False), and with --variation KEY=VALUE the env")
    print("settings given (e.g. other spreads of the hardware variation); each row lists the settings it ran with.")
    print_rows("Range & bearing [F14]", rows(res))
    return 0
