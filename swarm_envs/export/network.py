"""The deterministic actor of an SB3 ``MlpPolicy`` as plain arrays, its torch reference and its ONNX graph.

SB3's deterministic action is ``clip(action_net(policy_net(flatten(obs))), -1, 1)``: the mean of the
diagonal Gaussian, clipped to the ``Box(-1, 1)`` action space as ``predict`` does (no squashing).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["Layer", "actor_layers", "actor_forward", "write_onnx"]


@dataclass(frozen=True)
class Layer:
    """``y = activation(weight @ x + bias)``; ``weight`` (out, in) float32, ``activation`` ``tanh``/``relu``/``none``."""

    weight: np.ndarray
    bias: np.ndarray
    activation: str


def actor_layers(model: Any) -> list[Layer]:
    """The actor's layers of an SB3 PPO ``MlpPolicy`` (flatten features, ``net_arch`` layers, ``action_net``);
    ``ValueError`` for another policy structure."""
    import torch
    from stable_baselines3.common.torch_layers import FlattenExtractor

    policy = model.policy
    if not isinstance(policy.pi_features_extractor, FlattenExtractor):
        raise ValueError(f"the actor's features extractor is {type(policy.pi_features_extractor).__name__}, not the flat MLP's FlattenExtractor")
    if getattr(policy, "squash_output", False):
        raise ValueError("a policy with squashed (tanh) actions is not exported")
    names = {torch.nn.Tanh: "tanh", torch.nn.ReLU: "relu"}
    modules = list(policy.mlp_extractor.policy_net) + [policy.action_net]
    layers: list[Layer] = []
    for i, module in enumerate(modules):
        if isinstance(module, torch.nn.Linear):
            w, b = module.weight.detach().cpu().numpy().astype(np.float32), module.bias.detach().cpu().numpy().astype(np.float32)
            layers.append(Layer(w, b, "none"))
        elif type(module) in names and layers and layers[-1].activation == "none":
            layers[-1] = Layer(layers[-1].weight, layers[-1].bias, names[type(module)])
        else:
            raise ValueError(f"the actor's layer {i} is {type(module).__name__}; the export takes Linear, Tanh and ReLU layers")
    return layers


def actor_forward(layers: list[Layer], obs: np.ndarray) -> np.ndarray:
    """Clipped deterministic actions (N, A) of ``layers`` for observations (N, D), in float64 (a check of the extraction)."""
    x = np.asarray(obs, np.float64)
    for layer in layers:
        x = x @ layer.weight.T.astype(np.float64) + layer.bias
        x = np.tanh(x) if layer.activation == "tanh" else np.maximum(x, 0.0) if layer.activation == "relu" else x
    return np.clip(x, -1.0, 1.0)


def write_onnx(model: Any, path: Path) -> Path:
    """The deterministic actor (observation (N, D) float32 -> clipped action (N, A)) as an ONNX file at ``path``."""
    import torch

    policy = model.policy

    class Actor(torch.nn.Module):
        def __init__(self) -> None:
            super().__init__()
            self.features, self.mlp, self.head = policy.pi_features_extractor, policy.mlp_extractor.policy_net, policy.action_net

        def forward(self, obs: torch.Tensor) -> torch.Tensor:
            return torch.clamp(self.head(self.mlp(self.features(obs))), -1.0, 1.0)

    size = int(np.prod(model.observation_space.shape))
    # the TorchScript exporter (dynamo=False) writes this plain graph without the onnxscript package the newer
    # exporter needs; torch marks it deprecated with two DeprecationWarnings, which say nothing about this export
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", category=DeprecationWarning, module=r"torch\.onnx")
        warnings.filterwarnings("ignore", message="You are using the legacy TorchScript-based ONNX export", category=DeprecationWarning)
        torch.onnx.export(Actor().eval(), (torch.zeros(1, size),), str(path), input_names=["observation"], output_names=["action"],
                          dynamic_axes={"observation": {0: "batch"}, "action": {0: "batch"}}, dynamo=False)
    return path
