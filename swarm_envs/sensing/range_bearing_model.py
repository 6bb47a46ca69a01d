"""The range & bearing measurement [F14]: the emitter x sensor brightness matrix of a neighbour (Eqs. (1)-(20)),
its measurement with ADC noise at the power ladder's largest unsaturated power, and the range and bearing
estimated from it (Eqs. (21)-(27))."""

from __future__ import annotations
import numpy as np
from swarm_envs.sim.copies import CopyRandom, CopyStream, normal_noise
from swarm_envs.sim.geometry import wrap_angle
from swarm_envs.ir.layer import pair_gains
from swarm_envs.sim.platforms import Platform, get_platform
from swarm_envs.sensing.range_bearing_kernels import adc_pass
from swarm_envs.sensing.numpy_sums import sum_last

__all__ = ["POWER_LADDER", "amplitude_model", "brightness", "measure", "estimate", "read"]


#: Emitter power factors tried in order when the full-power reading saturates (docs/design.md#range-and-bearing). Halving steps
#: down to 1/256: two Droplets one radius apart (R = 6.6 cm) give up to ~31000 model counts at full
#: power, so 1/256 is needed to stay below 255 (the Droplet sets LED current with a 7-bit digital
#: potentiometer [F14 Sec. III], so a ~1/100 dynamic range is plausible).
POWER_LADDER: tuple[float, ...] = tuple(2.0**-k for k in range(9))


def amplitude_model(platform: Platform):
    """The platform's IR model with an amplitude model (the Droplet's), or ValueError for a binary one."""
    model = platform.ir_model
    if not hasattr(model, "amplitude_inverse"):
        raise ValueError(
            f"platform {platform.name!r} has a binary IR model without an amplitude model: no range & "
            "bearing estimation (use the bearing-only sensor)"
        )
    return model


def brightness(rel_position: np.ndarray, rel_heading: np.ndarray, platform: Platform | str = "droplet") -> np.ndarray:
    """Noiseless full-power model brightness matrices (P, n, n) [F14 Eq. (4)].

    Args:
        rel_position: (P, 2) TX centre in the RX body frame (m).
        rel_heading: (P,) TX heading in the RX frame (rad).
        platform: platform of both robots.

    Returns:
        (P, n_detectors, n_emitters): rows = RX sensors i, cols = TX emitters j, channel k at the
        platform's k-th angle; in the platform model's units (ADC counts for the Droplet), before power
        selection, noise and clipping. Line of sight is assumed.
    """
    return pair_gains(rel_position, rel_heading, platform)


def measure(
    brightness: np.ndarray,
    rng: np.random.Generator | CopyRandom | CopyStream,
    sigma: float | None = None,
    platform: Platform | str = "droplet",
    ladder: tuple[float, ...] = POWER_LADDER,
    row_copy: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Simulated ADC reading of brightness matrices with power selection (docs/design.md#range-and-bearing).

    ``measured = clip(round(p * lambda * s + n), 0, adc_max) / s`` with n ~ N(0, sigma^2) counts i.i.d. per
    entry and s = ``model.adc_scale`` counts per gain unit (1 for the Droplet). A matrix *saturates* when
    any measured entry reaches ``adc_max`` (255 for the Droplet's 8-bit ADC); then the TX fires again
    (fresh noise) at the next power factor of ``ladder``, and the first non-saturated reading is kept (the
    last one if all saturate). The power is chosen per RX-TX pair, as in [F14]'s pairwise request.

    Args:
        brightness: (P, n_d, n_e) noiseless full-power brightness (model units).
        rng: random generator for the noise, or per-copy streams (:class:`swarm_envs.sim.copies.CopyRandom`, or a
            normal :class:`swarm_envs.sim.copies.CopyStream`)
            with ``row_copy`` (P,) the env copy of each matrix (sorted): each copy's noise then comes from its
            own stream, as in a single env.
        sigma: noise standard deviation in ADC counts; default the model's ``default_noise_sigma``.
        platform: platform (selects the ADC constants).
        ladder: decreasing power factors, starting with 1.
        row_copy: see ``rng``.

    Returns:
        measured (P, n_d, n_e) in model units *at the chosen power* (divide by p for the estimate, or pass
        ``power=p`` to :func:`estimate`), and p (P,).
    """
    platform = get_platform(platform)
    model = platform.ir_model
    sigma = float(model.default_noise_sigma if sigma is None else sigma)
    lam = np.asarray(brightness, dtype=float)
    scale, top = float(model.adc_scale), float(model.adc_max)
    P = lam.shape[0]
    out = np.empty_like(lam)
    power = np.full(P, float(ladder[-1]))
    todo = np.arange(P)
    flat = np.ascontiguousarray(lam).reshape(P, -1)
    for k, p in enumerate(ladder):
        if todo.size == 0:
            break
        shape = (todo.size, *lam.shape[1:])
        noise = normal_noise(rng, sigma, shape, None if row_copy is None else row_copy[todo]) if sigma > 0 else None
        # clip(round(p * lam * scale + noise), 0, top) and the saturation flags in one pass (kernels.adc_pass)
        empty = np.zeros((0, flat.shape[1]))
        counts, sat = adc_pass(flat, todo, empty if noise is None else noise.reshape(todo.size, -1), float(p), scale, top)
        counts = counts.reshape(shape)
        done = ~sat if k < len(ladder) - 1 else np.ones(todo.size, dtype=bool)
        out[todo[done]] = counts[done] / scale
        power[todo[done]] = p
        todo = todo[~done]
    return out, power


def estimate(
    brightness: np.ndarray,
    platform: Platform | str = "droplet",
    power: np.ndarray | None = None,
    refine: int = 1,
    model: object | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Range, bearing and heading from brightness matrices [F14 Sec. II], vectorised over P pairs.

    Steps ([F14 Sec. II]; docs/design.md#range-and-bearing), with b_i / b_j the unit axis vectors of RX sensor i and TX emitter j, d_i / e_j
    their positions in their own body frames (d_i = rho b_i on the Droplet):

    1. ``S_i = sum_j lambda_ij``, ``T_j = sum_i lambda_ij`` [Eqs. (5),(6)].
    2. bearing ``theta = angle(sum_i S_i b_i)`` [Eqs. (7),(8)].
    3. heading ``phi = theta + pi - angle(sum_j T_j b_j)`` [Eqs. (9),(10)]: ``tau`` points from TX to RX
       in TX's frame, i.e. along theta + pi in RX's frame (the PDF lost the minus sign).
    4. (i*, j*) = argmax lambda; with R -> infinity ``alpha = theta - angle(b_i*)``,
       ``beta = theta + pi - (phi + angle(b_j*))`` [Eqs. (13),(14)];
       ``r0 = A^-1(lambda / (S(alpha) E(beta)))``, ``R0 = r0 + |d_i*| + |e_j*|`` (= r0 + 2 rho)
       [Eqs. (15),(16)].
    5. ``refine`` times (paper: once): ``r_vec = R0 b(theta) + Rot(phi) e_j* - d_i*`` [Eq. (1)], its
       alpha, beta [Eqs. (11),(12)], ``r = A^-1(lambda / (S E))`` [Eq. (17)],
       ``R = || r unit(r_vec) + d_i* - Rot(phi) e_j* ||`` [Eq. (18)], R from the maximal pair.
    6. No reading (NaN) when the largest *raw* entry (lambda * power) is below the model's
       ``no_reading_floor`` (Droplet firmware: 7 counts).

    ``S(alpha) E(beta)`` is floored at 1e-3 so a badly estimated angle (e.g. beyond the e-puck's 90-degree
    cut-off) cannot divide by zero.

    Args:
        brightness: (P, n_d, n_e) measured (or noiseless) brightness in model units.
        platform: platform of both robots (geometry, sensor/emitter/amplitude models).
        power: optional (P,) power factors of the readings; brightness is divided by it.
        refine: number of refinement passes of step 5 (0 returns R0).
        model: IR model whose S, E, A^-1 invert the matrix (default the platform's; the Droplet's
            low-power near model is :class:`swarm_envs.ir.models.DropletLowPowerIR`).

    Returns:
        ranges (m), bearings (rad), headings (rad), each (P,), NaN where there is no reading.
    """
    platform = get_platform(platform)
    model = amplitude_model(platform) if model is None else model
    lam = np.asarray(brightness, dtype=float)
    if lam.ndim == 2:
        lam = lam[None]
    P = lam.shape[0]
    raw_max = lam.reshape(P, -1).max(axis=1) if P else np.zeros(0)
    if power is not None:
        power = np.broadcast_to(np.asarray(power, dtype=float), (P,))
        lam = lam / power[:, None, None]
    dd = platform.detector_directions
    ed = platform.emitter_directions
    dpos = platform.detector_positions
    epos = platform.emitter_positions

    S = sum_last(lam)  # (P, n_d) [Eq. (5)]
    T = sum_last(lam.transpose(0, 2, 1))  # (P, n_e) [Eq. (6)]
    theta = np.arctan2(S @ np.sin(dd), S @ np.cos(dd))  # [Eqs. (7),(8)]
    phi = wrap_angle(theta + np.pi - np.arctan2(T @ np.sin(ed), T @ np.cos(ed)))  # [Eqs. (9),(10)]

    flat = lam.reshape(P, -1).argmax(axis=1)
    i_star, j_star = np.divmod(flat, lam.shape[2])
    lam_max = lam.reshape(P, -1)[np.arange(P), flat]

    def ainv_m(alpha: np.ndarray, beta: np.ndarray) -> np.ndarray:
        se = np.maximum(model.sensor(alpha) * model.emitter(beta), 1e-3)
        return model.amplitude_inverse(lam_max / se) / 100.0  # model inverse is in cm

    # step 4: R -> infinity
    alpha = wrap_angle(theta - dd[i_star])  # [Eq. (13)]
    beta = wrap_angle(theta + np.pi - (phi + ed[j_star]))  # [Eq. (14)]
    r0 = ainv_m(alpha, beta)  # [Eq. (15)]
    R = r0 + np.hypot(*dpos[i_star].T) + np.hypot(*epos[j_star].T)  # [Eq. (16)]

    # step 5: refine with the current R [Eqs. (11),(12),(17),(18)]
    c, s = np.cos(phi), np.sin(phi)
    d_i = dpos[i_star]
    e_j = np.stack([c * epos[j_star, 0] - s * epos[j_star, 1], s * epos[j_star, 0] + c * epos[j_star, 1]], -1)
    u = np.stack([np.cos(theta), np.sin(theta)], -1)
    for _ in range(int(refine)):  # an infinite r (light below a fit's floor) gives NaN: no reading
        rvec = R[:, None] * u + e_j - d_i
        ang = np.arctan2(rvec[:, 1], rvec[:, 0])
        alpha = wrap_angle(ang - dd[i_star])
        beta = wrap_angle(ang + np.pi - (phi + ed[j_star]))
        r = ainv_m(alpha, beta)
        norm = np.maximum(np.hypot(rvec[:, 0], rvec[:, 1]), 1e-12)
        with np.errstate(invalid="ignore"):
            Rvec = r[:, None] * rvec / norm[:, None] + d_i - e_j
        R = np.hypot(Rvec[:, 0], Rvec[:, 1])

    none = ~(raw_max >= model.no_reading_floor)
    R = np.where(none, np.nan, R)
    theta = np.where(none, np.nan, theta)
    phi = np.where(none, np.nan, phi)
    return R, theta, phi


def read(
    brightness: np.ndarray,
    rel_position: np.ndarray,
    rel_heading: np.ndarray,
    rng: np.random.Generator | CopyRandom | CopyStream,
    sigma: float | None = None,
    platform: Platform | str = "droplet",
    ladder: tuple[float, ...] = POWER_LADDER,
    near_model: bool = False,
    row_copy: np.ndarray | None = None,
    low_brightness: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Measure and estimate P matrices with power control: (range m, bearing rad, heading rad, power).

    Default: :func:`measure` on the power ladder, then :func:`estimate` divided by the chosen power.
    ``near_model=True`` (Droplet firmware style): one full-power reading; a saturated one is measured
    again with the emitters at the firmware's low power (brightness from the pair geometry with
    :class:`swarm_envs.ir.models.DropletLowPowerIR`) and inverted with that low-power amplitude fit;
    its power is reported as NaN (a different fit, not a factor). ``rng``/``row_copy`` as in :func:`measure`.
    ``low_brightness`` (P, n, n): the low-power matrices to use instead (e.g. summed over colliding TXs);
    ``rel_position``/``rel_heading`` are then unused.
    """
    platform = get_platform(platform)
    if not near_model:
        meas, p = measure(brightness, rng, sigma, platform, ladder, row_copy)
        return (*estimate(meas, platform, power=p), p)
    from swarm_envs.ir.models import DropletLowPowerIR

    meas, p = measure(brightness, rng, sigma, platform, (1.0,), row_copy)
    R, th, ph = estimate(meas, platform)
    sat = np.flatnonzero(meas.reshape(len(meas), -1).max(axis=1) >= float(platform.ir_model.adc_max))
    if sat.size:
        low = DropletLowPowerIR(platform)
        if low_brightness is not None:
            lam = np.asarray(low_brightness)[sat]
        else:
            lam = pair_gains(np.asarray(rel_position)[sat], np.asarray(rel_heading)[sat], platform, model=low)
            lam = lam * (np.asarray(brightness)[sat] > 0)  # rays occluded at full power stay dark (the Droplet lights every clear ray)
        meas_low, _ = measure(lam, rng, sigma, platform, (1.0,), None if row_copy is None else row_copy[sat])
        R[sat], th[sat], ph[sat] = estimate(meas_low, platform, model=low)
        p = p.copy()
        p[sat] = np.nan
    return R, th, ph, p
