"""Compiled (numba) kernels for the IR layer's hot path, with the numpy reference as fallback.

The IR layer's per-step work is a loop over P visible pairs x n_detectors x n_emitters that numpy can
only do through many (P, n_d, n_e) temporaries (memory-bound). These kernels do the same arithmetic
pair by pair, skipping dark emitter-detector combinations early. They implement exactly the models of
:mod:`swarm_envs.ir.models` (the numpy methods there stay the reference; ``tests/test_ir_kernels.py``
checks the two agree to 1e-12) and are used only when numba is importable (``pip install numba``, part
of the ``fast`` extra); otherwise the layer uses the numpy path.
"""

from __future__ import annotations

import math

import numpy as np

try:  # numba is optional: an accelerator, not a requirement
    from swarm_envs._numba import njit  # numba.njit whose cache recovers from corrupted files

    HAVE_NUMBA = True
except ImportError:  # pragma: no cover - exercised only without numba
    HAVE_NUMBA = False

__all__ = ["HAVE_NUMBA", "MODEL_IDS", "model_params", "gains_kernel", "occluded_kernel"]

#: model class name -> kernel model id
MODEL_IDS = {"DropletIR": 0, "EpuckIR": 1, "RoneIR": 2, "DropletLowPowerIR": 3}


def model_params(model: object) -> tuple[int, np.ndarray]:
    """(kernel id, float parameters) of an IR model instance; raises KeyError for unknown models."""
    kind = MODEL_IDS[type(model).__name__]
    if kind in (0, 3):
        p = [model.sensor_switch, model.emitter_switch, model.amp_coeff, model.amp_offset_cm, model.r_near_cm, model._a_near, 0.0, 0.0]
        if kind == 3:
            p[6], p[7] = model.low_coeff, model.low_offset
    elif kind == 1:
        p = [model.k_m, model.o_m, model.d_sat_cm]
    else:
        s_arc, e_arc = model.sensor_half_arc + model._eps, model.emitter_half_arc + model._eps
        p = [s_arc, e_arc, model.max_range, math.cos(s_arc), math.cos(e_arc)]
    return kind, np.asarray(p, dtype=np.float64)


if HAVE_NUMBA:

    @njit(cache=True, inline="always", error_model="numpy")
    def _droplet_sensor(a: float, switch: float) -> float:  # [F14 Eq. (19)]
        a4 = a * a * a * a
        return 1.0 - a4 if a < switch else 1.0 / (8.0 * a4)

    @njit(cache=True, inline="always", error_model="numpy")
    def _droplet_emitter(b: float, switch: float) -> float:  # [F14 Eq. (20)]
        b2 = b * b
        return -b2 * b2 + 0.5 * b2 + 0.9375 if b < switch else 1.0 / (4.0 * b2 * b2)

    @njit(cache=True, inline="always", error_model="numpy")
    def _gain(kind: int, p0: float, p1: float, p2: float, p3: float, p4: float, p5: float, p6: float, p7: float, d_m: float, cd: float, ce: float) -> float:
        if kind == 1:  # e-puck [T20 Eqs. (24),(25),(27)]
            if cd <= 0.0 or ce <= 0.0:
                return 0.0
            d_cm = 100.0 * d_m
            hm = 1.0 if d_cm <= p2 else p1 * math.exp(p0 * math.log(max(d_cm, 1e-12)))
            ce2 = ce * ce
            return ce2 * ce2 * ce2 * ce * cd * cd * cd * hm
        if kind == 2:  # r-one binary arcs [L Sec. 3.2]; p3, p4 = cos of the half arcs
            if d_m <= p2 and cd >= p3 and ce >= p4:
                return 1.0
            return 0.0
        # Droplet [F14 Eqs. (19)-(21)], full power (0) or the firmware's low power (3)
        a = math.acos(min(1.0, max(-1.0, cd)))
        b = math.acos(min(1.0, max(-1.0, ce)))
        r = 100.0 * d_m
        if kind == 3:
            amp = p6 / max(r, 1e-9) ** 2 + p7
        elif r >= p4:
            amp = p2 / max(r - p3, 1e-9) ** 2 - 1.0
        else:
            amp = p5 * (p4 / max(r, 1e-9)) ** 2 - 1.0
        amp = max(amp, 0.0)
        return _droplet_sensor(a, p0) * _droplet_emitter(b, p1) * amp

    @njit(cache=True, error_model="numpy")
    def gains_kernel(
        rel_position: np.ndarray,
        rel_heading: np.ndarray,
        det_pos: np.ndarray,
        det_dir: np.ndarray,
        em_pos: np.ndarray,
        em_dir: np.ndarray,
        kind: int,
        params: np.ndarray,
        ir_range: float,
    ) -> np.ndarray:
        """(P, n_d, n_e) gains; same geometry as ``pair_cosines`` (SPEC 2), same models."""
        P, nd, ne = rel_position.shape[0], det_pos.shape[0], em_pos.shape[0]
        out = np.zeros((P, nd, ne))
        dcos, dsin = np.cos(det_dir), np.sin(det_dir)
        ecos, esin = np.cos(em_dir), np.sin(em_dir)
        prm = np.zeros(8)
        prm[: params.shape[0]] = params
        p0, p1, p2, p3, p4, p5, p6, p7 = prm[0], prm[1], prm[2], prm[3], prm[4], prm[5], prm[6], prm[7]
        ex = np.empty(ne)
        ey = np.empty(ne)
        eax = np.empty(ne)
        eay = np.empty(ne)
        for p in range(P):
            Rx, Ry = rel_position[p, 0], rel_position[p, 1]
            if math.sqrt(Rx * Rx + Ry * Ry) > ir_range:
                continue
            c, s = math.cos(rel_heading[p]), math.sin(rel_heading[p])
            for j in range(ne):  # TX emitters and their axes in the RX frame
                ex[j] = Rx + c * em_pos[j, 0] - s * em_pos[j, 1]
                ey[j] = Ry + s * em_pos[j, 0] + c * em_pos[j, 1]
                eax[j] = c * ecos[j] - s * esin[j]
                eay[j] = s * ecos[j] + c * esin[j]
            for i in range(nd):
                for j in range(ne):
                    dx, dy = ex[j] - det_pos[i, 0], ey[j] - det_pos[i, 1]
                    d = math.sqrt(dx * dx + dy * dy)
                    inv = 1.0 / max(d, 1e-12)
                    ux, uy = dx * inv, dy * inv
                    cd = ux * dcos[i] + uy * dsin[i]
                    ce = -(ux * eax[j] + uy * eay[j])
                    out[p, i, j] = _gain(kind, p0, p1, p2, p3, p4, p5, p6, p7, d, cd, ce)
        return out

    @njit(cache=True, error_model="numpy")
    def occluded_kernel(
        positions: np.ndarray, radius: float, i: np.ndarray, j: np.ndarray, starts: np.ndarray, counts: np.ndarray, nbrs: np.ndarray
    ) -> np.ndarray:
        """(P,) True where a third robot's disc crosses the centre segment i-j (candidates: CSR lists)."""
        P = i.shape[0]
        blocked = np.zeros(P, dtype=np.bool_)
        r2 = radius * radius
        for p in range(P):
            a, b = i[p], j[p]
            ax, ay = positions[a, 0], positions[a, 1]
            sx, sy = positions[b, 0] - ax, positions[b, 1] - ay
            L2 = sx * sx + sy * sy
            if L2 <= 0.0:
                L2 = 1.0
            for end in (a, b):
                for q in range(starts[end], starts[end] + counts[end]):
                    k = nbrs[q]
                    if k == a or k == b:
                        continue
                    px, py = positions[k, 0] - ax, positions[k, 1] - ay
                    t = min(1.0, max(0.0, (px * sx + py * sy) / L2))
                    qx, qy = px - t * sx, py - t * sy
                    if qx * qx + qy * qy < r2:
                        blocked[p] = True
                        break
                if blocked[p]:
                    break
        return blocked
