"""Fixed-point form of the actor's layers and a bit-exact numpy model of the integer C forward pass.

Formats (``Qf``: an integer ``q`` stands for ``q / 2**f``): the observation enters as int16 ``Q(in)``, with
``in`` chosen so the observation space's largest bound fits; each layer's weights are int16 (``q15``) or int8
(``int8``) with one power-of-two scale per layer, the largest that fits the layer's largest weight; products
are summed in int64 with the bias at the accumulator's scale. A ``tanh`` layer rounds its sum to Q12 and looks
tanh up in a 513-entry Q15 table over [0, 8) (step 1/64, linear interpolation; 1 beyond 8), giving Q15; a
``relu`` layer keeps a format whose range covers twice the largest output seen on calibration observations
(the simulator's, when given), else the worst case by interval arithmetic from the input bound (saturating
at the format's end); the last layer rounds to Q15 and saturates at +-32767 (the action clip to [-1, 1]).
Rounding is to nearest, ties away from zero for the shifts' ``+ half`` and ties to even for the input
(``lrintf``), the same in the C code and here.

A DeepSets encoder (:class:`swarm_envs.export.network.SetFeatures`) is quantised in front of the MLP: its
``phi`` layers take the rows at the observation's ``Q(in)`` and give Q15 (tanh); per block the Q15 outputs of
the valid rows are summed in int64 and divided by their count (rounded to nearest, ties away from zero), the
share of valid rows is ``round(count * 32768 / K)`` (saturated at 32767), and both, with the frame's other
values, are brought to one feature format ``Q(feat)`` (set by the larger of 1 and those values' bound) that
the MLP's first layer takes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from swarm_envs.export.network import Layer, SetFeatures

__all__ = ["FixedLayer", "FixedSet", "FixedNet", "quantize", "set_features_float", "TANH_TABLE", "TANH_IN_FRAC", "fixed_forward", "input_frac"]

#: the Q format of a tanh layer's input (the table's index is its top bits)
TANH_IN_FRAC = 12
#: tanh at 0, 1/64, ..., 8 in Q15 (saturated at 32767)
TANH_TABLE = np.minimum(np.rint(np.tanh(np.arange(513) / 64.0) * 32768.0), 32767).astype(np.int64)
WEIGHT_MAX = {"q15": 32767, "int8": 127}
MAX_WEIGHT_FRAC = 24


@dataclass(frozen=True)
class FixedLayer:
    """One layer in integers: ``weight`` (out, in) at ``Q(w_frac)``, ``bias`` at ``Q(in_frac + w_frac)``,
    output at ``Q(out_frac)`` (15 for tanh and the last layer)."""

    weight: np.ndarray
    bias: np.ndarray
    activation: str
    in_frac: int
    w_frac: int
    out_frac: int


@dataclass(frozen=True)
class FixedSet:
    """The DeepSets encoder in integers: ``blocks`` (row indices (K, F) within a frame, the ``phi`` layers
    from ``Q(in_frac)`` to Q15), ``rest`` indices, all features at ``Q(feat_frac)``; one frame is
    ``frame_size`` values, ``n_stack`` frames."""

    frame_size: int
    n_stack: int
    blocks: list[tuple[np.ndarray, list[FixedLayer]]]
    rest: np.ndarray
    in_frac: int
    feat_frac: int


@dataclass(frozen=True)
class FixedNet:
    """The quantised actor: ``mode`` (``q15`` or ``int8``), input format ``Q(in_frac)``, the set encoder
    (None for the flat MLP), layers."""

    mode: str
    in_frac: int
    layers: list[FixedLayer]
    features: FixedSet | None = None


def input_frac(bound: float) -> int:
    """The Q format of int16 values in [-bound, bound]: ``14 - floor(log2(bound))`` (at most 15)."""
    return min(15, 14 - math.floor(math.log2(max(bound, 2.0**-8))))


def _quantize_chain(layers: list[Layer], frac: int, bound: float, qmax: int, x: np.ndarray | None, head: bool) -> list[FixedLayer]:
    """Layers from input ``Q(frac)`` (values within ``bound``); ``head``: the last layer is the action head."""
    out: list[FixedLayer] = []
    for i, layer in enumerate(layers):
        w = layer.weight.astype(np.float64)
        largest = float(np.abs(w).max()) or 1.0
        w_frac = min(MAX_WEIGHT_FRAC, math.floor(math.log2(qmax / largest)))
        wq = np.clip(np.rint(w * 2.0**w_frac), -qmax, qmax).astype(np.int64)
        bq = np.rint(layer.bias.astype(np.float64) * 2.0 ** (frac + w_frac)).astype(np.int64)
        last = head and i == len(layers) - 1
        if last or layer.activation == "tanh":
            o_frac, bound = 15, 1.0
        elif layer.activation == "relu":
            if x is not None:
                bound = 2.0 * float(np.maximum(x @ w.T + layer.bias, 0.0).max())
            else:
                bound = float((np.abs(w).sum(axis=1) * bound + np.abs(layer.bias)).max())
            o_frac = input_frac(bound)
        else:
            raise ValueError(f"layer {i}: a hidden layer without activation is not quantised")
        out.append(FixedLayer(wq, bq, layer.activation, frac, w_frac, o_frac))
        if x is not None:
            x = x @ w.T + layer.bias
            x = np.tanh(x) if layer.activation == "tanh" else np.maximum(x, 0.0)
        frac = o_frac
    return out


def set_features_float(features: SetFeatures, obs: np.ndarray) -> np.ndarray:
    """The DeepSets features (N, n_stack * frame_out) of network inputs (N, n_stack * frame_size), float64."""
    obs = np.asarray(obs, np.float64)
    out = []
    for f in range(features.n_stack):
        frame = obs[:, f * features.frame_size : (f + 1) * features.frame_size]
        for block in features.blocks:
            rows = frame[:, block.index]
            valid = (rows[..., 0] > 0.5).astype(np.float64)
            h = rows
            for layer in block.phi:
                h = h @ layer.weight.T.astype(np.float64) + layer.bias
                h = np.tanh(h) if layer.activation == "tanh" else np.maximum(h, 0.0) if layer.activation == "relu" else h
            count = valid.sum(axis=1, keepdims=True)
            out += [(h * valid[..., None]).sum(axis=1) / np.maximum(count, 1.0), count / rows.shape[1]]
        out.append(frame[:, features.rest])
    return np.concatenate(out, axis=1)


def quantize(layers: list[Layer], obs_bound: float, mode: str = "q15", calibration: np.ndarray | None = None,
             features: SetFeatures | None = None, rest_bound: float = 1.0) -> FixedNet:
    """:class:`FixedNet` of float ``layers`` for observations within ``[-obs_bound, obs_bound]``;
    ``calibration``: network inputs (N, D) whose activations set the ReLU layers' formats; ``features``: the
    DeepSets encoder in front of ``layers`` (its phi layers tanh), whose non-row values lie within
    ``rest_bound``."""
    if mode not in WEIGHT_MAX:
        raise ValueError(f"fixed-point mode {mode!r} unknown; allowed: {sorted(WEIGHT_MAX)}")
    qmax = WEIGHT_MAX[mode]
    frac = input_frac(obs_bound)
    x = None if calibration is None else np.asarray(calibration, np.float64)
    fixed_set = None
    if features is None:
        mlp = _quantize_chain(layers, frac, float(obs_bound), qmax, x, head=True)
    else:
        if any(layer.activation != "tanh" for b in features.blocks for layer in b.phi):
            raise ValueError("the set encoder's phi layers must be tanh layers for the fixed-point build")
        blocks = [(b.index, _quantize_chain(b.phi, frac, float(obs_bound), qmax, None, head=False)) for b in features.blocks]
        feat_bound = max(1.0, float(rest_bound))
        feat_frac = input_frac(feat_bound)
        fixed_set = FixedSet(features.frame_size, features.n_stack, blocks, features.rest, frac, feat_frac)
        mlp = _quantize_chain(layers, feat_frac, feat_bound, qmax, None if x is None else set_features_float(features, x), head=True)
    return FixedNet(mode, frac, mlp, fixed_set)


def _div_round(v: np.ndarray, count: np.ndarray) -> np.ndarray:
    """``v / count`` (count > 0) rounded to nearest, ties away from zero, as the C ``div_round``."""
    return np.where(v >= 0, (v + count // 2) // count, -((-v + count // 2) // count))


def _to_format(v: np.ndarray, frm: int, to: int) -> np.ndarray:
    return np.clip(_shift_round(v, frm - to), -32768, 32767)


def _chain_q(layers: list[FixedLayer], x: np.ndarray, head: bool) -> np.ndarray:
    for i, layer in enumerate(layers):
        acc = x @ layer.weight.T + layer.bias
        s = layer.in_frac + layer.w_frac
        if head and i == len(layers) - 1:
            x = np.clip(_shift_round(acc, s - 15), -32767, 32767)
        elif layer.activation == "tanh":
            z = _shift_round(acc, s - TANH_IN_FRAC)
            x = _tanh_q(np.clip(z, -(1 << 31), (1 << 31) - 1))
        else:
            x = np.clip(_shift_round(np.maximum(acc, 0), s - layer.out_frac), 0, 32767)
    return x


def _set_q(fs: FixedSet, x: np.ndarray) -> np.ndarray:
    """The integer DeepSets features at Q(feat_frac) of quantised network inputs (N, n_stack * frame_size)."""
    out = []
    for f in range(fs.n_stack):
        frame = x[:, f * fs.frame_size : (f + 1) * fs.frame_size]
        for index, phi in fs.blocks:
            rows = frame[:, index]
            valid = (rows[..., 0] > (1 << (fs.in_frac - 1))).astype(np.int64)
            h = _chain_q(phi, rows, head=False)
            count = valid.sum(axis=1, keepdims=True)
            mean = _div_round((h * valid[..., None]).sum(axis=1), np.maximum(count, 1))
            k = rows.shape[1]
            share = np.minimum((count * 32768 + k // 2) // k, 32767)
            out += [_to_format(mean, 15, fs.feat_frac), _to_format(share, 15, fs.feat_frac)]
        out.append(_to_format(frame[:, fs.rest], fs.in_frac, fs.feat_frac))
    return np.concatenate(out, axis=1)


def _shift_round(v: np.ndarray, s: int) -> np.ndarray:
    """``v / 2**s`` rounded (half up after the arithmetic shift, as the C ``shift_round``); ``s <= 0`` multiplies."""
    return (v + (1 << (s - 1))) >> s if s > 0 else v * (1 << -s)


def _tanh_q(z: np.ndarray) -> np.ndarray:
    a = np.abs(z)
    idx = np.minimum(a >> 6, 511)
    frac = a & 63
    lo, hi = TANH_TABLE[idx], TANH_TABLE[idx + 1]
    y = lo + (((hi - lo) * frac + 32) >> 6)
    y = np.where(a >= (8 << TANH_IN_FRAC), 32767, y)
    return np.where(z < 0, -y, y)


def quantize_input(net: FixedNet, obs: np.ndarray) -> np.ndarray:
    """int16 observations at ``Q(net.in_frac)`` (ties to even, saturated), as int64."""
    scaled = np.asarray(obs, np.float32) * np.float32(2.0**net.in_frac)
    return np.clip(np.rint(scaled), -32768, 32767).astype(np.int64)


def fixed_forward(net: FixedNet, obs: np.ndarray) -> np.ndarray:
    """Q15 actions (N, A) int64 of the integer forward pass, bit for bit as the C code computes them."""
    x = quantize_input(net, obs)
    if net.features is not None:
        x = _set_q(net.features, x)
    return _chain_q(net.layers, x, head=True)
