"""Compile an export folder's C on the host and run it: through ``ctypes``, and as a
:class:`swarm_envs.agents.base.Policy` for in-the-loop evaluation on the simulator."""

from __future__ import annotations

import ctypes
import shutil
import subprocess
from pathlib import Path

import numpy as np

from swarm_envs.agents.base import Policy, flatten_batch
from swarm_envs.sensing.observation import ObservationLayout
from swarm_envs.sim.platforms import Platform

__all__ = ["compiler", "compile_shared", "object_sizes", "CPolicyLibrary", "CPolicy"]

CFLAGS = ["-std=c99", "-O2", "-Wall", "-Wextra", "-Werror", "-pedantic", "-ffp-contract=off"]


def compiler() -> str | None:
    """The host C compiler (``cc``, ``gcc`` or ``clang``) or None."""
    for name in ("cc", "gcc", "clang"):
        path = shutil.which(name)
        if path:
            return path
    return None


def _cc() -> str:
    cc = compiler()
    if cc is None:
        raise RuntimeError("no C compiler (cc, gcc or clang) on this machine")
    return cc


def compile_shared(folder: Path, sources: tuple[str, ...] = ("policy.c", "actions.c"), name: str = "libpolicy.so") -> Path:
    """Build ``sources`` of ``folder`` into a shared library there (strict C99, warnings as errors)."""
    out = folder / name
    cmd = [_cc(), *CFLAGS, "-fPIC", "-shared", "-o", str(out), *(str(folder / s) for s in sources), "-lm"]
    done = subprocess.run(cmd, capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"compiling {', '.join(sources)} in '{folder}' failed:\n{done.stderr[-2000:]}")
    return out


def object_sizes(folder: Path, source: str = "policy.c", flags: tuple[str, ...] = ("-Os",)) -> dict[str, int]:
    """``text``, ``data``, ``bss`` bytes of ``source`` compiled to an object file for the host (``size``)."""
    obj = folder / (Path(source).stem + ".o")
    subprocess.run([_cc(), "-std=c99", *flags, "-c", "-o", str(obj), str(folder / source)], check=True, capture_output=True, text=True)
    try:
        out = subprocess.run(["size", str(obj)], check=True, capture_output=True, text=True).stdout.splitlines()
        fields = out[1].split()
        return {"text": int(fields[0]), "data": int(fields[1]), "bss": int(fields[2])}
    finally:
        obj.unlink(missing_ok=True)


class CPolicyLibrary:
    """The compiled ``policy_*`` and ``actions_decode`` functions of a shared library, for one or many robots."""

    def __init__(self, library: Path, obs_size: int, action_size: int) -> None:
        self.lib = ctypes.CDLL(str(library))
        self.obs_size, self.action_size = obs_size, action_size
        self.lib.policy_state_size.restype = ctypes.c_size_t
        self.state_size = int(self.lib.policy_state_size())
        f32 = np.ctypeslib.ndpointer(np.float32, flags="C_CONTIGUOUS")
        self.lib.policy_step.argtypes = [ctypes.c_void_p, f32, f32]
        self.lib.policy_reset.argtypes = [ctypes.c_void_p]
        self.states: list[ctypes.Array] = []

    def reset(self, n: int) -> None:
        """Fresh states for ``n`` robots (``policy_reset`` on each)."""
        self.states = [ctypes.create_string_buffer(self.state_size) for _ in range(n)]
        for s in self.states:
            self.lib.policy_reset(ctypes.addressof(s))

    def step(self, flat: np.ndarray) -> np.ndarray:
        """Actions (N, A) float32 for flat observations (N, D), robot i with state i."""
        flat = np.ascontiguousarray(flat, dtype=np.float32)
        out = np.zeros((len(flat), self.action_size), np.float32)
        for i, row in enumerate(flat):
            action = np.zeros(self.action_size, np.float32)
            self.lib.policy_step(ctypes.addressof(self.states[i]), row, action)
            out[i] = action
        return out


class CPolicy(Policy):
    """The compiled C policy as a :class:`Policy` on the env's named observations (one state per robot)."""

    name = "c"

    def __init__(self, library: Path, platform: Platform, layout: ObservationLayout, obs_size: int, action_size: int) -> None:
        super().__init__(platform, layout)
        self.c = CPolicyLibrary(library, obs_size, action_size)

    def reset(self, n: int, rng: np.random.Generator | None = None) -> None:
        super().reset(n, rng)
        self.c.reset(n)

    def act_batch(self, obs: dict[str, np.ndarray]) -> np.ndarray:
        return self.c.step(flatten_batch(self.layout, obs))
