"""SwarmCom physical channel: received intensity and the 12-bit ADC measurement [T20 Sec. 3].

The geometry and the emitter/medium/detector gains come from the shared IR layer
(:mod:`swarm_envs.ir.layer`, :mod:`swarm_envs.ir.models`); this module only turns gains into the
received intensity ``y`` and into ADC counts ``m``:

- robot-to-robot model [T20 Eqs. (10),(11)]: ``y_j = min(1, sum_i h_e(alpha_ij) h_m(d_ij) h_d(beta_ji) s(t)
  + n_j)``, summed over every emitter i of every transmitting robot in line of sight (superposition,
  so overlapping transmissions collide physically);
- measurement model [T20 Eqs. (15)-(22)]: ``m = floor((m_max - m_min)(1 - y^0) + m_min + n_m)``, clipped
  to the ADC range [0, 4095], m_max = 4080 (ambient), m_min = 150 (saturation), n_m ~ N(0, 2.5)
  (variance 2.5 counts^2) [T20 Sec. 3.4.1, Table 1].

Intensity noise ``n_j``: the paper writes it in Eq. (11) but identifies only the measurement noise n_m
(Eq. (22) uses the noise-free ``y^0``); so by default ``n_j = 0`` and all noise is n_m. A non-zero
``intensity_sigma`` adds Gaussian ``n_j`` before the ``min(1, .)`` saturation.

Bit-rate-dependent detector response [T20 Secs. 5.2, 5.3, 7]. The paper's reliable range (P_e < 0.01,
two static e-pucks facing each other, dynamic detector, m_tr = 5) falls from 61 cm at 310 bps to 14 cm at
1800 bps, which it attributes to the measuring circuit: charged capacitive elements, slow symbol
transitions and inter-symbol interference, high error rates at high bit rates "when the robots are not
near each other". An instantaneous detector has none of this (P_e = 0 out to ~50 cm at every rate), so
the ADC samples, at the end of every bit slot of duration ``T = 1 / bitrate``, the level ``v`` of a
detector circuit that follows the light ``y`` (the saturated intensity above) with a speed set by its
own photocurrent, as a bipolar phototransistor whose small-signal bandwidth ``g_m / C`` grows with its
collector current:

    dv/dt = (y - v) (v + b) / c,   i.e. time constant tau = c / (v + b),

with ``b`` the bias (ambient + dark) photocurrent in intensity units and ``c`` a charge constant (s). Over
a slot of constant ``y`` this logistic equation has the exact solution (``u0 = v + b``, ``Y = y + b``)

    v' = Y u0 / (u0 + (Y - u0) exp(-Y T / c)) - b,

(:func:`detector_response`; the compiled slot loop inlines the same arithmetic). ``v`` is a per-robot,
per-detector state carried across slots and control steps (``Network.rx_level``, reset with the robot's
env copy); the ADC then reads ``m = floor((m_max - m_min)(1 - v) + m_min + n_m)``. A strong signal rises
within a slot; a weak one (far away) rises slowly, so its sampled amplitude shrinks at short slots; after
a '1' the level decays quickly at first and slowly near the bias (the slow discharge the paper names), so
the next bits see the tail (inter-symbol interference). Only the e-puck has the response (other
platforms' receivers sample instantly: ``response_c = 0``).

Fit (docs/design.md#swarmcom-messaging: the response is fitted to the published ranges). ``b`` and ``c`` are not both identifiable from the
two published numbers. For each b, ``c`` is fitted to **14 cm at 1800 bps** [T20 Sec. 7] with
``python -m swarm_envs.validate swarmcom --fit-response`` (:func:`swarm_envs.validate.swarmcom_pairs.fit_response_c`:
bisection in log c on a static facing pair, 7..30 cm in 1 cm steps, 300 control steps per distance,
seed 11; for b = 0.01 the 14 cm plateau is c in [1.28e-5, 1.37e-5] s, fit c = 1.32e-5 s = RESPONSE_C,
i.e. tau = 1.3 ms for a dark detector, 0.27 ms at 14 cm, 13 us at saturation). **61 cm at 310 bps**
[T20 Sec. 7] then bounds b from below: a small b makes weak, far signals slow even at 310 bps. P_e at
61 cm, 310 bps (3 x 2000 steps) is 0.0099 with the instantaneous detector and 0.0173 / 0.0132 / 0.0117 /
0.0109 / 0.0107 / 0.0102 for b = 0.003 / 0.005 / 0.007 / 0.01 / 0.015 / 0.03 (each with its fitted c). We
take **b = 0.01** (RESPONSE_BIAS), the smallest of these within 10 % of the instantaneous detector (61 cm
kept to ~0.5 cm). Fitted: c (to 14 cm at 1800 bps) and the choice of b (61 cm at 310 bps). Predictions:
the other rates, whose values the paper shows only in figures (Figs. 10-12b; not in its text), and they
depend on b. Reliable range at 310 / 650 / 1080 / 1160 / 1670 / 1800 bps (cm; one seed, 300 steps, 1 cm
grid): b = 0.005: 59 / 51 / 24 / 22 / 15 / 14; b = 0.01: 59 / 55 / 32 / 27 / 15 / 14; b = 0.02:
59 / 56 / 52 / 49 / 16 / 14; b = 0.03: 59 / 57 / 53 / 51 / 16 / 14; instantaneous: 61 / 61 / 60 / 60 /
60 / 60 (``python -m swarm_envs.validate swarmcom --experiment e`` prints the default model's).

Other platforms. The protocol only needs a dimensionless intensity ``y`` in [0, 1] and an ADC. For a
platform whose IR model gain is in other units we normalise with the model's measurement constants:
``y = gain * model.adc_scale / model.adc_max`` (so y = 1 is the platform's saturation level; for the
e-puck this is the identity), and use an ADC with ``m_max = model.adc_max``, ``m_min = 0`` and noise
``model.default_noise_sigma``: the Droplet's 8-bit IR receiver (y = counts / 255, noise sigma 2 counts;
the relative threshold m_tr is then in Droplet counts and should be >= ~8, i.e. 4 sigma, see
:func:`recommended_relative_threshold`). Binary receivers (the r-one, y in {0, 1}) get the e-puck's
12-bit scale without noise, so the default m_tr = 5 and Eq. (36) work unchanged. All platforms then run
the same OOK / start-symbol / dynamic-threshold protocol.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from swarm_envs.sim._vecmath import exp_array
from swarm_envs.sim.platforms import Platform, get_platform

__all__ = [
    "ADCModel",
    "adc_model_for",
    "recommended_relative_threshold",
    "gain_to_intensity",
    "detector_intensity",
    "adc",
    "detector_response",
    "M_MAX",
    "M_MIN",
    "M_SUP",
    "NOISE_VAR",
]

M_MAX = 4080.0  # ambient light value (counts) [T20 Table 1]
M_MIN = 150.0  # saturation value (counts) [T20 Table 1]
M_SUP = 4095  # 12-bit ADC full scale, 2^12 - 1 [T20 Sec. 3.3]
NOISE_VAR = 2.5  # ADC noise variance (counts^2) [T20 Sec. 3.4.1]
#: e-puck detector response (module docstring "Bit-rate-dependent detector response", "Fit"): bias intensity
#: b (chosen: lower bound from 61 cm at 310 bps) and charge constant c (s, fitted to 14 cm at 1800 bps [T20 Sec. 7]).
RESPONSE_BIAS = 0.01
RESPONSE_C = 1.32e-5  # s
#: a dark detector's response level below this is set to 0 (1e-6 of saturation = 0.004 counts, far below
#: the ADC noise sigma of 1.6 counts): its decay tail then stops costing compute
DARK_LEVEL = 1e-6


@dataclass(frozen=True)
class ADCModel:
    """Measurement model of one platform [T20 Eqs. (15)-(22)].

    Attributes:
        m_max: ambient-light value (counts): what an unlit detector reads on average.
        m_min: saturation value (counts): what a detector reads at y >= 1.
        m_sup: ADC full scale (counts); measurements are clipped to [0, m_sup].
        noise_var: variance of the additive Gaussian ADC noise n_m (counts^2).
        intensity_scale: multiply a summed model gain by this to get the intensity y (1 = saturation).
        response_c: charge constant c (s) of the detector response (time constant at photocurrent
            y + b = 1); 0 = instantaneous detector (no bit-rate dependence), see :func:`detector_response`.
        response_bias: bias intensity b of the detector response (dimensionless, > 0 when response_c > 0).
    """

    m_max: float = M_MAX
    m_min: float = M_MIN
    m_sup: int = M_SUP
    noise_var: float = NOISE_VAR
    intensity_scale: float = 1.0
    response_c: float = RESPONSE_C
    response_bias: float = RESPONSE_BIAS

    @property
    def noise_sigma(self) -> float:
        return float(np.sqrt(self.noise_var))


def adc_model_for(platform: Platform | str) -> ADCModel:
    """The ADC model of a platform: the e-puck constants of [T20 Table 1]; for other platforms the IR
    model's own scale (module docstring)."""
    platform = get_platform(platform)
    if platform.name == "epuck" or (platform.extras or {}).get("ir_model") == "epuck":
        return ADCModel()
    model = platform.ir_model
    full = float(model.adc_max)
    sigma = float(getattr(model, "default_noise_sigma", 0.0))
    # the detector response is fitted to the e-puck's circuit only: other platforms sample instantly
    if full <= 1.0:  # binary receivers (r-one): a noiseless 12-bit-like scale so m_tr and Eq. (36) work
        return ADCModel(noise_var=sigma * sigma, intensity_scale=float(model.adc_scale) / full, response_c=0.0)
    return ADCModel(
        m_max=full,
        m_min=0.0,
        m_sup=int(np.ceil(full)),
        noise_var=sigma * sigma,
        intensity_scale=float(model.adc_scale) / full,
        response_c=0.0,
    )


def recommended_relative_threshold(platform: Platform | str) -> float:
    """A relative threshold m_tr (counts of the platform's ADC model) giving few noise-triggered starts:
    5 for the e-puck [T20 Eq. (33)] and binary receivers, else 4 noise sigmas (8 for the Droplet)."""
    platform = get_platform(platform)
    m = adc_model_for(platform)
    if platform.name == "epuck" or m.noise_var == 0:
        return 5.0
    return float(np.ceil(4.0 * m.noise_sigma))


def gain_to_intensity(gain_sum: np.ndarray, platform: Platform | str, adc_model: ADCModel | None = None) -> np.ndarray:
    """Summed model gain -> saturated intensity ``y = min(1, scale * gain)`` [T20 Eq. (10)]."""
    m = adc_model if adc_model is not None else adc_model_for(platform)
    return np.minimum(1.0, m.intensity_scale * np.asarray(gain_sum, dtype=float))


def detector_intensity(
    tx_xy: np.ndarray,
    tx_heading: np.ndarray | float,
    rx_xy: np.ndarray,
    rx_heading: np.ndarray | float,
    platform: Platform | str,
) -> np.ndarray:
    """Noiseless received intensity y at each detector of the receiver when every emitter of the
    transmitter is on, line of sight assumed [T20 Eqs. (7)-(14), (10) with n_j = 0].

    Args:
        tx_xy: (..., 2) transmitter centre, world frame (m).
        tx_heading: (...) transmitter heading (rad).
        rx_xy: (..., 2) receiver centre (m).
        rx_heading: (...) receiver heading (rad).
        platform: platform of both robots.

    Returns:
        (..., n_detectors) intensity ``y = min(1, sum_emitters gain)`` (dimensionless, 1 = saturation).
    """
    from swarm_envs.ir.layer import pair_gains
    from swarm_envs.sim.geometry import wrap_angle

    platform = get_platform(platform)
    tx_xy, rx_xy = np.asarray(tx_xy, dtype=float), np.asarray(rx_xy, dtype=float)
    tx_h, rx_h = np.asarray(tx_heading, dtype=float), np.asarray(rx_heading, dtype=float)
    shape = np.broadcast_shapes(tx_xy.shape[:-1], rx_xy.shape[:-1], tx_h.shape, rx_h.shape)
    tx_xy = np.broadcast_to(tx_xy, shape + (2,)).reshape(-1, 2)
    rx_xy = np.broadcast_to(rx_xy, shape + (2,)).reshape(-1, 2)
    tx_h = np.broadcast_to(tx_h, shape).reshape(-1)
    rx_h = np.broadcast_to(rx_h, shape).reshape(-1)
    d = tx_xy - rx_xy
    c, s = np.cos(rx_h), np.sin(rx_h)
    rel = np.stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]], axis=-1)
    g = pair_gains(rel, wrap_angle(tx_h - rx_h), platform)  # (P, n_d, n_e)
    y = gain_to_intensity(g.sum(axis=-1), platform)
    return y.reshape(shape + (platform.n_detectors,))


def adc(
    y: np.ndarray,
    rng: np.random.Generator,
    m_max: float | np.ndarray = M_MAX,
    m_min: float = M_MIN,
    noise_var: float = NOISE_VAR,
    m_sup: int = M_SUP,
    intensity_sigma: float = 0.0,
) -> np.ndarray:
    """12-bit ADC measurement of intensity y [T20 Eqs. (20)-(22)].

    ``m = floor((m_max - m_min)(1 - min(1, y + n_j)) + m_min + n_m)`` clipped to [0, m_sup], with
    ``n_m ~ N(0, noise_var)`` and ``n_j ~ N(0, intensity_sigma^2)`` (0 by default, see module doc).

    Args:
        y: intensity (any shape), dimensionless.
        rng: random generator for the noise.
        m_max: ambient value (counts), scalar or broadcastable to y (per-robot ambient light).

    Returns:
        int32 array of counts, same shape as y.
    """
    y = np.asarray(y, dtype=float)
    if intensity_sigma > 0:
        y = y + rng.normal(0.0, intensity_sigma, size=y.shape)
    y = np.minimum(y, 1.0)
    m = (np.asarray(m_max) - m_min) * (1.0 - y) + m_min
    if noise_var > 0:
        m = m + rng.normal(0.0, np.sqrt(noise_var), size=y.shape)
    return np.clip(np.floor(m), 0, m_sup).astype(np.int32)


def detector_response(v: np.ndarray, y: np.ndarray, slot_s: float, c: float, b: float) -> np.ndarray:
    """Detector level after one bit slot of ``slot_s`` seconds at constant intensity ``y`` (module docstring).

    Exact solution of ``dv/dt = (y - v)(v + b)/c`` over the slot: with ``u0 = v + b`` and ``Y = y + b``,
    ``v' = Y u0 / (u0 + (Y - u0) exp(-Y slot_s / c)) - b`` (``exp``: :func:`swarm_envs.sim._vecmath.exp_array`,
    within 1 ulp of the C library's). ``y`` is clipped to [0, 1] (no negative
    photocurrent); a dark detector whose level has decayed below DARK_LEVEL is set to exactly 0. ``c <= 0``
    returns the instantaneous level ``clip(y, 0, 1)``. Same arithmetic as the compiled slot loop.
    """
    y = np.clip(np.asarray(y, dtype=float), 0.0, 1.0)
    if c <= 0:
        return y
    v = np.asarray(v, dtype=float)
    kt = slot_s / c
    Y = y + b
    u0 = v + b
    E = exp_array(-Y * kt)  # the library's exp (swarm_envs.sim._vecmath), as the compiled slot loop
    out = Y * u0 / (u0 + (Y - u0) * E) - b
    return np.where((y == 0.0) & ((out < DARK_LEVEL) | (v == 0.0)), 0.0, out)
