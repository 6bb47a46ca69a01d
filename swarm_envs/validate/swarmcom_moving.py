"""Channel count of [T20 Fig. 21] with moving robots, run in the env: the centre robot static at the centre of
the 72 x 72 cm arena sends, the others start at random places and drive the random walk of [T20 Alg. 1], and
after 30 s of simulated time the robots that currently detect the centre are counted [T20 Sec. 6.2.6: "Every
30 s, the number of illuminated robots, n_C, is determined ... The process is repeated 30 times per
experiment. In other words, in total 90 experimental trials were conducted": one count per trial].

Everything goes through the simulator's public API: the set-up is a task (:class:`CentreBroadcast`) made with
:func:`swarm_envs.make_vec`, one env copy per seed; the listeners are driven by the scripted
:class:`swarm_envs.agents.scripted.RandomWalk` on their observations (physics with collisions and the arena
walls, motion error on); the receiver is the ``sensing="full"`` stack (IR links with per-ray occlusion and
per-robot hardware variation, ADC noise, detector response, start detection and the dynamic threshold of
[T20 Eq. (36)], the bit-level SwarmCom network at 310 bps). The bearing exchange is ``exchange="ideal"``: over
the network it would put the centre's bearing lists on the air between its frames, and the paper's centre
sends only its signal.

Detection rule (the paper's robots light their LEDs "whenever they receive the signal" [T20 Fig. 21]; how
long an LED stays lit is not stated): a listener is lit at a count instant t when its own observation held a
decoded SwarmCom frame whose header names the centre (the ``message_ids`` row's decoded id 0, as the receiver
decoded it) in at least one control step of the window (t - ``window_s``, t]. A frame lasts 0.15 s (46 bit
slots at 310 bps with an 8-bit payload) and a listener parked next to the centre decodes one every 1-3
control steps (0.2 s on average), so the 0.3 s window of the rule is the shortest that always holds a frame's
end for a robot that keeps receiving: it is lit while it currently detects the centre, and not 0.3 s after
it stopped. The counts for 1 s and 5 s windows (an LED held lit that long) are measured beside it.
"""

from __future__ import annotations

from typing import Any

import numpy as np

import swarm_envs
from swarm_envs.agents.base import Policy
from swarm_envs.agents.scripted import RandomWalk
from swarm_envs.tasks.task import DT, BatchState, Task, spawn_positions
from swarm_envs.validate.swarmcom_setup import ARENA, PLATFORM

__all__ = ["COUNT_PERIOD_S", "LIT_WINDOW_S", "WINDOWS_S", "CentreBroadcast", "centre_heard", "count_lit", "moving_channels"]

COUNT_PERIOD_S = 30.0  # s between two counts of lit robots [T20 Sec. 6.2.6]
LIT_WINDOW_S = 0.3  # s, a robot is lit when it decoded a centre frame this recently (module docstring)
WINDOWS_S = (LIT_WINDOW_S, 1.0, 5.0)  # windows measured (s): the rule's, and an LED held lit 1 s or 5 s
PAYLOAD_BITS = 8  # the centre's payload: all ones, a series of s_1 as far as a frame allows


class CentreBroadcast(Task):
    """The set-up of [T20 Fig. 21] as a task: world robot 0 is static at the arena centre and transmit-only
    (``receive_off``), queueing an all-ones payload (s_1 symbols) whenever its transmit queue is empty; the
    agents are receive-only (``transmit_off``), so the centre is the only robot on the air. Agents spawn
    uniformly without overlap. Rewards are zero: the experiment counts from the observations."""

    def n_static_robots(self) -> int:
        return 1

    def default_arena_size(self) -> float:
        return ARENA

    def spawn(self, rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray]:
        r = self.platform.radius
        others = spawn_positions(rng, self.n_agents, r, self.arena, avoid=np.zeros((1, 2)), avoid_distance=2.05 * r)
        return np.vstack([np.zeros((1, 2)), others]), rng.uniform(-np.pi, np.pi, self.n_world)

    def transmit_off(self, num_cycles: np.ndarray) -> np.ndarray:
        mask = np.ones((self.n_copies, self.n_world), dtype=bool)
        mask[:, 0] = False
        return mask

    def receive_off(self, num_cycles: np.ndarray) -> np.ndarray:
        mask = np.zeros((self.n_copies, self.n_world), dtype=bool)
        mask[:, 0] = True
        return mask

    def static_messages(self, observations: dict[str, np.ndarray], first: np.ndarray) -> np.ndarray:
        return np.ones((self.n_copies, 1, int(self.config["message_bits"])), dtype=bool)

    def rewards(self, state: BatchState, first: np.ndarray) -> tuple[np.ndarray, dict[str, np.ndarray], dict[str, np.ndarray]]:
        return np.zeros((self.n_copies, self.n_agents)), {}, {}


def centre_heard(observations: dict[str, np.ndarray], n_world: int, centre: int = 0) -> np.ndarray:
    """(B, N) bool: the agent's observation of this step holds a decoded message whose header names world
    robot ``centre`` (the ``message_ids`` part of an env made with ``observe_ids=True``)."""
    ids = observations["message_ids"]
    decoded = ids[..., 0] > 0.5
    sender = np.rint(ids[..., 1] * max(n_world - 1, 1)).astype(np.int64)
    return (decoded & (sender == centre)).any(axis=-1)


def count_lit(
    env: Any,
    policy: Policy | None,
    n_counts: int,
    period_s: float = COUNT_PERIOD_S,
    windows_s: tuple[float, ...] = WINDOWS_S,
    observations: dict[str, np.ndarray] | None = None,
) -> dict[float, np.ndarray]:
    """Step a reset vector env of :class:`CentreBroadcast` (or a subclass) for ``n_counts`` x ``period_s``
    and count, at the end of every period, the agents lit under each window of ``windows_s`` (s): those that
    heard the centre (:func:`centre_heard`) in a step ending within the window. ``policy`` drives the agents
    from their observations (None: zero actions, robots parked); ``observations`` are the reset's.
    Returns {window: (B, n_counts) int}: lit agents per copy and count."""
    B, N = env.num_envs, env.n_agents
    n_world = env.task.n_world
    period = round(period_s / DT)
    window_steps = {w: max(1, round(w / DT)) for w in windows_s}
    obs = observations if observations is not None else env.batch.observations()
    last = np.full((B, N), -(10**9), dtype=np.int64)  # step of the last frame from the centre
    out = {w: np.zeros((B, n_counts), dtype=np.int64) for w in windows_s}
    zeros = np.zeros((B, N, env.layout.action_size), dtype=np.float32)
    if policy is not None:
        policy.reset(B * N)
    for k in range(1, n_counts * period + 1):
        if policy is None:
            actions = zeros
        else:
            flat = {key: v.reshape(B * N, *v.shape[2:]) for key, v in obs.items()}
            actions = policy.act_batch(flat).reshape(B, N, -1)
        obs, _, terminated, truncated, _ = env.step(actions)
        if np.any(terminated) or np.any(truncated):
            raise RuntimeError("an episode ended during the count: make the env with max_cycles above the steps run")
        last[centre_heard(obs, n_world)] = k
        if k % period == 0:
            for w, s in window_steps.items():
                out[w][:, k // period - 1] = (k - last < s).sum(axis=1)
    return out


def moving_channels(
    n_robots: int,
    relative_threshold: float,
    seeds: list[int],
    n_counts: int = 1,
    period_s: float = COUNT_PERIOD_S,
    windows_s: tuple[float, ...] = WINDOWS_S,
) -> dict[str, Any]:
    """[T20 Fig. 21] with moving robots: ``n_robots`` e-pucks (the centre among them) in the 72 x 72 cm arena,
    one env copy (trial) per seed of ``seeds``, m_tr = ``relative_threshold`` (ADC counts), 310 bps; the agents
    start at random places and headings and drive the random walk [T20 Alg. 1, t_m = 2 s, v in
    [-128, 128] mm/s, no obstacle avoidance]; lit agents counted at t = ``period_s``, 2 ``period_s``, ...
    (``n_counts`` counts per trial). Returns ``lit`` {window (s): (len(seeds), n_counts) lit agents} and
    ``centre_drift_m`` (len(seeds),): how far (m, ground truth) the walkers pushed the static centre robot
    off the arena centre by the last count (its motors hold it with the physics' bounded motor force)."""
    steps = round(n_counts * period_s / DT)
    env = swarm_envs.make_vec(
        CentreBroadcast, len(seeds), platform=PLATFORM, n_robots=n_robots - 1, arena_size=ARENA, sensing="full",
        message_bits=PAYLOAD_BITS, observe_ids=True, relative_threshold=relative_threshold, bitrate=310,
        exchange="ideal", max_cycles=steps + 1,
    )
    try:
        obs, _ = env.reset(seed=[int(s) for s in seeds])
        walk = RandomWalk(env.platform, env.layout, np.random.default_rng(np.random.SeedSequence([int(s) for s in seeds])))
        lit = count_lit(env, walk, n_counts, period_s, windows_s, observations=obs)
        centre = env.core.positions.reshape(len(seeds), env.task.n_world, 2)[:, 0]
        return {"lit": lit, "centre_drift_m": np.linalg.norm(centre, axis=1)}
    finally:
        env.close()
