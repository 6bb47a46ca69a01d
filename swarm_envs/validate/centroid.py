"""Centroid seeking with scale-free coordinates [L Sec. 6.2.2, Figs. 6.3-6.4].

The thesis's experiment: 4 static r-ones in an arbitrary polygon and one seeker starting outside it. "The
robot pauses in a stationary state when measuring neighbor bearings", computes its scale-free coordinates
and the angle to the scale-free centroid, moves ``d_step = 11 cm`` towards it, "then pauses for the next
neighbor round and repeats". Metric (Fig. 6.4(b)): mean seeker-centroid distance over the rounds in which
the seeker is inside the polygon ("errors outside the polygon are not included"); paper 14.03 cm, within
2 d_step = 22 cm. Layouts here: 4 anchors at the corners of a random convex quadrilateral (circumradius
``--polygon-radius`` range, every pair within the 1 m IR range), seeker starts 55-80 cm from the centroid.

**In the env** (:func:`experiment_env`, first row): ``swarm_envs/CentroidSeeking-v0`` with r-ones and the
full sensing stack (physics, message-borne sector bearings with the measured 63-74 degree arc spread, the
bearing exchange over SwarmCom, 2-hop coordinates), one batched copy per trial, the seeker driven by
:class:`PauseStepSeeker`: pause one beacon / exchange round (``--pause-rounds``), read the centroid of its
``scale_free`` observation rows, turn in place, drive 11 cm. The seeker's drive carries the r-one's motion
error (``motion_noise``, the env's default: per-wheel gains, per-step speed noise, the 15 mm/s dead zone;
``docs/design.md#motion-error``); ``--no-motion-noise`` runs it with exact differential-drive kinematics.

**Kinematic** (:func:`experiment`, no physics, exact turns and steps). Each round:

1. the shared IR layer gives the links of the current poses (binary r-one gains, line of sight:
   the seeker can occlude anchor-anchor links) (:func:`swarm_envs.ir.layer.compute_links`);
2. the firmware sector rule turns them into 22.5-degree bearings (:mod:`swarm_envs.sensing.bearing_sensor`),
   noiseless (nominal 68-degree arcs) or with the hardware noise model of the env's ``bearing_noise``
   (each robot's own receiver arcs and transmitter cones drawn once per trial from the thesis' measured 63-74 degrees
   [L Sec. 3.2.1]; :func:`swarm_envs.sensing.bearing_sensor.draw_half_arcs`);
3. an ideal exchange round (:class:`swarm_envs.sensing.exchange.BearingExchange`, ``mode="ideal"``);
4. the seeker computes 2-hop scale-free coordinates with ANGLEBALANCE and the noise-sensitivity MST
   [L Alg. 4] (:func:`swarm_envs.sensing.scale_free.coordinates_all`) and the centroid of the anchors it
   has coordinates for (the direction to it is scale-free);
5. it turns to that direction and moves ``d_step = 11 cm``; a step that would overlap an anchor is
   projected back onto the contact circle (the seeker slides around it).

In both, if no anchor length is computable in a round, the seeker steps along the mean of the unit bearing
vectors of the anchors it sees (a bearing-only fallback, ours; counted in the output). Optional motion
noise of the kinematic runs (``--heading-noise-deg``, ``--step-noise``; default off) perturbs each step's
direction and length. Also reported: the mean over the second half of each run, and the kinematic runs
with exact bearings (no quantisation) as a reference. The thesis's bearing-error histogram [L Fig. 3.13(a)]
has no numbers in its text; the arc spread is the only measured hardware figure used (nothing is tuned
to the 14.03 cm).
"""

from __future__ import annotations

import json
import os
import sys
import time
from typing import Any

import numpy as np

from swarm_envs.ir.layer import compute_links
from swarm_envs.sim.platforms import get_platform
from swarm_envs.sensing.bearing_sensor import BearingReadings, draw_half_arcs, pair_half_arcs, sense_bearings
from swarm_envs.sensing.exchange import BearingExchange
from swarm_envs.sensing.scale_free import coordinates_all
from swarm_envs.validate.report import Row, print_rows, rows_json
from swarm_envs.tasks.settings import Int, Real
from swarm_envs.tasks.settings_cli import OneLineArgumentParser, cli_type

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
    arcs = None if noise_rng is None else draw_half_arcs(noise_rng, len(pos), plat)  # each robot's own arcs and cones
    for _ in range(rounds):
        links = compute_links(pos, hd, plat, drop_zero=noise_rng is None)  # wider arcs may light a dark pair
        if exact:
            P = len(links)
            z = np.zeros(P)
            rd = BearingReadings(links.rx, links.tx, links.bearing, z, z, z.astype(np.uint16), z.astype(np.uint16), np.ones(P, bool))
        elif noise_rng is not None:
            rd = sense_bearings(links, plat, half_arcs=pair_half_arcs(arcs, links.rx, links.tx, plat))
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


# ------------------------------------------------------------------------------------------- in the env
PAUSE, TURN, DRIVE = 0, 1, 2


class PauseStepSeeker:
    """The thesis's centroid controller [L Sec. 6.2.2] on env observations, one phase machine per seeker:

    1. pause ``pause_steps`` control steps ("the robot pauses in a stationary state when measuring neighbor
       bearings"; one beacon / exchange round by default), zero action;
    2. read the observation: the direction of the centroid of the valid ``scale_free`` rows (the anchors it
       has coordinates for, in its own frame; only the direction is used; straight ahead when the estimate
       is exactly at the robot, as the thesis's robot "cannot stop"). With none, the mean bearing of the
       valid ``range_bearing`` rows (the kinematic run's bearing-only fallback, counted); with neither,
       pause another round (counted);
    3. turn in place to that direction, open loop, at up to the platform's maximum angular speed;
    4. drive ``d_step`` (11 cm) at up to the maximum speed, then pause again.

    Reads nothing but the observation. ``moved`` marks the seekers that finished a step in the last call.
    """

    def __init__(self, n: int, max_speed: float, max_angular_speed: float, pause_steps: int, d_step: float = D_STEP, dt: float = 0.1) -> None:
        if pause_steps < 1:
            raise ValueError(f"pause_steps must be >= 1, got {pause_steps}")
        self.n, self.w_step, self.pause_steps = n, max_angular_speed * dt, int(pause_steps)
        self.drive_steps = int(np.ceil(d_step / (max_speed * dt) - 1e-9))
        self.drive_fraction = d_step / (self.drive_steps * max_speed * dt)  # d_step exactly in whole steps
        self.phase = np.full(n, PAUSE)
        self.timer = np.full(n, self.pause_steps)
        self.turn_left = np.zeros(n, dtype=np.int64)
        self.turn_fraction = np.zeros(n)
        self.drive_left = np.zeros(n, dtype=np.int64)
        self.moved = np.zeros(n, dtype=bool)
        self.plans = {"scale_free": 0, "bearing_fallback": 0, "waited": 0}
        self.rigid_at_plan: list[bool] = []

    def direction(self, obs: dict[str, np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
        """Body-frame direction (rad) of the scale-free centroid, and its source (0 none, 1 scale-free, 2 bearings)."""
        sf = obs["scale_free"]
        valid = sf[..., 0] > 0.5
        count = valid.sum(axis=1)
        cx = (sf[..., 1] * valid).sum(axis=1) / np.maximum(count, 1)
        cy = (sf[..., 2] * valid).sum(axis=1) / np.maximum(count, 1)
        rb = obs["range_bearing"]
        seen = rb[..., 0] > 0.5
        bx, by = (rb[..., 2] * seen).sum(axis=1), (rb[..., 3] * seen).sum(axis=1)
        has_sf = count > 0
        has_rb = seen.any(axis=1)
        # an estimate exactly at the robot (a symmetric sector pattern) gives atan2(0, 0) = 0: straight ahead,
        # as the thesis's robot "cannot stop"
        angle = np.where(has_sf, np.arctan2(cy, cx), np.arctan2(by, bx))
        return angle, np.where(has_sf, 1, np.where(has_rb, 2, 0))

    def act(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        """(n, 2) actions (linear, angular fractions of the maxima) for the seekers' observations ``obs``."""
        lin, ang = np.zeros(self.n), np.zeros(self.n)
        pausing = self.phase == PAUSE
        self.timer[pausing] -= 1
        ready = pausing & (self.timer <= 0)
        if ready.any():
            angle, source = self.direction(obs)
            wait = ready & (source == 0)
            self.timer[wait] = self.pause_steps
            go = ready & (source > 0)
            self.plans["waited"] += int(wait.sum())
            self.plans["scale_free"] += int((go & (source == 1)).sum())
            self.plans["bearing_fallback"] += int((go & (source == 2)).sum())
            self.rigid_at_plan.extend((obs["rigid"][go, 0] > 0.5).tolist())
            steps = np.ceil(np.abs(angle) / self.w_step - 1e-9).astype(np.int64)
            self.turn_left[go] = steps[go]
            self.turn_fraction[go] = (angle / (np.maximum(steps, 1) * self.w_step))[go]
            self.phase[go] = TURN
        turned = (self.phase == TURN) & (self.turn_left <= 0)
        self.phase[turned] = DRIVE
        self.drive_left[turned] = self.drive_steps
        turning = self.phase == TURN
        ang[turning] = self.turn_fraction[turning]
        self.turn_left[turning] -= 1
        driving = self.phase == DRIVE
        lin[driving] = self.drive_fraction
        self.drive_left[driving] -= 1
        self.moved = driving & (self.drive_left <= 0)
        self.phase[self.moved] = PAUSE
        self.timer[self.moved] = self.pause_steps
        return np.stack([lin, ang], axis=-1)


def trial_layouts(seed: int, polygons: int, starts: int, r_range: tuple[float, float]) -> list[tuple[np.ndarray, np.ndarray, float]]:
    """(anchor polygon (4, 2) m centred on its centroid, seeker start (2,) m outside it, seeker heading rad)
    for ``polygons`` x ``starts`` trials, drawn as the kinematic :func:`experiment` draws them."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(polygons):
        poly = random_polygon(rng, *r_range, min_sep=0.25)
        poly = poly - poly.mean(0)
        for _ in range(starts):
            while True:
                a = rng.uniform(0, 2 * np.pi)
                s = rng.uniform(0.55, 0.8) * np.array([np.cos(a), np.sin(a)])
                if not inside(poly, s) and np.hypot(*(poly - s).T).min() > 0.15 and np.hypot(*(poly - s).T).max() < 0.98:
                    break
            out.append((poly, s, float(rng.uniform(-np.pi, np.pi))))
    return out


def experiment_env(
    seed: int, polygons: int, starts: int, rounds: int, r_range: tuple[float, float], pause_steps: int, **settings: Any,
) -> dict:
    """Centroid seeking run in ``swarm_envs/CentroidSeeking-v0`` (r-one, full sensing: physics, message-borne
    sector bearings with the arc spread, the bearing exchange over SwarmCom, scale-free coordinates), one
    batched copy per trial (:mod:`swarm_envs.validate.envs`; trial k seeded ``seed + k``), the seeker driven
    by :class:`PauseStepSeeker`. The distance to the anchors' current centroid (a seeker can push an anchor;
    the largest anchor displacement is reported) is recorded after each of a seeker's first ``rounds``
    steps; metrics as :func:`experiment`. ``settings`` override the env's."""
    from swarm_envs.sim.platforms import get_platform
    from swarm_envs.validate.envs import scene_core

    layouts = trial_layouts(seed, polygons, starts, r_range)
    B = len(layouts)
    plat = get_platform("rone")
    heading_rng = np.random.default_rng([seed, 1])
    positions = [np.vstack([poly, s]) for poly, s, _ in layouts]
    headings = [np.r_[heading_rng.uniform(-np.pi, np.pi, 4), h0] for _, _, h0 in layouts]
    seekers = PauseStepSeeker(B, plat.max_speed, plat.max_angular_speed, pause_steps)
    turn_max = int(np.ceil(np.pi / seekers.w_step)) + 1
    cap = rounds * (pause_steps + turn_max + seekers.drive_steps) * 4
    cfg = dict(n_robots=1, n_anchors=4, platform="rone", sensing="full", arena_size=2.0, max_cycles=cap + 1)
    cfg.update(settings)
    core = scene_core("swarm_envs/CentroidSeeking-v0", positions, headings, [seed + k for k in range(B)], **cfg)
    rows = core.agent_rows()[:, 0]
    n_world = core.n_world
    dists = np.full((B, rounds), np.nan)
    ins = np.zeros((B, rounds), dtype=bool)
    done = np.zeros(B, dtype=np.int64)
    anchors_moved = 0.0
    steps = 0
    actions = np.zeros((core.n_total, core.layout.action_size))
    while done.min() < rounds and steps < cap:
        obs = {k: v[rows] for k, v in core.observations().items()}
        actions[rows] = seekers.act(obs)
        core.step(actions)
        steps += 1
        pos = core.positions.reshape(B, n_world, 2)
        anchors_moved = max(anchors_moved, float(np.abs(pos[:, :4] - np.array([poly for poly, _, _ in layouts])).max()))
        for b in np.flatnonzero(seekers.moved & (done < rounds)):
            # the anchors' centroid and polygon now (a seeker can push an anchor)
            dists[b, done[b]] = np.hypot(*(pos[b, 4] - pos[b, :4].mean(axis=0)))
            ins[b, done[b]] = inside(pos[b, :4], pos[b, 4])
            done[b] += 1
    complete = done >= rounds
    inside_d = dists[complete][ins[complete]]
    half = dists[complete][:, rounds // 2 :].ravel()
    return {
        "mean_inside_cm": float(inside_d.mean() * 100) if inside_d.size else float("nan"),
        "mean_second_half_cm": float(half.mean() * 100) if half.size else float("nan"),
        "frac_second_half_within_2dstep": float(np.mean(half <= 2 * D_STEP)) if half.size else float("nan"),
        "rounds_inside": int(inside_d.size),
        "rounds": int(complete.sum() * rounds),
        "trials_complete": int(complete.sum()),
        "trials": B,
        "seeker_rigid_frac": float(np.mean(seekers.rigid_at_plan)) if seekers.rigid_at_plan else float("nan"),
        "fallback_rounds": seekers.plans["bearing_fallback"],
        "waited_rounds": seekers.plans["waited"],
        "pause_steps": pause_steps,
        "motion_noise": bool(core.motion_noise),
        "control_steps": steps,
        "anchors_max_displacement_m": anchors_moved,
        "_inside": inside_d,
    }


THESIS_SETUP = ("real r-ones: 4 static in an arbitrary polygon, one seeker starting outside it at several places; it pauses for "
                "each neighbour round, then steps d_step = 11 cm towards its scale-free centroid; distances inside the polygon [L Sec. 6.2.2, Fig. 6.4]")


def rows(summary: dict[str, Any]) -> list[Row]:
    """The compared figures of a ``centroid`` run, one :class:`Row` each."""
    out = []
    runs = []
    if "env" in summary:
        e = summary["env"]
        drive = "the r-one's motion error" if e.get("motion_noise", True) else "exact drive (motion_noise=False)"
        runs.append((e, f"in the env (physics with {drive}, message-borne bearings, SwarmCom exchange), pause {e['pause_steps']} steps per "
                        f"round, {e['trials_complete']} of {e['trials']} trials x {summary['rounds']} rounds"))
    runs.append((summary["sector_bearings_hardware_noise"], "kinematic (exact turns and steps), IR-layer sector bearings with the 63-74 deg arcs, ideal exchange"))
    runs.append((summary["sector_bearings"], "kinematic, nominal 68-degree arcs, ideal exchange"))
    for r, how in runs:
        out.append(Row("[L Sec. 6.2.2, Fig. 6.4(b)]", "mean seeker-centroid distance inside the polygon", f"{r['mean_inside_cm']:.2f} cm",
                       f"{PAPER_MEAN_CM} cm", THESIS_SETUP, how))
    for r, how in runs[:1]:
        out.append(Row("[L Sec. 6.2.2]", "second-half rounds within 2 d_step = 22 cm", f"{100 * r['frac_second_half_within_2dstep']:.1f} %",
                       "mean within 2 d_step", THESIS_SETUP, how))
    return out


def main(argv: list[str]) -> int:
    from swarm_envs.sensing.full import BEACON_PERIOD

    ap = OneLineArgumentParser(prog="python -m swarm_envs.validate centroid", description=__doc__.split("\n")[0])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--polygons", type=cli_type(Int(20, low=1, high=100_000)), default=20)
    ap.add_argument("--starts", type=cli_type(Int(10, low=1, high=100_000)), default=10, help="starting points per polygon")
    ap.add_argument("--rounds", type=cli_type(Int(40, low=1, high=100_000)), default=40)
    ap.add_argument("--polygon-radius", type=cli_type(Real(0.3, low=0.0, low_open=True, high=100.0, unit="of metres")), nargs=2,
                    default=[0.3, 0.5], metavar=("MIN", "MAX"))
    ap.add_argument("--heading-noise-deg", type=cli_type(Real(0.0, low=0.0, high=360.0, unit="of degrees")), default=0.0,
                    help="kinematic runs: std of the seeker's turn error per step (deg)")
    ap.add_argument("--step-noise", type=cli_type(Real(0.0, low=0.0, high=10.0)), default=0.0,
                    help="kinematic runs: relative std of the step length")
    ap.add_argument("--pause-rounds", type=cli_type(Real(1.0, low=0.0, low_open=True, high=1000.0)), default=1.0,
                    help=f"env run: the seeker's pause before each step, in beacon / exchange rounds of {BEACON_PERIOD} control steps (default 1)")
    ap.add_argument("--no-env", action="store_true", help="skip the run in the env")
    ap.add_argument("--no-motion-noise", action="store_true",
                    help="env run: exact differential-drive kinematics instead of the r-one's motion error (motion_noise=False)")
    ap.add_argument("--seed", type=cli_type(Int(0, low=0, high=2**63 - 1)), default=0)
    ap.add_argument("--out", default="validation_output")
    ap.add_argument("--no-plots", action="store_true")
    args = ap.parse_args(argv)
    if args.polygon_radius[0] > args.polygon_radius[1]:
        ap.error(f"argument --polygon-radius: MIN must not exceed MAX, got {args.polygon_radius}")
    pause_steps = int(round(args.pause_rounds * BEACON_PERIOD))
    if pause_steps < 1:
        ap.error(f"--pause-rounds must give at least one control step, got {args.pause_rounds}")
    rr = tuple(args.polygon_radius)
    hn, sn = np.deg2rad(args.heading_noise_deg), args.step_noise
    t0 = time.perf_counter()
    sec = experiment(args.seed, args.polygons, args.starts, args.rounds, False, rr, hn, sn)
    noi = experiment(args.seed, args.polygons, args.starts, args.rounds, False, rr, hn, sn, bearing_noise=True)
    exa = experiment(args.seed, args.polygons, args.starts, args.rounds, True, rr, hn, sn)
    t1 = time.perf_counter()
    env = None if args.no_env else experiment_env(args.seed, args.polygons, args.starts, args.rounds, rr, pause_steps,
                                                  motion_noise=not args.no_motion_noise)
    t2 = time.perf_counter()
    public = lambda d: {k: v for k, v in d.items() if not k.startswith("_")}  # noqa: E731
    summary = {
        "sector_bearings": public(sec),
        "sector_bearings_hardware_noise": public(noi),
        "exact_bearings": public(exa),
        "paper_mean_cm": PAPER_MEAN_CM,
        "paper_bound_cm": 2 * D_STEP * 100,
        "d_step_cm": D_STEP * 100,
        "rounds": args.rounds,
        "heading_noise_deg": args.heading_noise_deg,
        "step_noise": args.step_noise,
        "runtime_s": {"kinematic": t1 - t0, "env": t2 - t1},
    }
    if env is not None:
        summary["env"] = public(env)
    summary["rows"] = rows_json(rows(summary))
    if not args.no_plots:
        try:
            import matplotlib

            matplotlib.use("Agg")
            import matplotlib.pyplot as plt

            os.makedirs(args.out, exist_ok=True)
            fig, ax = plt.subplots(figsize=(6, 4))
            bins = np.arange(0, 45, 2.5)
            if env is not None:
                ax.hist(env["_inside"] * 100, bins=bins, alpha=0.8, color="k", histtype="step", lw=2,
                        label=f"in the env: mean {env['mean_inside_cm']:.1f} cm")
            ax.hist(noi["_inside"] * 100, bins=bins, alpha=0.5, label=f"kinematic, sectors + arc spread: mean {noi['mean_inside_cm']:.1f} cm")
            ax.hist(exa["_inside"] * 100, bins=bins, alpha=0.4, label=f"kinematic, exact bearings: mean {exa['mean_inside_cm']:.1f} cm")
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
    print(f"Centroid seeking [L Sec. 6.2.2, Fig. 6.4]: {args.polygons} polygons x {args.starts} starts x {args.rounds} rounds, "
          f"d_step = 11 cm, 2-hop Alg. 4 coordinates")
    print("kinematic (no physics, exact turns and steps, ideal exchange, IR-layer sector bearings): 'sectors' nominal 68-degree")
    print(f"arcs, '+ hw noise' arcs and cones drawn from 63-74 deg per robot [L Sec. 3.2.1]; motion noise: heading "
          f"{args.heading_noise_deg} deg, step {args.step_noise * 100:.0f}%")
    if env is not None:
        print(f"in the env: swarm_envs/CentroidSeeking-v0, r-one, full sensing, motion error {'on' if env['motion_noise'] else 'off'}; "
              f"the seeker pauses {pause_steps} control steps "
              f"({args.pause_rounds:g} beacon round(s)), turns, drives 11 cm ({env['control_steps']} steps; anchors pushed up to "
              f"{100 * env['anchors_max_displacement_m']:.1f} cm, distances to their current centroid)")
    cols = ([("in the env", env)] if env is not None else []) + [("sectors", sec), ("+ hw noise", noi), ("exact", exa)]
    print(f"{'':38} " + " ".join(f"{name:>11}" for name, _ in cols) + f" {'paper':>8}")
    print(f"{'mean distance inside polygon (cm)':38} " + " ".join(f"{r['mean_inside_cm']:11.2f}" for _, r in cols) + f" {PAPER_MEAN_CM:8.2f}")
    print(f"{'mean distance, 2nd half of run (cm)':38} " + " ".join(f"{r['mean_second_half_cm']:11.2f}" for _, r in cols))
    print(f"{'2nd-half rounds within 2 d_step':38} " + " ".join(f"{100 * r['frac_second_half_within_2dstep']:10.1f}%" for _, r in cols) + f" {'(< 22 cm)':>8}")
    print(f"{'seeker rigid (% of rounds)':38} " + " ".join(f"{100 * r['seeker_rigid_frac']:10.1f}%" for _, r in cols))
    print(f"{'bearing-only fallback rounds':38} " + " ".join(f"{r['fallback_rounds']:11d}" for _, r in cols))
    if env is not None:
        print(f"{'env: rounds waited (no neighbour seen)':38} {env['waited_rounds']:11d}")
    print(f"runtime: kinematic {t1 - t0:.1f} s, env {t2 - t1:.1f} s")
    if "plots" in summary:
        print("plots:", ", ".join(summary["plots"]))
    print_rows("Centroid seeking [L]", rows(summary))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
