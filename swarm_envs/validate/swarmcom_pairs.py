"""Static facing-pair experiments of the SwarmCom validation [T20]: a transmitter facing a receiver at a
sweep of distances, run through the bit-level network, for the communication and reliable range vs the
relative threshold (a: Figs. 11, 12a), the block error of the channel codes vs Eq. (34) (d: Fig. 13), the
ranges vs bit rate (e: Sec. 7, Figs. 10-12b) and the fit of the detector response's charge constant."""

from __future__ import annotations

from typing import Any

import numpy as np

from swarm_envs.comm.channel import RESPONSE_BIAS, ADCModel
from swarm_envs.comm.network import Network
from swarm_envs.ir.layer import compute_links
from swarm_envs.validate.swarmcom_setup import (
    BITRATE_SWEEP,
    PAPER_BITRATE_RELIABLE,
    PAPER_RANGE,
    PAPER_RELIABLE_CM,
    PLATFORM,
    SEP,
)


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
    """(a) Communication range (P_l <= 0.5, <= 0.1) and reliable range (P_e < 0.01) in cm per relative
    threshold m_tr, with the P_e / P_l curves vs distance [T20 Sec. 6.2.4, Fig. 12a; Sec. 7]."""
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


def message_error_probability(p_e: np.ndarray, n: int, t: int) -> np.ndarray:
    """1 - P_f of [T20 Eq. (34)], summed as ``sum_{i>t} C(n,i) p^i (1-p)^(n-i)`` (no cancellation);
    equals ``1 - error_free_probability(p_e, n, t)``."""
    from math import comb

    p = np.asarray(p_e, dtype=float)
    return sum(comb(n, i) * p**i * (1.0 - p) ** (n - i) for i in range(t + 1, n + 1))


def experiment_d(rng: np.random.Generator, quick: bool) -> dict[str, Any]:
    """(d) Measured 15-bit block error of the [15,15], [15,11] and [15,1] codes vs distance (cm) beside
    the Eq. (34) prediction from the uncoded P_e [T20 Sec. 5.4, Fig. 13]."""
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
    """(e) Reliable and communication range (cm) per bit rate at m_tr = 5, and at m_tr = 75 for three rates
    [T20 Secs. 6.2.5, 7]."""
    steps = 60 if quick else 300
    step_cm = 2.0 if quick else 1.0
    ranges = bitrate_ranges(rng, BITRATE_SWEEP, steps, step_cm)
    # [T20 Sec. 6.2.5]: with the range restricted to 21 cm (m_tr = 75) the bit rate matters little for P_e
    restricted = bitrate_ranges(rng, (310, 1080, 1670), steps, step_cm, relative_threshold=75, max_cm=30.0)
    return {"ranges": ranges, "restricted_mtr75": restricted, "paper": PAPER_BITRATE_RELIABLE, "steps": steps, "step_cm": step_cm}
