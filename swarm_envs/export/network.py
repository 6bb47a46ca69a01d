"""The deterministic actor of an SB3 / sb3-contrib policy as plain arrays, and its ONNX graph.

SB3's deterministic action is ``clip(action_net(policy_net(features(obs))), -1, 1)``: the mean of the
diagonal Gaussian, clipped to the ``Box(-1, 1)`` action space as ``predict`` does (no squashing). The
features are the flat observation (``FlattenExtractor``) or the DeepSets encoding of
:class:`swarm_envs.agents.policies.SetEncoder`; sb3-contrib's ``MlpLstmPolicy`` puts its actor LSTM
(``lstm_actor``) between the features and ``policy_net``.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["Layer", "SetBlock", "SetFeatures", "LstmLayer", "Actor", "actor_network", "actor_layers", "actor_forward", "write_onnx"]


@dataclass(frozen=True)
class Layer:
    """``y = activation(weight @ x + bias)``; ``weight`` (out, in) float32, ``activation`` ``tanh``/``relu``/``none``."""

    weight: np.ndarray
    bias: np.ndarray
    activation: str


@dataclass(frozen=True)
class SetBlock:
    """One row block of the DeepSets encoder: ``index`` (K, F) the flat indices (within one frame) of each
    row's features, column 0 the row's ``valid`` flag; ``phi`` the layers applied to every row."""

    index: np.ndarray
    phi: list[Layer]


@dataclass(frozen=True)
class SetFeatures:
    """The DeepSets encoder of one frame of ``frame_size`` values, applied to each of ``n_stack`` frames:
    per block the mean of ``phi`` over the valid rows (zeros when none) and the share of valid rows, then
    the values at ``rest``."""

    frame_size: int
    n_stack: int
    blocks: list[SetBlock]
    rest: np.ndarray

    @property
    def frame_out(self) -> int:
        """Features per frame."""
        return sum(b.phi[-1].weight.shape[0] + 1 for b in self.blocks) + len(self.rest)


@dataclass(frozen=True)
class LstmLayer:
    """One layer of ``torch.nn.LSTM``: gates ``w_ih @ x + w_hh @ h + bias`` (``bias`` = ``b_ih + b_hh``),
    in torch's order input, forget, cell, output; ``w_ih`` (4H, in), ``w_hh`` (4H, H)."""

    w_ih: np.ndarray
    w_hh: np.ndarray
    bias: np.ndarray

    @property
    def hidden(self) -> int:
        """H, the layer's units."""
        return self.w_hh.shape[1]


@dataclass(frozen=True)
class Actor:
    """The deterministic actor: network input of ``input_size`` floats (the stacked observation) ->
    ``features`` (None: the input itself) -> ``lstm`` layers (empty: none) -> ``layers`` (``net_arch``,
    then ``action_net``) -> clip to [-1, 1]."""

    input_size: int
    features: SetFeatures | None
    lstm: list[LstmLayer]
    layers: list[Layer]


def _f32(t: Any) -> np.ndarray:
    return t.detach().cpu().numpy().astype(np.float32)


def _dense_layers(modules: list[Any], where: str) -> list[Layer]:
    """Linear / Tanh / ReLU modules as :class:`Layer` s; ``ValueError`` for anything else."""
    import torch

    names = {torch.nn.Tanh: "tanh", torch.nn.ReLU: "relu"}
    layers: list[Layer] = []
    for i, module in enumerate(modules):
        if isinstance(module, torch.nn.Linear):
            layers.append(Layer(_f32(module.weight), _f32(module.bias), "none"))
        elif type(module) in names and layers and layers[-1].activation == "none":
            layers[-1] = Layer(layers[-1].weight, layers[-1].bias, names[type(module)])
        else:
            raise ValueError(f"{where} layer {i} is {type(module).__name__}; the export takes Linear, Tanh and ReLU layers")
    return layers


def _set_features(extractor: Any) -> SetFeatures:
    blocks = []
    for i, phi in enumerate(extractor.phis):
        index = getattr(extractor, f"_index{i}").cpu().numpy().astype(np.int64)
        if index.shape[0] == 0:
            raise ValueError(f"the set encoder's block {i} has no rows")
        blocks.append(SetBlock(index, _dense_layers(list(phi), f"the set encoder's phi {i}:")))
    return SetFeatures(int(extractor.size), int(extractor.n_stack), blocks, extractor._rest.cpu().numpy().astype(np.int64))


def _lstm_layers(lstm: Any) -> list[LstmLayer]:
    if lstm.bidirectional or getattr(lstm, "proj_size", 0) or not lstm.bias or lstm.batch_first:
        raise ValueError("the actor's LSTM is bidirectional, projected, bias-free or batch-first; the export takes torch's default LSTM")
    return [LstmLayer(_f32(getattr(lstm, f"weight_ih_l{k}")), _f32(getattr(lstm, f"weight_hh_l{k}")),
                      (_f32(getattr(lstm, f"bias_ih_l{k}")) + _f32(getattr(lstm, f"bias_hh_l{k}"))).astype(np.float32))
            for k in range(lstm.num_layers)]


def actor_network(model: Any) -> Actor:
    """The deterministic actor of an SB3 PPO ``MlpPolicy`` or an sb3-contrib RecurrentPPO ``MlpLstmPolicy``,
    with the flat or the DeepSets features; ``ValueError`` for another policy structure."""
    from stable_baselines3.common.torch_layers import FlattenExtractor

    from swarm_envs.agents.policies import SetEncoder

    policy = model.policy
    if getattr(policy, "squash_output", False):
        raise ValueError("a policy with squashed (tanh) actions is not exported")
    extractor = policy.pi_features_extractor
    if isinstance(extractor, SetEncoder):
        features = _set_features(extractor)
    elif isinstance(extractor, FlattenExtractor):
        features = None
    else:
        raise ValueError(f"the actor's features extractor is {type(extractor).__name__}, not FlattenExtractor or SetEncoder")
    lstm = _lstm_layers(policy.lstm_actor) if getattr(policy, "lstm_actor", None) is not None else []
    layers = _dense_layers(list(policy.mlp_extractor.policy_net) + [policy.action_net], "the actor's")
    return Actor(int(np.prod(model.observation_space.shape)), features, lstm, layers)


def actor_layers(model: Any) -> list[Layer]:
    """The actor's layers of an SB3 PPO ``MlpPolicy`` (flatten features, ``net_arch`` layers, ``action_net``);
    ``ValueError`` for another policy structure."""
    actor = actor_network(model)
    if actor.features is not None or actor.lstm:
        raise ValueError("the actor has a set encoder or an LSTM, not the flat MLP's FlattenExtractor")
    return actor.layers


def actor_forward(layers: list[Layer], obs: np.ndarray) -> np.ndarray:
    """Clipped deterministic actions (N, A) of ``layers`` for observations (N, D), in float64 (a check of the extraction)."""
    x = np.asarray(obs, np.float64)
    for layer in layers:
        x = x @ layer.weight.T.astype(np.float64) + layer.bias
        x = np.tanh(x) if layer.activation == "tanh" else np.maximum(x, 0.0) if layer.activation == "relu" else x
    return np.clip(x, -1.0, 1.0)


def write_onnx(model: Any, path: Path) -> Path:
    """The deterministic actor as an ONNX file at ``path``: input ``observation`` (N, D) float32 (the
    network's input: with ``frame_stack`` k, the last k observations, oldest first), output ``action``
    (N, A) clipped to [-1, 1]; a recurrent actor also takes ``h``, ``c`` (layers, N, H), zeros at an
    episode start, and gives the next ones as ``h_out``, ``c_out``."""
    import torch

    policy = model.policy
    recurrent = getattr(policy, "lstm_actor", None) is not None

    class Actor(torch.nn.Module):
        def __init__(self) -> None:
            super().__init__()
            self.features, self.mlp, self.head = policy.pi_features_extractor, policy.mlp_extractor.policy_net, policy.action_net
            self.lstm = policy.lstm_actor if recurrent else None

        def forward(self, obs: torch.Tensor, *state: torch.Tensor):
            x = self.features(obs)
            if self.lstm is None:
                return torch.clamp(self.head(self.mlp(x)), -1.0, 1.0)
            out, (h, c) = self.lstm(x.unsqueeze(0), (state[0], state[1]))
            return torch.clamp(self.head(self.mlp(out[0])), -1.0, 1.0), h, c

    size = int(np.prod(model.observation_space.shape))
    args: tuple = (torch.zeros(1, size),)
    inputs, outputs, axes = ["observation"], ["action"], {"observation": {0: "batch"}, "action": {0: "batch"}}
    if recurrent:
        shape = (policy.lstm_actor.num_layers, 1, policy.lstm_actor.hidden_size)
        args += (torch.zeros(shape), torch.zeros(shape))
        inputs += ["h", "c"]
        outputs += ["h_out", "c_out"]
        axes.update({name: {1: "batch"} for name in ("h", "c", "h_out", "c_out")})
    # the TorchScript exporter (dynamo=False) writes this plain graph without the onnxscript package the newer
    # exporter needs; torch marks it deprecated with two DeprecationWarnings, which say nothing about this export
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", category=DeprecationWarning, module=r"torch\.onnx")
        warnings.filterwarnings("ignore", message="You are using the legacy TorchScript-based ONNX export", category=DeprecationWarning)
        # the LSTM's state is an input here, which is what torch's warnings about batch sizes and traced shape checks ask for
        warnings.filterwarnings("ignore", message=".*batch_size other than 1.*LSTM", category=UserWarning)
        warnings.filterwarnings("ignore", category=torch.jit.TracerWarning)
        torch.onnx.export(Actor().eval(), args, str(path), input_names=inputs, output_names=outputs,
                          dynamic_axes=axes, dynamo=False)
    return path
