"""The range & bearing request frames [F14 Sec. III]: each robot's 16-bit id with a CRC-16 as a frame, and the
ids a receiver decodes from the superposed frames of robots that fired together (bit by bit, with ADC noise)."""

from __future__ import annotations
import numpy as np
from swarm_envs.sim.copies import CopyRandom, CopyStream, normal_noise
from swarm_envs.sim.platforms import Platform, get_platform
from swarm_envs.sensing.range_bearing_kernels import FRAME_WORDS_MAX_GROUP, adc_bits, frame_words, pick_ids
from swarm_envs.sensing.numpy_sums import segment_sum

__all__ = ["ID_BITS", "CRC16", "NOT_HEARD", "CONFLICT", "id_frames", "decode_ids", "frame_words_numpy"]


#: Bits of a robot id in the ``rnb_r`` command header (the Droplet firmware's ``uint16_t`` sender id).
ID_BITS = 16

_CRC_BITS = 16


def _crc16_table() -> np.ndarray:
    """CRC-16 of every 16-bit id: avr-libc ``_crc16_update`` (poly 0xA001) over the low then high byte,
    init 0xFFFF (the Droplet firmware's header check)."""
    ids = np.arange(2**ID_BITS, dtype=np.uint32)
    crc = np.full(ids.size, 0xFFFF, dtype=np.uint32)
    for byte in (ids & 0xFF, ids >> 8):
        crc ^= byte
        for _ in range(8):
            crc = np.where(crc & 1, (crc >> 1) ^ 0xA001, crc >> 1)
    return crc.astype(np.int64)

_WEIGHTS = 1 << np.arange(ID_BITS, dtype=np.int64)

#: Decode outcomes of :func:`decode_ids` (besides a decoded id >= 0).
NOT_HEARD, CONFLICT = -1, -2

#: the CRC-16 of every ``ID_BITS``-bit robot id (indexed by id), the check an id frame carries
CRC16 = _crc16_table()


def id_frames(ids: np.ndarray) -> np.ndarray:
    """(K, 1 + 16 + 16) bool on-off-keyed frames of robot ids: start bit, id bits (LSB first), CRC-16 bits.

    Args:
        ids: (K,) ints in [0, 2**16) (a copy's own robot numbers).
    """
    ids = np.asarray(ids, dtype=np.int64).reshape(-1)
    if ids.size and (ids.min() < 0 or ids.max() >= 2**ID_BITS):
        raise ValueError(f"robot ids must be in [0, {2**ID_BITS}) to fit the {ID_BITS}-bit id field")
    bits = np.arange(ID_BITS)
    return np.concatenate(
        [np.ones((ids.size, 1), bool), (ids[:, None] >> bits) & 1 == 1, (CRC16[ids][:, None] >> bits) & 1 == 1], axis=1
    )


def decode_ids(
    light: np.ndarray,
    frames: np.ndarray,
    starts: np.ndarray,
    rng: np.random.Generator | CopyRandom | CopyStream,
    sigma: float,
    platform: Platform | str = "droplet",
    id_check: bool = True,
    row_copy: np.ndarray | None = None,
    group_light: np.ndarray | None = None,
) -> np.ndarray:
    """Ids that receivers decode from the (possibly colliding) ``rnb_r`` frames of the TXs they see.

    Links are grouped by receiving event: group g is links ``starts[g]:starts[g+1]`` (one link = no
    collision). Per group, detector i's level in bit slot k is ``sum_links frames[l, k] * light[l, i]``
    (light adds, so colliding bits OR), read as ``clip(round(level * s + n), 0, adc_max)`` counts with
    n ~ N(0, sigma^2) and taken as a 1 at or above ``no_reading_floor`` (module docstring). Each detector is
    a channel: it hears a frame when its start bit reads 1; the frame checks when its CRC bits equal the
    CRC-16 of its id bits (always, with ``id_check=False``).

    Args:
        light: (L, n_d) light of each link on each RX detector with all TX emitters on (model units).
        frames: (L, n_bits) bool frame of each link's TX (:func:`id_frames`).
        starts: (G,) sorted first link of each group (``starts[0] = 0``).
        rng, row_copy: noise stream(s); ``row_copy`` (G,) the env copy of each group, as in :func:`measure`.
        sigma: ADC noise (counts).
        platform: platform of the robots (ADC constants and floor).
        id_check: apply the CRC check.
        group_light: optional (G, n_d) ``light`` summed per group as here (``segment_sum(light, starts)``),
            if the caller has it already.

    Returns:
        (G,) decoded id (a copy's own robot number), or :data:`NOT_HEARD` (-1: no channel's frame checks)
        or :data:`CONFLICT` (-2: checking channels name different ids).
    """
    model = get_platform(platform).ir_model
    light = np.asarray(light, dtype=float)
    L, n_d = light.shape
    G = int(len(starts))
    if G == 0:
        return np.zeros(0, dtype=np.int64)

    # start bit (1 in every frame): which channels hear a frame at all
    if group_light is not None:
        start = np.asarray(group_light, dtype=float)
    else:
        start = segment_sum(light, starts) if G < L else light
    # ADC + floor, as the matrix, in one pass (kernels.adc_bits)
    noise0 = normal_noise(rng, sigma, (G, n_d), row_copy) if sigma > 0 else np.zeros((0, n_d))
    heard = adc_bits(np.ascontiguousarray(start), noise0, float(model.adc_scale), float(model.adc_max), float(model.no_reading_floor))
    # the rest of the frame, only on channels that heard a start bit (draws: per copy, after the start bits)
    hg, hi = np.nonzero(heard)
    H = hg.size
    n_bits = frames.shape[1] - 1
    if sigma > 0:
        noise = normal_noise(rng, sigma, (H, n_bits), None if row_copy is None else row_copy[hg])
    else:
        noise = np.zeros((H, n_bits))
    compiled = int(np.diff(np.r_[starts, L]).max()) <= FRAME_WORDS_MAX_GROUP  # larger groups: numpy's recursive sums
    words = frame_words if compiled else frame_words_numpy
    ident_h, crc_h = words(
        light, np.asarray(frames, dtype=bool), np.asarray(starts, dtype=np.int64), heard, noise,
        float(model.adc_scale), float(model.adc_max), float(model.no_reading_floor), ID_BITS,
    )
    # the decode rule (numpy reference: swarm_envs._compile.reference.pick_ids)
    return pick_ids(heard, ident_h, crc_h, CRC16, bool(id_check), NOT_HEARD, CONFLICT)


def frame_words_numpy(
    light: np.ndarray, frames: np.ndarray, starts: np.ndarray, heard: np.ndarray, noise: np.ndarray,
    scale: float, top: float, floor: float, id_bits: int = ID_BITS,
) -> tuple[np.ndarray, np.ndarray]:
    """Id and CRC words read on the heard channels (reference of the compiled
    :func:`swarm_envs.sensing.range_bearing_kernels.frame_words`, and the path of groups larger than it takes).

    Channel h (``np.nonzero(heard)`` order: group g, detector i) reads bit k of the frame at level
    ``sum_links frames[l, 1 + k] * light[l, i]`` over its group's links (summed as ``np.add.reduceat``),
    ``clip(round(level * scale + noise[h, k]), 0, top) / scale >= floor``; bits 0..id_bits-1 are the id
    word, the rest the CRC word (LSB first). Returns ((H,), (H,)) int64.
    """
    G, n_d = heard.shape
    L = light.shape[0]
    group = np.repeat(np.arange(G), np.diff(np.r_[starts, L]))
    hg, hi = np.nonzero(heard)
    H = hg.size
    row_of = np.full((G, n_d), -1, dtype=np.int64)
    row_of[hg, hi] = np.arange(H)
    ll, li = np.nonzero(heard[group])  # (link, detector) pairs that feed a heard channel
    rows = row_of[group[ll], li]
    order = np.argsort(rows, kind="stable")  # every heard channel gets >= 1 link of its group
    level = light[ll, li, None] * frames[ll, 1:]
    if ll.size > H:  # light adds: colliding bits OR
        level = segment_sum(level[order], np.flatnonzero(np.r_[True, np.diff(rows[order]) != 0]))
    else:
        level = level[order]
    counts = np.clip(np.round(level * scale + noise), 0.0, top)
    bits = (counts / scale >= floor).astype(np.int64)
    weights = 1 << np.arange(max(id_bits, bits.shape[1] - id_bits), dtype=np.int64)
    return bits[:, :id_bits] @ weights[:id_bits], bits[:, id_bits:] @ weights[: bits.shape[1] - id_bits]
