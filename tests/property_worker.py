"""A child process that builds, resets and steps envs for the property tests, so that a crash (an abort in
a C library) or a hang cannot take the test run down with it: :class:`EnvWorker` sends one example at a
time and waits at most a time limit for the answer."""

from __future__ import annotations

import multiprocessing as mp
import traceback
from typing import Any

import numpy as np

#: steps an accepted env takes (random actions) after its reset
STEPS = 3


def try_env(env_id: str, kwargs: dict[str, Any], num_envs: Any = None) -> tuple[str, str, str]:
    """Build ``env_id`` with ``kwargs`` (a vector env of ``num_envs`` copies unless it is the string
    ``"single"``), reset it and step it :data:`STEPS` times with random actions, checking every observation
    against its space. Returns ``("ok", "", "")``, ``("error", type, message)`` for a ``TypeError`` or
    ``ValueError`` raised by the build, or ``("raw", type, traceback)`` for anything else (a reset or a
    step that fails, an observation outside its space, another exception type)."""
    import swarm_envs

    single = isinstance(num_envs, str) and num_envs == "single"
    try:
        env = swarm_envs.make(env_id, **kwargs) if single else swarm_envs.make_vec(env_id, num_envs, **kwargs)
    except (TypeError, ValueError) as err:
        return "error", type(err).__name__, str(err)
    except Exception as err:  # noqa: BLE001 - reported to the test as a raw failure
        return "raw", type(err).__name__, traceback.format_exc()
    try:
        rng = np.random.default_rng(0)
        if single:
            obs, _ = env.reset(seed=1)
            for _ in range(STEPS):
                _check(env.observation_space(env.possible_agents[0]), obs.values())
                if not env.agents:
                    break
                obs, *_ = env.step({a: rng.uniform(-1, 1, env.action_space(a).shape) for a in env.agents})
        else:
            obs, _ = env.reset(seed=1)
            for _ in range(STEPS):
                _check(env.observation_space, [obs])
                obs, *_ = env.step(rng.uniform(-1, 1, env.action_space.shape))
            _check(env.observation_space, [obs])
        env.close()
    except Exception as err:  # noqa: BLE001
        return "raw", type(err).__name__, traceback.format_exc()
    return "ok", "", ""


def _check(space: Any, observations: Any) -> None:
    for obs in observations:
        if not space.contains(obs):
            raise AssertionError(f"an observation is outside its space {space}")


def _serve(conn: Any) -> None:  # pragma: no cover - runs in the child
    import warnings

    warnings.simplefilter("ignore")
    while True:
        message = conn.recv()
        if message is None:
            return
        conn.send(try_env(*message))


class EnvWorker:
    """One child process answering :func:`try_env` calls; restarted after a crash or a time-out."""

    def __init__(self) -> None:
        self._ctx = mp.get_context("spawn")
        self._start()

    def _start(self) -> None:
        self.conn, child = self._ctx.Pipe()
        self.proc = self._ctx.Process(target=_serve, args=(child,), daemon=True)
        self.proc.start()
        child.close()

    def run(self, env_id: str, kwargs: dict[str, Any], num_envs: Any, timeout: float) -> tuple[str, str, str]:
        """:func:`try_env` in the child; ``("crash", exit code, "")`` or ``("hang", seconds, "")`` if it dies
        or takes longer than ``timeout`` seconds (the child is then restarted)."""
        self.conn.send((env_id, kwargs, num_envs))
        timed_out = False
        try:
            if self.conn.poll(timeout):
                return self.conn.recv()
            timed_out = True
        except (EOFError, OSError):  # the child closed the pipe: it died
            self.proc.join(timeout=10)
        self.proc.kill()
        self.proc.join()
        code = self.proc.exitcode
        self._start()
        return ("hang", str(timeout), "") if timed_out else ("crash", str(code), "")

    def close(self) -> None:
        try:
            self.conn.send(None)
        except (BrokenPipeError, OSError):
            pass
        self.proc.join(timeout=10)
        if self.proc.is_alive():
            self.proc.kill()
