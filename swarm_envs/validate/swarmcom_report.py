"""Output of the SwarmCom validation [T20]: the text tables of experiments (a)-(e), the compared-figure rows
(:class:`swarm_envs.validate.report.Row`), the matplotlib plots and the conversion of the results to JSON."""

from __future__ import annotations

import os
from typing import Any

import numpy as np

from swarm_envs.validate.report import Row
from swarm_envs.validate.swarmcom_channels import CHANNEL_FRAMES, CHANNEL_MIN_SHARE
from swarm_envs.validate.swarmcom_setup import (
    FIG21_MTRS,
    M_TR_SWEEP,
    PAPER_BITRATE_RELIABLE,
    PAPER_FIG20A,
    PAPER_MTR,
    PAPER_RANGE,
    PAPER_RELIABLE_CM,
)


def _save(fig, out_dir: str, name: str) -> str:
    """Lay out, write and close a matplotlib figure; returns its path."""
    import matplotlib.pyplot as plt

    fig.tight_layout()
    path = os.path.join(out_dir, name)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def write_plots(results: dict[str, Any], out_dir: str) -> list[str]:
    """Plot the experiments in ``results`` as PNG files in ``out_dir`` (created if missing); returns their paths."""
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


def print_results(results: dict[str, Any]) -> None:
    """Print the text tables of the experiments in ``results``."""
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
        if "moving" in b:
            mv = b["moving"]
            print(f"  moving robots in the env [Alg. 1 random walk, full sensing]: {mv['trials']} trials, each counted once after {mv['count_at_s']:g} s;"
                  " lit = decoded a centre frame within the window: median [10%, 90%] (mean); the static centre pushed off the centre by (cm)")
            mcols = [(f"moving m_tr={m:g}, {w:g} s", f"moving_mtr{m}" if w == mv["window_s"] else f"moving_mtr{m}_window{w:g}s")
                     for m in b["fig21_m_tr"] for w in mv["windows_s"]]
            print(f"  {'robots':>6} | {'paper':>5} | " + " | ".join(f"{name:>25}" for name, _ in mcols) + " | centre pushed by, median [max]")
            for n, r in b["arena"].items():
                cells = [f"{r[key]['median']:4.0f} [{r[key]['p10']:.0f}, {r[key]['p90']:.0f}] ({r[key]['mean']:.1f})" for _, key in mcols]
                drift = r[f"moving_centre_drift_cm_mtr{b['fig21_m_tr'][0]}"]
                print(f"  {n:>6} | {r['paper']:>5} | " + " | ".join(f"{c:>25}" for c in cells) + f" | {drift['median']:.1f} [{drift['max']:.1f}]")
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
        if "moving" in b:
            mv = b["moving"]
            how = (f"median [10 %, 90 %] of {mv['trials']} trials, each an env copy started at random and counted once after {mv['count_at_s']:g} s of the random walk "
                   f"(physics, full sensing); lit: decoded a frame from the centre in the last {mv['window_s']:g} s")
            for m in b["fig21_m_tr"]:
                key = f"moving_mtr{m}"
                cells = " / ".join(f"{arena[n][key]['median']:.0f} [{arena[n][key]['p10']:.0f}, {arena[n][key]['p90']:.0f}]" for n in ns)
                out.append(Row("[T20 Fig. 21]", f"n_C with 10 / 20 / 30 robots, m_tr = {m} (moving, env)", cells,
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


def jsonable(x: Any) -> Any:
    """``x`` with dict keys as strings, tuples and arrays as lists, numpy scalars as Python ones and NaN as None."""
    if isinstance(x, dict):
        return {str(k): jsonable(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [jsonable(v) for v in x]
    if isinstance(x, (np.floating, float)):
        return None if np.isnan(x) else float(x)
    if isinstance(x, (np.integer,)):
        return int(x)
    if isinstance(x, np.ndarray):
        return jsonable(x.tolist())
    return x
