"""r-one bearing-only sensor: sector bearing and neighbour orientation [L Sec. 3.2.1, 3.2.3; SPEC 5.1].

The r-one has 8 IR receivers at ``22.5 + 45 k`` degrees, each seeing a 68-degree arc; the overlaps form 16
sectors, so the bearing resolution is 22.5 degrees [L Fig. 3.9]. The firmware keeps the *longest
contiguous run* of receivers that heard the message (indices taken cyclically, so receivers 7 and 0 are
adjacent) and reports the angle of the sum of their unit vectors: one receiver gives its axis, two give
the midpoint of their axes, three give the middle axis, and so on.

The neighbour's orientation uses the same rule on the indices of its 8 transmitters (at ``45 k`` degrees;
every message carries the index of the transmitter that sent it [L Sec. 3.2.3, "encoded orientation
bit"]). The transmitter run gives the direction from the neighbour w back to the receiver u *in w's frame*,
an estimate of ``theta_w(u)``; the neighbour's heading in u's frame is then
``psi = theta_u(w) + pi - theta_w(u)`` (the reciprocal-bearing identity, cf. [F14 Eq. (10)]).

Choices the thesis does not state (ours): when two runs are equally long, the run that starts at the
lowest receiver index wins; a mask with all 8 receivers lit has no contiguous run with a defined
direction (the unit vectors sum to zero) and gives NaN, as does an empty mask.

Inputs come from the shared IR layer (:func:`swarm_envs.ir.layer.compute_links`): a receiver i "heard"
link p iff any emitter of the transmitter reaches it (``gains[p, i, :] > threshold``), and transmitter j
"was heard" iff any receiver got its light (``gains[p, :, j] > threshold``). The r-one gains are binary
(:class:`swarm_envs.ir.models.RoneIR`). Everything is vectorised over links through a 256-entry lookup table
indexed by the 8-bit mask.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from swarm_envs.platforms import Platform, get_platform

__all__ = [
    "sector_bearing",
    "run_mask",
    "sector_lut",
    "BearingReadings",
    "sense_bearings",
    "RONE_RX_ANGLES",
    "RONE_TX_ANGLES",
]

RONE_RX_ANGLES = np.deg2rad(22.5 + 45.0 * np.arange(8))  # receiver axes [L Sec. 3.2.1]
RONE_TX_ANGLES = np.deg2rad(45.0 * np.arange(8))  # transmitter axes


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


@lru_cache(maxsize=8)
def _lut(angles_key: tuple[float, ...]) -> np.ndarray:
    angles = np.asarray(angles_key)
    n = len(angles)
    lut = np.full(1 << n, np.nan)
    ux, uy = np.cos(angles), np.sin(angles)
    for m in range(1, 1 << n):
        if m == (1 << n) - 1:
            continue  # all receivers: no direction
        r = run_mask(m, n)
        sel = np.array([(r >> i) & 1 for i in range(n)], dtype=bool)
        lut[m] = np.arctan2(uy[sel].sum(), ux[sel].sum())
    lut.setflags(write=False)
    return lut


def sector_lut(axis_angles: np.ndarray | None = None) -> np.ndarray:
    """The lookup table ``(2**n,)`` mask -> reported angle (rad, NaN for no reading).

    axis_angles: (n,) channel axes (rad), bit i of a mask = channel i; default the r-one receivers.
    """
    a = RONE_RX_ANGLES if axis_angles is None else np.asarray(axis_angles, dtype=float)
    return _lut(tuple(float(x) for x in a))


def sector_bearing(mask_bits: np.ndarray | int, axis_angles: np.ndarray | None = None) -> np.ndarray:
    """Firmware sector rule [L Sec. 3.2.1]: angle (rad, (-pi, pi]) of the sum of the unit vectors of the
    longest contiguous (cyclic) run of channels in ``mask_bits`` (bit i = channel i heard).

    Args:
        mask_bits: int or int array of channel bitmasks.
        axis_angles: channel axes (rad); default the r-one receivers at 22.5 + 45 k degrees. Pass
            :data:`RONE_TX_ANGLES` for the transmitter (orientation) rule.

    Returns: float array of the same shape (NaN where the mask is empty or full).
    """
    lut = sector_lut(axis_angles)
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


def sense_bearings(links, platform: Platform | str = "rone", threshold: float = 0.0) -> BearingReadings:
    """Sector bearings and orientations for every link [L Sec. 3.2.1, 3.2.3; SPEC 5.1].

    Args:
        links: :class:`swarm_envs.ir.layer.IRLinks` (uses ``rx``, ``tx``, ``gains (P, n_d, n_e)``).
        platform: platform whose detector / emitter axes define the sectors (the r-one by default; any
            platform with at most 16 channels works, e.g. the Droplet's 6 for a coarse ablation).
        threshold: a receiver hears / a transmitter is heard where the gain exceeds this (the r-one's
            gains are 0/1).

    Returns: :class:`BearingReadings` (vectorised, no loop over links).
    """
    platform = get_platform(platform)
    g = np.asarray(links.gains, dtype=float)
    if g.ndim != 3:
        g = g.reshape(-1, platform.n_detectors, platform.n_emitters)
    heard_rx = (g > threshold).any(axis=2)  # (P, n_d)
    heard_tx = (g > threshold).any(axis=1)  # (P, n_e)
    rx_mask = _bits_to_mask(heard_rx)
    tx_mask = _bits_to_mask(heard_tx)
    bearing = sector_bearing(rx_mask, platform.detector_directions)
    tx_bearing = sector_bearing(tx_mask, platform.emitter_directions)
    heading = np.pi - np.mod(np.pi - (bearing + np.pi - tx_bearing), 2.0 * np.pi)
    return BearingReadings(
        rx=np.asarray(links.rx),
        tx=np.asarray(links.tx),
        bearing=bearing,
        tx_bearing=tx_bearing,
        heading=heading,
        rx_mask=rx_mask.astype(np.uint16),
        tx_mask=tx_mask.astype(np.uint16),
        valid=np.isfinite(bearing),
    )
