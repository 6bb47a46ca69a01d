"""Centroid seeking with scale-free coordinates [L Sec. 6.2.2, Figs. 6.3-6.4; SPEC 5.4].

Kinematic reproduction (no physics env): 4 static r-one robots at the corners of a random convex
quadrilateral (circumradius ``--polygon-radius`` range, every pair within the 1 m IR range) and one seeker
that starts outside the polygon. Each round, as in the thesis (the robot pauses, measures, then moves):

1. the shared IR layer gives the links of the current poses (binary r-one gains, line of sight:
   the seeker can occlude anchor-anchor links) (:func:`swarm_envs.ir.layer.compute_links`);
2. the firmware sector rule turns them into 22.5-degree bearings (:mod:`swarm_envs.sensing.bearing_sensor`),
   noiseless (nominal 68-degree arcs) or with the hardware noise model of the env's ``bearing_noise``
   (every reading's receiver arcs and transmitter cones drawn from the thesis' measured 63-74 degrees
   [L Sec. 3.2.1]; :func:`swarm_envs.sensing.bearing_sensor.draw_half_arcs`);
3. an ideal exchange round (:class:`swarm_envs.sensing.exchange.BearingExchange`, ``mode="ideal"``);
4. the seeker computes 2-hop scale-free coordinates with ANGLEBALANCE and the noise-sensitivity MST
   [L Alg. 4] (:func:`swarm_envs.sensing.scale_free.coordinates_all`) and the centroid of the anchors it
   has coordinates for (the direction to it is scale-free);
5. it turns to that direction and moves ``d_step = 11 cm``; a step that would overlap an anchor is
   projected back onto the contact circle (the seeker slides around it; our kinematic stand-in for the
   physics engine).

If no anchor length is computable in a round (never rigid), the seeker steps along the mean of the unit
bearing vectors of the anchors it sees (a bearing-only fallback, ours; counted in the output).

Metric (thesis Fig. 6.4(b)): mean seeker-centroid distance over the rounds in which the seeker is inside
the polygon ("errors outside the polygon are not included"); paper 14.03 cm, within 2 d_step = 22 cm.
Optional motion noise (``--heading-noise-deg``, ``--step-noise``; default off) perturbs each step's
direction and length, as a real robot's odometry would. Also reported: the mean over the second half of each run (the env's metric, SPEC 6), and the same runs
with exact bearings (no quantisation) as a reference. The thesis's bearing-error histogram [L Fig. 3.13(a)]
has no numbers in its text; the arc spread is the only measured hardware figure used (nothing is tuned
to the 14.03 cm).
"""

from __future__ import annotations

import json
import os
import sys

import numpy as np

from swarm_envs.ir.layer import compute_links
from swarm_envs.platforms import get_platform
from swarm_envs.sensing.bearing_sensor import BearingReadings, draw_half_arcs, sense_bearings
from swarm_envs.sensing.exchange import BearingExchange
from swarm_envs.sensing.scale_free import coordinates_all
from swarm_envs.settings import Int, OneLineArgumentParser, Real, cli_type

PAPER_MEAN_CM = 14.03
D_STEP = 0.11  # m [L Sec. 6.2.2]


def random_polygon(rng: np.random.Generator, r_lo: float, r_hi: float, min_sep: float) -> np.ndarray:
    """4 corners of a random convex quadrilateral around the origin (m), pairwise >= min_sep apart."""
    while True:
        ang = np.sort(rng.uniform(0, 2 * np.pi, 4))
        gaps = np.diff(np.r_[ang, ang[0] + 2 * np.pi])
        if gaps.max() > 0.8 * np.pi or gaps.min() < 0.25 * np.pi:
            continue
        rad = rng.uniform(r_lo, r_hi, 4)
        p = np.stack([rad * np.cos(ang), rad * np.sin(ang)], -1)
        d = np.hypot(*(p[:, None] - p[None]).transpose(2, 0, 1))
        if d[np.triu_indices(4, 1)].min() < min_sep or d.max() > 0.95:
            continue
        e = np.roll(p, -1, 0) - p
        cross = e[:, 0] * np.roll(e, -1, 0)[:, 1] - e[:, 1] * np.roll(e, -1, 0)[:, 0]
        if (cross > 0).all():
            return p


def inside(poly: np.ndarray, x: np.ndarray) -> bool:
    e = np.roll(poly, -1, 0) - poly
    w = x[None] - poly
    return bool((e[:, 0] * w[:, 1] - e[:, 1] * w[:, 0] > 0).all())


def run_trial(
    rng: np.random.Generator, rounds: int, exact: bool, poly: np.ndarray, start: np.ndarray, h0: float,
    heading_noise: float = 0.0, step_noise: float = 0.0, noise_rng: np.random.Generator | None = None,
) -> dict:
    """One seeker run; ``noise_rng`` (not None) switches on the hardware bearing noise (module doc)."""
    plat = get_platform("rone")
    pos = np.vstack([poly, start])
    hd = np.r_[rng.uniform(-np.pi, np.pi, 4), h0]
    cen = poly.mean(0)
    ex = BearingExchange(5, "ideal", k_max=5)
    dists, ins, fallback, rigid = [], [], 0, 0
    for _ in range(rounds):
        links = compute_links(pos, hd, plat, drop_zero=noise_rng is None)  # wider arcs may light a dark pair
        if exact:
            P = len(links)
            z = np.zeros(P)
            rd = BearingReadings(links.rx, links.tx, links.bearing, z, z, z.astype(np.uint16), z.astype(np.uint16), np.ones(P, bool))
        elif noise_rng is not None:
            rd = sense_bearings(links, plat, half_arcs=draw_half_arcs(noise_rng, len(links.rx), plat))
        else:
            rd = sense_bearings(links, plat)
        res = coordinates_all(ex.step(rd))
        u = 4
        sel = res.valid[u] & (res.ids[u] >= 0) & (res.ids[u] < 4)
        rigid += bool(res.rigid[u])
        if sel.any():
            c = res.xy[u, sel].mean(0)
            ang = np.arctan2(c[1], c[0])
        else:
            seen = (rd.rx == u) & rd.valid & (rd.tx < 4)
            if not seen.any():
                ang = np.arctan2(*(cen - pos[u])[::-1]) - hd[u]  # lost: cannot happen within range
            else:
                v = np.stack([np.cos(rd.bearing[seen]), np.sin(rd.bearing[seen])], -1).mean(0)
                ang = np.arctan2(v[1], v[0])
            fallback += 1
        hd[u] = hd[u] + ang + (rng.normal(0.0, heading_noise) if heading_noise > 0 else 0.0)
        length = D_STEP * (1.0 + (rng.normal(0.0, step_noise) if step_noise > 0 else 0.0))
        step = max(length, 0.0) * np.array([np.cos(hd[u]), np.sin(hd[u])])
        # contact with an anchor: project back onto the contact circle, so the seeker slides around the
        # anchor (kinematic stand-in for the physics engine's collision response)
        new = pos[u] + step
        for a in range(4):
            d = new - pos[a]
            dn = float(np.hypot(*d))
            if dn < 2 * plat.radius:
                new = pos[a] + d / max(dn, 1e-9) * 2 * plat.radius
        pos[u] = new
        dists.append(float(np.hypot(*(pos[u] - cen))))
        ins.append(inside(poly, pos[u]))
    return {"dist": np.array(dists), "inside": np.array(ins), "fallback": fallback, "rigid": rigid}


def experiment(
    seed: int, polygons: int, starts: int, rounds: int, exact: bool, r_range: tuple[float, float],
    heading_noise: float = 0.0, step_noise: float = 0.0, bearing_noise: bool = False,
) -> dict:
    rng = np.random.default_rng(seed)
    noise_rng = rng.spawn(1)[0] if bearing_noise else None  # same polygons and starts with and without noise
    inside_d, half_d, fb, rig, n_rounds = [], [], 0, 0, 0
    traj_example = None
    for _ in range(polygons):
        poly = random_polygon(rng, *r_range, min_sep=0.25)
        cen = poly.mean(0)
        poly = poly - cen
        for _ in range(starts):
            while True:
                a = rng.uniform(0, 2 * np.pi)
                s = rng.uniform(0.55, 0.8) * np.array([np.cos(a), np.sin(a)])
                if not inside(poly, s) and np.hypot(*(poly - s).T).min() > 0.15 and np.hypot(*(poly - s).T).max() < 0.98:
                    break
            tr = run_trial(rng, rounds, exact, poly, s, rng.uniform(-np.pi, np.pi), heading_noise, step_noise, noise_rng)
            inside_d.extend(tr["dist"][tr["inside"]].tolist())
            half_d.extend(tr["dist"][rounds // 2 :].tolist())
            fb += tr["fallback"]
            rig += tr["rigid"]
            n_rounds += rounds
            if traj_example is None:
                traj_example = (poly, s, tr["dist"])
    inside_d = np.array(inside_d)
    half_d = np.array(half_d)
    return {
        "mean_inside_cm": float(inside_d.mean() * 100) if inside_d.size else float("nan"),
        "mean_second_half_cm": float(half_d.mean() * 100),
        "frac_second_half_within_2dstep": float(np.mean(half_d <= 2 * D_STEP)),
        "rounds_inside": int(inside_d.size),
        "rounds": n_rounds,
        "seeker_rigid_frac": rig / n_rounds,
        "fallback_rounds": fb,
        "_inside": inside_d,
    }


def main(argv: list[str]) -> int:
    ap = OneLineArgumentParser(prog="python -m swarm_envs.validate centroid", description=__doc__.split("\n")[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--polygons", type=cli_type(Int(20, low=1, high=100_000)), default=20)
    ap.add_argument("--starts", type=cli_type(Int(10, low=1, high=100_000)), default=10, help="starting points per polygon")
    ap.add_argument("--rounds", type=cli_type(Int(40, low=1, high=100_000)), default=40)
    ap.add_argument("--polygon-radius", type=cli_type(Real(0.3, low=0.0, low_open=True, high=100.0, unit="of metres")), nargs=2,
                    default=[0.3, 0.5], metavar=("MIN", "MAX"))
    ap.add_argument("--heading-noise-deg", type=cli_type(Real(0.0, low=0.0, high=360.0, unit="of degrees")), default=0.0,
                    help="std of the seeker's turn error per step (deg)")
    ap.add_argument("--step-noise", type=cli_type(Real(0.0, low=0.0, high=10.0)), default=0.0, help="relative std of the step length")
    ap.add_argument("--seed", type=cli_type(Int(0, low=0, high=2**63 - 1)), default=0)
    ap.add_argument("--out", default="validation_output")
    ap.add_argument("--no-plots", action="store_true")
    args = ap.parse_args(argv)
    if args.polygon_radius[0] > args.polygon_radius[1]:
        ap.error(f"argument --polygon-radius: MIN must not exceed MAX, got {args.polygon_radius}")
    rr = tuple(args.polygon_radius)
    hn, sn = np.deg2rad(args.heading_noise_deg), args.step_noise
    sec = experiment(args.seed, args.polygons, args.starts, args.rounds, False, rr, hn, sn)
    noi = experiment(args.seed, args.polygons, args.starts, args.rounds, False, rr, hn, sn, bearing_noise=True)
    exa = experiment(args.seed, args.polygons, args.starts, args.rounds, True, rr, hn, sn)
    summary = {
        "kinematic": True,
        "sector_bearings": {k: v for k, v in sec.items() if not k.startswith("_")},
        "sector_bearings_hardware_noise": {k: v for k, v in noi.items() if not k.startswith("_")},
        "exact_bearings": {k: v for k, v in exa.items() if not k.startswith("_")},
        "paper_mean_cm": PAPER_MEAN_CM,
        "paper_bound_cm": 2 * D_STEP * 100,
        "d_step_cm": D_STEP * 100,
        "heading_noise_deg": args.heading_noise_deg,
        "step_noise": args.step_noise,
    }
    if not args.no_plots:
        try:
            import matplotlib

            matplotlib.use("Agg")
            import matplotlib.pyplot as plt

            os.makedirs(args.out, exist_ok=True)
            fig, ax = plt.subplots(figsize=(5, 3.5))
            ax.hist(sec["_inside"] * 100, bins=np.arange(0, 45, 2.5), alpha=0.7, label=f"sectors: mean {sec['mean_inside_cm']:.1f} cm")
            ax.hist(noi["_inside"] * 100, bins=np.arange(0, 45, 2.5), alpha=0.5, label=f"sectors + hw noise: mean {noi['mean_inside_cm']:.1f} cm")
            ax.hist(exa["_inside"] * 100, bins=np.arange(0, 45, 2.5), alpha=0.5, label=f"exact: mean {exa['mean_inside_cm']:.1f} cm")
            ax.axvline(PAPER_MEAN_CM, c="k", ls="--", label=f"paper mean {PAPER_MEAN_CM} cm")
            ax.axvline(22, c="r", ls=":", label="2 d_step")
            ax.set_xlabel("seeker-centroid distance (cm), inside polygon")
            ax.legend(fontsize=7)
            fig.tight_layout()
            path = os.path.join(args.out, "centroid_error.png")
            fig.savefig(path, dpi=120)
            plt.close(fig)
            summary["plots"] = [path]
        except Exception as exc:
            summary["plots_error"] = repr(exc)
    if args.json:
        print(json.dumps(summary, indent=2))
        return 0
    print(f"Centroid seeking [L Sec. 6.2.2, Fig. 6.4] (kinematic, no physics): {args.polygons} polygons x {args.starts} starts x "
          f"{args.rounds} rounds, d_step = 11 cm, 2-hop Alg. 4 on r-one sector bearings (IR layer); "
          f"motion noise: heading {args.heading_noise_deg} deg, step {args.step_noise * 100:.0f}%")
    print("sectors: noiseless (nominal 68-degree arcs); + hw noise: arcs and cones drawn from 63-74 deg per reading [L Sec. 3.2.1]")
    print(f"{'':38} {'ours (sectors)':>15} {'+ hw noise':>11} {'ours (exact)':>13} {'paper':>8}")
    print(f"{'mean distance inside polygon (cm)':38} {sec['mean_inside_cm']:15.2f} {noi['mean_inside_cm']:11.2f} {exa['mean_inside_cm']:13.2f} {PAPER_MEAN_CM:8.2f}")
    print(f"{'mean distance, 2nd half of run (cm)':38} {sec['mean_second_half_cm']:15.2f} {noi['mean_second_half_cm']:11.2f} {exa['mean_second_half_cm']:13.2f} {'':>8}")
    print(f"{'2nd-half rounds within 2 d_step':38} {sec['frac_second_half_within_2dstep'] * 100:14.1f}% {noi['frac_second_half_within_2dstep'] * 100:10.1f}% "
          f"{exa['frac_second_half_within_2dstep'] * 100:12.1f}% {'(< 22 cm)':>8}")
    print(f"{'seeker rigid (% of rounds)':38} {sec['seeker_rigid_frac'] * 100:14.1f}% {noi['seeker_rigid_frac'] * 100:10.1f}% {exa['seeker_rigid_frac'] * 100:12.1f}%")
    print(f"{'bearing-only fallback rounds':38} {sec['fallback_rounds']:15d} {noi['fallback_rounds']:11d} {exa['fallback_rounds']:13d}")
    if "plots" in summary:
        print("plots:", ", ".join(summary["plots"]))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
