"""r-one bearing-only sensor: sector bearing and neighbour orientation [L Sec. 3.2.1, 3.2.3; docs/design.md#bearing-only-sensing].

The r-one has 8 IR receivers at ``22.5 + 45 k`` degrees, each seeing a 68-degree arc; the overlaps form 16
sectors, so the bearing resolution is 22.5 degrees [L Fig. 3.9]. The firmware keeps the *longest
contiguous run* of receivers that heard the message (indices taken cyclically, so receivers 7 and 0 are
adjacent) and reports the angle of the sum of their unit vectors: one receiver gives its axis, two give
the midpoint of their axes, three give the middle axis, and so on.

The neighbour's orientation comes from the indices of its 8 transmitters (at ``45 k`` degrees; every
message carries the index of the transmitter that sent it [L Sec. 3.2.3, "encoded orientation bit"]). Each
transmitter lights its outward half-plane (:class:`swarm_envs.ir.models.RoneIR`), so in the far field a
receiver is reached by 4 adjacent transmitters (5 on a boundary): a 45-degree orientation resolution. Close
up, the receivers' 68-degree arcs select different emitters on the neighbour's perimeter (facing at 14 cm,
the two lit receivers hear transmitters 1 and 7 but not 0), so the heard indices can have gaps; the rule
(ours) takes the smallest cyclic run of transmitters containing all heard ones (:func:`cover_mask`) and
reports the angle of the sum of their unit vectors. The transmitter run gives the direction from the neighbour w back to the receiver u *in w's frame*,
an estimate of ``theta_w(u)``; the neighbour's heading in u's frame is then
``psi = theta_u(w) + pi - theta_w(u)`` (the reciprocal-bearing identity, cf. [F14 Eq. (10)]).

Choices the thesis does not state (ours): the transmitter rule above; when two runs are equally long, the
run that starts at the lowest index wins; a mask with all 8 receivers lit has no contiguous run with a defined
direction (the unit vectors sum to zero) and gives NaN, as does an empty mask.

Inputs come from the shared IR layer (:func:`swarm_envs.ir.layer.compute_links`): a receiver i "heard"
link p iff any emitter of the transmitter reaches it (``gains[p, i, :] > threshold``), and transmitter j
"was heard" iff any receiver got its light (``gains[p, :, j] > threshold``). The r-one gains are binary
(:class:`swarm_envs.ir.models.RoneIR`). Everything is vectorised over links through a 256-entry lookup table
indexed by the 8-bit mask.

Message-borne readings (:class:`MessageBearings`, docs/design.md#bearing-only-sensing): on the robot, a bearing and an orientation
exist only for a message that was received: the receivers whose own copy of the frame was clean give the
bearing and the transmitter indices encoded in their copies give the orientation [L Sec. 3.2.1, 3.2.3].
:class:`MessageBearings` measures them on the frames the SwarmCom receiver decoded
(:class:`swarm_envs.comm.deliveries.Deliveries`; a receiver's copy is lost where another robot's light reached
it during the frame, ``Deliveries.interference``), names the neighbour by the frame's decoded header
``origin`` (never the true id), and rebuilds each robot's readings every neighbour round from that round's
frames [L Sec. 3.2.2]. :func:`link_masks` gives the lit receivers / reached transmitters of one link,
nominal (from the IR layer's gains) or with the receiver-arc spread measured on the hardware
(``arc_range``, [L Sec. 3.2.1, Fig. 3.9(b)]: 63 to 74 degrees over 10 trials, mean 68).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from swarm_envs.sim.copies import CopyRandom
from swarm_envs.sim.platforms import Platform, get_platform
from swarm_envs.sensing.base import NeighbourReadings

__all__ = [
    "sector_bearing",
    "run_mask",
    "cover_mask",
    "sector_lut",
    "BearingReadings",
    "sense_bearings",
    "RONE_RX_ANGLES",
    "RONE_TX_ANGLES",
    "RONE_ARC_RANGE_DEG",
    "RONE_ARC_MEAN_DEG",
    "arc_widths_deg",
    "link_masks",
    "draw_half_arcs",
    "pair_half_arcs",
    "MessageBearings",
]

RONE_RX_ANGLES = np.deg2rad(22.5 + 45.0 * np.arange(8))  # receiver axes [L Sec. 3.2.1]
RONE_TX_ANGLES = np.deg2rad(45.0 * np.arange(8))  # transmitter axes
#: measured spread of a receiver's detection arc (deg) [L Sec. 3.2.1, Fig. 3.9(b)]: "varies from 63 to 74
#: with a mean of 68 over 10 trials", the shield's "geometric tolerances"; the hardware bearing-noise model
#: gives every robot's receivers and transmitters their own arcs from it (MessageBearings)
RONE_ARC_RANGE_DEG = (63.0, 74.0)
#: the measured mean arc (deg) [L Sec. 3.2.1, Fig. 3.9(b)]: "a mean of 68"
RONE_ARC_MEAN_DEG = 68.0


def arc_widths_deg(u: np.ndarray, arc_range: tuple[float, float], mean: float | None = None) -> np.ndarray:
    """Arc widths (deg) from uniform [0, 1) draws ``u``: with ``mean`` None uniform on ``arc_range``; else the
    triangular law on ``arc_range`` with that mean (mode ``3 mean - min - max``), the law that has the
    thesis's three reported numbers, 63 / 74 / mean 68 [L Sec. 3.2.1], as its minimum, maximum and mean."""
    lo, hi = (float(a) for a in arc_range)
    u = np.asarray(u, dtype=float)
    if mean is None or hi <= lo:
        return lo + (hi - lo) * u
    mode = 3.0 * float(mean) - lo - hi
    if not lo <= mode <= hi:
        raise ValueError(f"an arc mean of {mean} deg needs a triangular mode in {arc_range}, got {mode}")
    fc = (mode - lo) / (hi - lo)
    left = lo + np.sqrt(u * (hi - lo) * (mode - lo))
    right = hi - np.sqrt((1.0 - u) * (hi - lo) * (hi - mode))
    return np.where(u < fc, left, right)


def run_mask(mask: int, n: int = 8) -> int:
    """The longest cyclic run of set bits of ``mask`` (n bits) as a mask; ties -> lowest start index.

    ``0`` for an empty mask; the full mask for all n bits set.
    """
    mask = int(mask) & ((1 << n) - 1)
    if mask == 0:
        return 0
    if mask == (1 << n) - 1:
        return mask
    bits = [(mask >> i) & 1 for i in range(n)]
    best_start, best_len = -1, 0
    for s in range(n):
        if bits[s] and not bits[(s - 1) % n]:  # a run starts here
            length = 0
            while bits[(s + length) % n] and length < n:
                length += 1
            if length > best_len:
                best_start, best_len = s, length
    out = 0
    for t in range(best_len):
        out |= 1 << ((best_start + t) % n)
    return out


def cover_mask(mask: int, n: int = 8) -> int:
    """The smallest cyclic run of channels that contains every set bit of ``mask`` (n bits), as a mask: all
    channels but the longest cyclic run of clear bits (ties -> the clear run starting at the lowest index).

    ``0`` for an empty mask; the full mask for all n bits set.
    """
    mask = int(mask) & ((1 << n) - 1)
    full = (1 << n) - 1
    if mask in (0, full):
        return mask
    return full & ~run_mask(full & ~mask, n)


@lru_cache(maxsize=16)
def _lut(angles_key: tuple[float, ...], cover: bool = False) -> np.ndarray:
    angles = np.asarray(angles_key)
    n = len(angles)
    lut = np.full(1 << n, np.nan)
    ux, uy = np.cos(angles), np.sin(angles)
    for m in range(1, 1 << n):
        if m == (1 << n) - 1:
            continue  # all receivers: no direction
        r = cover_mask(m, n) if cover else run_mask(m, n)
        if r == (1 << n) - 1:
            continue
        sel = np.array([(r >> i) & 1 for i in range(n)], dtype=bool)
        lut[m] = np.arctan2(uy[sel].sum(), ux[sel].sum())
    lut.setflags(write=False)
    return lut


def sector_lut(axis_angles: np.ndarray | None = None, cover: bool = False) -> np.ndarray:
    """The lookup table ``(2**n,)`` mask -> reported angle (rad, NaN for no reading).

    axis_angles: (n,) channel axes (rad), bit i of a mask = channel i; default the r-one receivers.
    cover: use the smallest cyclic run containing every heard channel (:func:`cover_mask`, the transmitter
    rule) instead of the longest contiguous run (:func:`run_mask`, the receiver rule).
    """
    a = RONE_RX_ANGLES if axis_angles is None else np.asarray(axis_angles, dtype=float)
    return _lut(tuple(float(x) for x in a), bool(cover))


def sector_bearing(mask_bits: np.ndarray | int, axis_angles: np.ndarray | None = None, cover: bool = False) -> np.ndarray:
    """Firmware sector rule [L Sec. 3.2.1]: angle (rad, (-pi, pi]) of the sum of the unit vectors of the
    longest contiguous (cyclic) run of channels in ``mask_bits`` (bit i = channel i heard); with ``cover``
    of the smallest cyclic run containing them all (the transmitter rule, module doc).

    Args:
        mask_bits: int or int array of channel bitmasks.
        axis_angles: channel axes (rad); default the r-one receivers at 22.5 + 45 k degrees. Pass
            :data:`RONE_TX_ANGLES` and ``cover=True`` for the transmitter (orientation) rule.
        cover: see above.

    Returns: float array of the same shape (NaN where the mask is empty or the run is all channels).
    """
    lut = sector_lut(axis_angles, cover)
    return lut[np.asarray(mask_bits, dtype=np.int64)]


@dataclass
class BearingReadings:
    """Bearing-only readings, one per IR link (P links).

    Attributes:
        rx, tx: (P,) int receiving / transmitting robot.
        bearing: (P,) sector bearing theta_rx(tx) (rad), NaN where no receiver heard.
        tx_bearing: (P,) sector estimate of theta_tx(rx) from the heard transmitter indices (rad).
        heading: (P,) tx's orientation in rx's frame, ``bearing + pi - tx_bearing`` (rad, wrapped).
        rx_mask, tx_mask: (P,) uint8 bitmasks of the receivers that heard / transmitters heard.
        valid: (P,) bool, bearing available.
    """

    rx: np.ndarray
    tx: np.ndarray
    bearing: np.ndarray
    tx_bearing: np.ndarray
    heading: np.ndarray
    rx_mask: np.ndarray
    tx_mask: np.ndarray
    valid: np.ndarray

    def __len__(self) -> int:
        return int(self.rx.shape[0])


def _bits_to_mask(heard: np.ndarray) -> np.ndarray:
    """(P, n) bool -> (P,) int mask, bit i = column i."""
    n = heard.shape[-1]
    return (heard.astype(np.int64) << np.arange(n, dtype=np.int64)).sum(-1)


def _readings(rx: np.ndarray, tx: np.ndarray, rx_mask: np.ndarray, tx_mask: np.ndarray, platform: Platform) -> BearingReadings:
    """Firmware rule on the masks: sector bearing, transmitter bearing and the neighbour's heading."""
    bearing = sector_bearing(rx_mask, platform.detector_directions)
    tx_bearing = sector_bearing(tx_mask, platform.emitter_directions, cover=True)
    heading = np.pi - np.mod(np.pi - (bearing + np.pi - tx_bearing), 2.0 * np.pi)
    return BearingReadings(
        rx=np.asarray(rx),
        tx=np.asarray(tx),
        bearing=bearing,
        tx_bearing=tx_bearing,
        heading=heading,
        rx_mask=np.asarray(rx_mask).astype(np.uint16),
        tx_mask=np.asarray(tx_mask).astype(np.uint16),
        valid=np.isfinite(bearing),
    )


def link_masks(
    links,
    platform: Platform | str = "rone",
    rows: np.ndarray | None = None,
    half_arcs: np.ndarray | None = None,
    threshold: float = 0.0,
) -> tuple[np.ndarray, np.ndarray]:
    """Receivers lit and transmitters heard on links ``rows`` of this step (bitmasks, bit i = channel i).

    Args:
        links: :class:`swarm_envs.ir.links.IRLinks` of the step.
        platform: the robots' platform.
        rows: (R,) link indices (default all links).
        half_arcs: None for the nominal masks (``gains > threshold``); else (R, n_d + n_e) half-widths (rad)
            of each receiver's arc and each transmitter's emission angle for that reading (r-one binary model,
            :class:`swarm_envs.ir.models.RoneIR`): the masks are recomputed from the link's emitter-detector
            angles (:func:`swarm_envs.ir.layer.pair_geometry`), range and this step's per-ray occlusion.

    Returns: ``(rx_mask, tx_mask)``, (R,) int each.
    """
    platform = get_platform(platform)
    rows = np.arange(len(links.rx)) if rows is None else np.asarray(rows, dtype=np.int64)
    if half_arcs is None:
        g = np.asarray(links.gains, dtype=float).reshape(-1, platform.n_detectors, platform.n_emitters)[rows] > threshold
    else:
        g = _link_hits(links, platform, rows, half_arcs)
    return _bits_to_mask(g.any(axis=2)), _bits_to_mask(g.any(axis=1))


def sense_bearings(
    links, platform: Platform | str = "rone", threshold: float = 0.0, half_arcs: np.ndarray | None = None
) -> BearingReadings:
    """Sector bearings and orientations for every link [L Sec. 3.2.1, 3.2.3; docs/design.md#bearing-only-sensing].

    The nominal, per-link geometry of the sensor (what a receiver *would* measure on a message from each
    linked neighbour); the env's r-one readings are measured on decoded frames only (:class:`MessageBearings`).

    Args:
        links: :class:`swarm_envs.ir.links.IRLinks` (uses ``rx``, ``tx``, ``gains (P, n_d, n_e)``).
        platform: platform whose detector / emitter axes define the sectors (the r-one by default; any
            platform with at most 16 channels works, e.g. the Droplet's 6 for a coarse ablation).
        threshold: a receiver hears / a transmitter is heard where the gain exceeds this (the r-one's
            gains are 0/1).
        half_arcs: optional (P, n_d + n_e) receiver-arc / transmitter-emission half-widths (rad) per link, the
            hardware-noise model (:func:`link_masks`); None = the IR layer's nominal gains.

    Returns: :class:`BearingReadings` (vectorised, no loop over links).
    """
    platform = get_platform(platform)
    rx_mask, tx_mask = link_masks(links, platform, half_arcs=half_arcs, threshold=threshold)
    return _readings(links.rx, links.tx, rx_mask, tx_mask, platform)


def draw_half_arcs(
    rng: np.random.Generator, n: int, platform: Platform | str = "rone", arc_range: tuple[float, float] = RONE_ARC_RANGE_DEG,
    arc_mean: float | None = RONE_ARC_MEAN_DEG,
) -> np.ndarray:
    """(n, n_d + n_e) half-widths (rad) of receiver arcs and transmitter emission angles: the receivers' drawn
    from ``arc_range`` with mean ``arc_mean`` (deg, :func:`arc_widths_deg`; default the r-one's measured 63-74
    degrees, mean 68 [L Sec. 3.2.1, Fig. 3.9(b)], the receiver shield's tolerances), the transmitters' the
    model's nominal half-plane (:class:`swarm_envs.ir.models.RoneIR`; the thesis measures no transmitter
    spread): one row per robot (its hardware, :func:`pair_half_arcs`) or per reading."""
    platform = get_platform(platform)
    u = rng.random((int(n), platform.n_detectors))
    rx = 0.5 * np.deg2rad(arc_widths_deg(u, arc_range, arc_mean))
    tx_half = float(getattr(platform.ir_model, "emitter_half_arc", 0.5 * np.pi))
    return np.concatenate([rx, np.full((int(n), platform.n_emitters), tx_half)], axis=1)


def pair_half_arcs(robot_arcs: np.ndarray, rx: np.ndarray, tx: np.ndarray, platform: Platform | str = "rone") -> np.ndarray:
    """(P, n_d + n_e) half-widths (rad) for links ``rx[p] <- tx[p]``: the receiver's own detector arcs and the
    transmitter's own emission angles, from per-robot arcs ``robot_arcs`` (N, n_d + n_e) (:func:`draw_half_arcs`
    with one row per robot)."""
    platform = get_platform(platform)
    nd = platform.n_detectors
    robot_arcs = np.asarray(robot_arcs, dtype=float)
    rx, tx = np.asarray(rx, dtype=np.int64), np.asarray(tx, dtype=np.int64)
    return np.concatenate([robot_arcs[rx, :nd], robot_arcs[tx, nd:]], axis=1)


_TABLE_FIELDS = ("rx", "tx", "bearing", "tx_bearing", "heading", "time")


def _empty_table() -> dict[str, np.ndarray]:
    return {f: np.zeros(0, np.int64 if f in ("rx", "tx", "time") else float) for f in _TABLE_FIELDS}


def _link_hits(links, platform: Platform, rows: np.ndarray, half_arcs: np.ndarray | None) -> np.ndarray:
    """(R, n_d, n_e) bool: detector d of the receiver hears emitter e of the transmitter on links ``rows``
    (:func:`link_masks`)."""
    n_d, n_e = platform.n_detectors, platform.n_emitters
    if half_arcs is None:
        return np.asarray(links.gains, dtype=float).reshape(-1, n_d, n_e)[rows] > 0.0
    from swarm_envs.ir.layer import pair_geometry
    from swarm_envs.ir.links import IRLinks

    half_arcs = np.asarray(half_arcs, dtype=float).reshape(rows.size, n_d + n_e)
    sub = IRLinks(
        links.rx[rows], links.tx[rows], links.distance[rows], links.rel_position[rows], links.rel_heading[rows],
        links.gains[rows], links.n_robots,
        None if links.occluders is None else (*links.occluders[:2], links.occluders[2][rows]),
    )
    dist, det_ang, em_ang = pair_geometry(sub.rel_position, sub.rel_heading, platform)
    max_range = float(getattr(platform.ir_model, "max_range", platform.ir_range))
    return (
        (np.abs(det_ang) <= half_arcs[:, :n_d, None])
        & (np.abs(em_ang) <= half_arcs[:, None, n_d:])
        & (dist <= max_range)
        & (sub.distance <= platform.ir_range)[:, None, None]
        & sub.ray_clear(platform)
    )


class MessageBearings:
    """Message-borne sector bearings and orientations of neighbours [L Sec. 3.2.1-3.2.3; docs/design.md#bearing-only-sensing].

    Each decoded frame (any kind: on the r-one every message carries the transmitter's encoded orientation
    bit [L Sec. 3.2.3, Table 3.3]) is a measurement by its receiver of the robot its header names
    (``Deliveries.origin``, the decoded id, right or wrong). Whose light it was is physics,
    ``Deliveries.transmitter`` (the robot whose start symbol was detected) and this step's IR link of that
    robot. A frame started by noise (``transmitter = -1``), whose light no longer reaches the receiver, or
    whose origin is not a robot of the receiver's env copy (or the receiver itself) measures nothing.

    Per-receiver copies [L Sec. 3.2.1]: the r-one decodes the frame on each of its 8 receivers separately
    and a receiver counts only if its own copy passes the CRC, so a receiver that another robot's light
    reached in a slot where the frame's own light was off (``Deliveries.interference``: that light turned a
    dark bit on) drops out. The bearing comes from the lit receivers whose copies were clean, the
    orientation from the transmitters whose light reached one of those receivers; a frame without a clean
    lit receiver, or whose clean receivers give no direction (none or all 8), measures nothing.

    Rounds [L Sec. 3.2.2]: each robot's neighbour round starts at its beacon step (every ``period`` steps
    at its own random phase, :attr:`phase`; the env sets it to the exchange's broadcast phase when the
    exchange is the beacon). "When a new round begins, each robot clears all prior neighbor information":
    at the start of a robot's round the measurements of the round that just ended become its readings
    (:meth:`readings`, the newest per decoded sender, with its age in steps) and everything older is
    dropped; the new round's measurements are collected apart (:attr:`fresh` holds this step's) until the
    following round starts. A neighbour is thus in a robot's readings for exactly the round after one in which
    a frame of it was measured: losses, collisions and range reach the readings, and no reading is older
    than 2 rounds less a step.

    Hardware noise (``arc_range``, default on in the env's ``bearing_noise``): each robot's 8 receiver arcs
    are its own, drawn from ``arc_range`` (with mean ``arc_mean``,
    :func:`arc_widths_deg`) when its env copy is reset
    (deg; [L Sec. 3.2.1, Fig. 3.9(b)]: the arc "varies from 63 to 74 with a mean of 68 over 10 trials", a
    "physical model of the IR receivers' geometric tolerances", i.e. of the shield, fixed on a robot)
    instead of the nominal 68 degrees, so directions near a sector boundary fall into the neighbouring
    sector, the same way on every frame of that pair in that geometry. The thesis's bearing and orientation
    error histogram [L Fig. 3.13(a)] has no numbers in the text we have, and of the other source it names,
    "the transmitter power" [L Sec. 3.2.1], it gives no magnitude; the arc spread is the only measured
    hardware figure, so it is the whole noise model (assumptions: the triangular law, the one with the
    reported minimum, maximum and mean, and arcs symmetric about the channel axis; the transmitters keep
    RoneIR's nominal half-plane, the spread being the receiver shield's).

    Beacons (:meth:`send_beacons`): every robot broadcasts a header-only frame (its id, no payload) as
    system traffic at the start of each of its rounds, for stacks whose bearing exchange does not already
    broadcast (an exchange in ``"network"`` mode is the beacon: [L Sec. 3.2.2] one message per robot per
    round).

    Args:
        platform: the robots' platform (sector axes from its detectors / emitters).
        n_robots: robots per env copy.
        rng: generator (or :class:`swarm_envs.sim.copies.CopyRandom`, one per copy) for round phases and noise.
        n_copies: env copies (rows copy-major).
        period: round (beacon) period (steps).
        arc_range: (min, max) arc width (deg) for the noise model, or None (nominal gains, noiseless).
        arc_mean: mean arc width (deg) of the triangular law on ``arc_range`` (:func:`arc_widths_deg`), or
            None for the uniform law.
    """

    def __init__(
        self,
        platform: Platform | str,
        n_robots: int,
        rng: np.random.Generator | CopyRandom | None = None,
        n_copies: int = 1,
        period: int = 24,
        arc_range: tuple[float, float] | None = None,
        arc_mean: float | None = None,
    ) -> None:
        self.platform = get_platform(platform)
        if int(period) < 1:
            raise ValueError(f"need period >= 1, got {period}")
        if arc_range is not None:
            lo, hi = (float(a) for a in arc_range)
            if not (0.0 < lo <= hi < 360.0):
                raise ValueError(f"arc_range must be (min, max) degrees with 0 < min <= max < 360, got {arc_range!r}")
            arc_range = (lo, hi)
        self.arc_range = arc_range
        self.arc_mean = None if arc_mean is None else float(arc_mean)
        if arc_range is not None:
            arc_widths_deg(np.zeros(1), arc_range, self.arc_mean)  # checks the mean fits the range
        self.copy_size = int(n_robots)
        self.n_copies = int(n_copies)
        self.n = self.copy_size * self.n_copies
        self.copy_of = np.repeat(np.arange(self.n_copies), self.copy_size)
        self.offset = self.copy_of * self.copy_size
        self.period = int(period)
        rng = rng if rng is not None else np.random.default_rng()
        self.rng = rng if isinstance(rng, CopyRandom) else CopyRandom([rng] * self.n_copies)
        self.t = 0  # steps since construction: ages are differences, so copies need no own clock
        self.clock = np.zeros(self.n_copies, np.int64)  # steps since each copy's reset (round schedule)
        self.phase = np.zeros(self.n, np.int64)
        #: (N, n_d + n_e) each robot's receiver-arc and transmitter-cone half-widths (rad), drawn at reset
        #: (None: the nominal gains)
        self.half_arcs = None if arc_range is None else np.zeros((self.n, self.platform.n_detectors + self.platform.n_emitters))
        self.stats = {"measured": 0, "unmeasured": 0, "rejected": 0, "interfered": 0}
        self.fill = _empty_table()  # the current round's measurements, newest per (receiver, decoded sender)
        self.pub = _empty_table()  # the last complete round's: the readings
        self.fresh = NeighbourReadings()
        self.reset()

    def reset(self, copies: np.ndarray | None = None, rngs: list[np.random.Generator] | None = None) -> None:
        """Forget the readings of env ``copies`` (all if None), give them the generators ``rngs`` and draw
        new round phases (and, with ``arc_range``, their robots' arcs) from them."""
        copies = np.arange(self.n_copies) if copies is None else np.asarray(copies, dtype=np.int64).reshape(-1)
        if rngs is not None:
            for b, g in zip(copies, rngs):
                self.rng.generators[b] = g
        for name in ("fill", "pub"):
            tab = getattr(self, name)
            keep = ~np.isin(self.copy_of[tab["rx"]], copies)
            setattr(self, name, {f: v[keep] for f, v in tab.items()})
        rows = np.flatnonzero(np.isin(self.copy_of, copies))
        self.clock[copies] = 0
        self.phase[rows] = self.rng.integers(0, self.period, self.copy_of[rows])
        if self.half_arcs is not None:
            u = self.rng.random(self.copy_of[rows], (self.half_arcs.shape[1],))
            self.half_arcs[rows] = 0.5 * np.deg2rad(arc_widths_deg(u, self.arc_range, self.arc_mean))

    def round_starts(self) -> np.ndarray:
        """(N,) bool: the robots whose round starts this step (their beacon step)."""
        return (self.clock[self.copy_of] - self.phase) % self.period == 0

    # ------------------------------------------------------------------ beacons
    def send_beacons(self, network, kind: str = "bearing_beacon") -> int:
        """Queue a header-only beacon for every robot whose round starts this step (``network.queue_system``);
        returns the number queued. Call before ``network.step``."""
        due = np.flatnonzero(self.round_starts())
        if due.size:
            network.queue_system(due, np.zeros((due.size, 0), bool), kind)
        return int(due.size)

    # ------------------------------------------------------------------ measurement
    def update(self, deliveries, links) -> int:
        """Measure on this step's decoded frames (class docstring) into the current round's table; returns
        the number of readings taken.

        Args:
            deliveries: :class:`swarm_envs.comm.deliveries.Deliveries` of this step (``receiver``, ``origin``,
                ``transmitter``, and ``interference`` if the channel reports it; none means no receiver's
                copy was corrupted).
            links: the :class:`swarm_envs.ir.links.IRLinks` the network stepped with.
        """
        if deliveries is None or len(deliveries.receiver) == 0:
            return 0
        if deliveries.transmitter is None:
            raise ValueError("MessageBearings needs Deliveries.transmitter (whose light lit the receivers)")
        recv = np.asarray(deliveries.receiver, np.int64)
        origin = np.asarray(deliveries.origin, np.int64)
        light = np.asarray(deliveries.transmitter, np.int64)
        interference = getattr(deliveries, "interference", None)
        interference = np.zeros(recv.size, np.int64) if interference is None else np.asarray(interference, np.int64)
        base = self.offset[recv]
        named = (origin >= base) & (origin < base + self.copy_size) & (origin != recv)
        self.stats["rejected"] += int((~named).sum())
        # the link (receiver <- transmitter) of this step carrying the light
        lkey = np.asarray(links.rx, np.int64) * self.n + np.asarray(links.tx, np.int64)
        lorder = np.argsort(lkey, kind="stable")
        skey = lkey[lorder]
        key = recv * self.n + np.maximum(light, 0)
        pos = np.minimum(np.searchsorted(skey, key), max(skey.size - 1, 0))
        lit = named & (light >= 0) & (skey.size > 0) & (skey[pos] == key if skey.size else False)
        sel = np.flatnonzero(lit)
        sel = sel[np.argsort(self.copy_of[recv[sel]], kind="stable")]  # rows grouped by copy, canonical order within
        rows = lorder[pos[sel]]
        half = None if self.half_arcs is None else pair_half_arcs(self.half_arcs, recv[sel], light[sel], self.platform)
        hits = _link_hits(links, self.platform, rows, half)
        clean = ((interference[sel][:, None] >> np.arange(self.platform.n_detectors)) & 1) == 0
        heard = hits.any(axis=2)
        self.stats["interfered"] += int((heard & ~clean).any(axis=1).sum())
        hits = hits & clean[:, :, None]  # only the receivers whose own copy of the frame was clean
        r = _readings(recv[sel], origin[sel], _bits_to_mask(hits.any(axis=2)), _bits_to_mask(hits.any(axis=1)), self.platform)
        ok = r.valid
        self.stats["measured"] += int(ok.sum())
        self.stats["unmeasured"] += int(named.sum() - ok.sum())
        if not ok.any():
            return 0
        # newest measurement per (receiver, decoded sender): old entries first, this step's in arrival order
        f = self.fill
        rx = np.concatenate([f["rx"], r.rx[ok]])
        tx = np.concatenate([f["tx"], r.tx[ok]])
        key = rx * self.n + tx
        _, last = np.unique(key[::-1], return_index=True)
        take = key.size - 1 - last  # sorted by key, i.e. by (receiver, sender)
        new = {"rx": r.rx[ok], "tx": r.tx[ok], "bearing": r.bearing[ok], "tx_bearing": r.tx_bearing[ok], "heading": r.heading[ok],
               "time": np.full(int(ok.sum()), self.t, np.int64)}  # fmt: skip
        self.fill = {name: np.concatenate([f[name], new[name]])[take] for name in _TABLE_FIELDS}
        return int(ok.sum())

    def _roll(self, starts: np.ndarray) -> None:
        """Start a new round for robots ``starts`` (N,) bool: their current round's measurements become their
        readings, the older readings are dropped."""
        if not starts.any():
            return
        moved = starts[self.fill["rx"]]
        kept = ~starts[self.pub["rx"]]
        pub = {f: np.concatenate([self.pub[f][kept], self.fill[f][moved]]) for f in _TABLE_FIELDS}
        order = np.argsort(pub["rx"] * self.n + pub["tx"], kind="stable")
        self.pub = {f: v[order] for f, v in pub.items()}
        self.fill = {f: v[~moved] for f, v in self.fill.items()}

    def _as_readings(self, tab: dict[str, np.ndarray]) -> NeighbourReadings:
        return NeighbourReadings(
            tab["rx"].copy(), tab["tx"].copy(), np.zeros(tab["rx"].size), tab["bearing"].copy(), tab["heading"].copy(),
            (self.t - tab["time"]).astype(float),
        )

    def readings(self) -> NeighbourReadings:
        """The readings: each robot's measurements of its last complete round, one per (receiver, decoded
        sender), sorted by both; range 0 (bearing-only), age in steps since the frame."""
        return self._as_readings(self.pub)

    def step(self, deliveries, links) -> NeighbourReadings:
        """Start the rounds due this step, measure this step's frames, and return the readings (:meth:`readings`);
        :attr:`fresh` then holds the measurements of this step's frames (age 0). Advances the clocks."""
        self._roll(self.round_starts())
        self.update(deliveries, links)
        out = self.readings()
        now = self.fill["time"] == self.t
        self.fresh = self._as_readings({f: v[now] for f, v in self.fill.items()})
        self.t += 1
        self.clock += 1
        return out
