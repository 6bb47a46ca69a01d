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
    (:func:`swarm_envs.validate.swarmcom_channels.detector_channels`: ADC noise, detector response, min
    over detectors, start detection and dynamic threshold; it must receive at least half of the centre's
    frames intact) and, as a second row, as a noiseless amplitude above m_tr
    (:func:`swarm_envs.validate.swarmcom_channels.centre_amplitude`) for per-ray line of sight (as
    simulated) and for a centre-line rule, with m_tr swept over the paper's 61/45/33/21 cm settings;
    and Fig. 21 as the paper ran it, with the robots moving in the env
    (:func:`swarm_envs.validate.swarmcom_moving.moving_channels`: the random walk through physics and the
    full sensing stack, 100 trials per size, each counted once after 30 s; a robot is lit when it decoded a
    frame from the centre in the last 0.3 s, counts for 1 s and 5 s beside it);
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

This module is the command line; the experiments live in :mod:`swarm_envs.validate.swarmcom_pairs` (a, d, e),
:mod:`swarm_envs.validate.swarmcom_channels` and :mod:`swarm_envs.validate.swarmcom_moving` (b) and
:mod:`swarm_envs.validate.swarmcom_flooding` (c), their shared set-ups and the paper's figures in :mod:`swarm_envs.validate.swarmcom_setup`, and the tables, rows and
plots in :mod:`swarm_envs.validate.swarmcom_report`.
"""

from __future__ import annotations

import functools
import json
import time
from typing import Any

import numpy as np

from swarm_envs.comm.channel import M_MAX, M_MIN
from swarm_envs.tasks.settings import Int
from swarm_envs.tasks.settings_cli import OneLineArgumentParser, cli_type
from swarm_envs.validate.report import print_rows, rows_json
from swarm_envs.validate.swarmcom_channels import experiment_b
from swarm_envs.validate.swarmcom_flooding import experiment_c
from swarm_envs.validate.swarmcom_pairs import (
    experiment_a,
    experiment_d,
    experiment_e,
    fit_response_c,
)
from swarm_envs.validate.swarmcom_report import (
    jsonable,
    print_results,
    rows,
    write_plots,
)
from swarm_envs.validate.swarmcom_setup import FIG21_MTRS


def main(argv: list[str]) -> int:
    """Command line of ``swarm-validate swarmcom``: run the chosen experiments, print their tables (or JSON)
    and write the plots; returns the exit code (0; a bad option exits with 2)."""
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
    files = [] if args.no_plots else write_plots(results, args.out)
    if args.json:
        print(json.dumps(jsonable({"results": results, "rows": rows_json(rows(results)), "plots": files, "seconds": timing}), indent=1))
    else:
        print_results(results)
        print_rows("SwarmCom [T20]", rows(results))
        if files:
            print("plots: " + ", ".join(files))
        print("seconds: " + ", ".join(f"{k}={v:.1f}" for k, v in timing.items()))
    return 0
