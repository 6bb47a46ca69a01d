"""Local broadcast vs flooding experiment of the SwarmCom validation [T20 Sec. 6.2.2, Fig. 16b]: 2..7
robots on the random walk of [T20 Alg. 1] in the 72 x 72 cm arena, independent arenas side by side in one
bit-level network, and the share of robots each message reaches within 2 s (experiment c)."""

from __future__ import annotations

from typing import Any

import numpy as np

from swarm_envs.comm.network import Network
from swarm_envs.ir.layer import compute_links
from swarm_envs.sim.platforms import get_platform
from swarm_envs.validate.swarmcom_setup import (
    ARENA,
    PLATFORM,
    SEP,
    RandomWalk,
    arena_configuration,
)


def experiment_c(rng: np.random.Generator, quick: bool) -> dict[str, Any]:
    """(c) Message loss P_l and frames per message of local broadcast, flooding with the CRC-8 and flooding
    without it, per group size 2..7 [T20 Fig. 16b]."""
    messages = 60 if quick else 600
    replicas = 12 if quick else 30
    p = get_platform(PLATFORM)
    out = {}
    for label, mode, crc in (("broadcast", "broadcast", 0), ("flooding", "flooding", 8), ("flooding_no_crc", "flooding", 0)):
        out[label] = {}
        for n in range(2, 8):
            out[label][n] = _flood_run(n, mode, rng, messages, replicas, p, crc)
    return out


def _flood_run(n: int, mode: str, rng: np.random.Generator, messages: int, replicas: int, p, crc_bits: int = 0) -> dict[str, float]:
    N = n * replicas
    scene = np.repeat(np.arange(replicas), n)
    origin = np.stack([SEP * np.arange(replicas), np.zeros(replicas)], -1)
    pos = np.vstack([arena_configuration(n, rng) for _ in range(replicas)])
    pos = pos + origin[scene]
    head = rng.uniform(-np.pi, np.pi, N)
    walk = RandomWalk(N, rng)
    net = Network(PLATFORM, N, rng, relative_threshold=10, comm_mode=mode, crc_bits=crc_bits)
    period = 20  # steps: one message every 2 s per arena, declared lost after 2 s
    rounds = int(np.ceil(messages / replicas))
    pending: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    reached = []
    static = np.zeros(N, dtype=bool)
    for r in range(rounds):
        src = np.arange(replicas) * n + rng.integers(0, n, replicas)
        seq = net.send_many(src, rng.integers(0, 2, (replicas, 8)).astype(bool))
        got = np.zeros((replicas, n), dtype=bool)
        for k in range(period):
            walk.step(pos, head, scene, origin, ARENA, p.radius, static)
            links = compute_links(pos, head, PLATFORM)
            d = net.step(links)
            if len(d):
                sc = d.receiver // n
                hit = (d.origin == src[sc]) & (d.seq == seq[sc]) & (d.kind == "app")
                got[sc[hit], d.receiver[hit] % n] = True
        got[np.arange(replicas), src % n] = False
        reached.append(got.sum(axis=1) / (n - 1))
    reach = np.concatenate(reached)[:messages]
    st = net.stats
    return {
        "P_l": float(1.0 - reach.mean()),
        "reach": float(reach.mean()),
        "all_reached": float((reach == 1.0).mean()),
        "messages": int(reach.size),
        "bit_error_rate": net.summary()["bit_error_rate"],
        "frames_per_message": st["tx_started"] / max(1, int(reach.size)),
        "corrupt_delivered": st["rx_corrupt_delivered"] / max(1, st["rx_delivered"]),
    }
