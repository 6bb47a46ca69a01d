"""What training prints and logs: the progress line, the robot-steps/s rate, SB3's logger writing progress.csv,
and the callbacks (checkpoints, Ctrl-C)."""

from __future__ import annotations
import importlib.util
import math
import sys
import time
from pathlib import Path
from typing import Any
import numpy as np
from swarm_envs.agents.config import progress_bar_on

__all__ = ["say", "RATE_KEY", "rate_callback", "make_logger", "make_callbacks"]


def say(line: str) -> None:
    """Print a line without breaking a tqdm bar that may be on screen."""
    from tqdm import tqdm

    tqdm.write(line, file=sys.stdout)


def _progress_writer(total: int, repeat: int = 1):
    """An SB3 logger output that prints one short line per ~10 % of ``total`` PPO timesteps (and the last),
    counted in robot-steps (``repeat`` per timestep)."""
    from stable_baselines3.common.logger import KVWriter

    class ProgressLine(KVWriter):
        def __init__(self) -> None:
            self.next_fraction = 0.1
            self.last = -1

        def write(self, key_values: dict[str, Any], key_excluded: dict, step: int = 0) -> None:
            done = key_values.get("time/total_timesteps", step)
            if done <= self.last or (done < self.next_fraction * total and done < total):
                return
            self.last = done
            self.next_fraction = math.floor(done / total * 10 + 1) / 10
            parts = [f"PPO {done * repeat}/{total * repeat} robot-steps ({100 * done / total:.0f}%)"]
            for key, label, fmt in (("rollout/ep_rew_mean", "ep_rew_mean", ".4g"), ("rollout/ep_len_mean", "ep_len", ".4g"),
                                    (RATE_KEY, "robot-steps/s", ".0f"), ("train/loss", "loss", ".3g")):
                if key in key_values:
                    parts.append(f"{label} {key_values[key]:{fmt}}")
            say("  ".join(parts))

        def close(self) -> None:
            pass

    return ProgressLine()

#: the progress.csv column of the training rate (robot-steps/s) from the end of the first env step on
RATE_KEY = "time/robot_steps_per_s"


def rate_callback(repeat: int = 1):
    """An SB3 callback that logs :data:`RATE_KEY` at the end of every rollout: robot-steps (PPO timesteps x
    ``repeat``) per second of wall time since the end of the first env step, PPO updates included. The start
    lies after the env's first reset and step, where a cold numba cache compiles the kernels, so unlike
    SB3's ``time/fps`` (from the start of ``learn``) the rate does not count the one-off compile."""
    from stable_baselines3.common.callbacks import BaseCallback

    class RateCallback(BaseCallback):
        start: tuple[float, int] | None = None  # (perf_counter s, num_timesteps) at the end of the first step

        def _on_training_start(self) -> None:
            self.start = None

        def _on_step(self) -> bool:
            if self.start is None:
                self.start = (time.perf_counter(), self.num_timesteps)
            return True

        def _on_rollout_end(self) -> None:
            if self.start is None:
                return
            seconds = time.perf_counter() - self.start[0]
            steps = (self.num_timesteps - self.start[1]) * repeat
            if seconds > 0 and steps > 0:
                self.logger.record(RATE_KEY, steps / seconds)

    return RateCallback()


def make_logger(out: Path, total: int, progress_lines: bool, repeat: int = 1):
    """SB3 logger: ``progress.csv`` always, TensorBoard if installed, short progress lines if asked (``total``
    PPO timesteps, each ``repeat`` robot-steps)."""
    from stable_baselines3.common.logger import Logger, make_output_format

    formats = [make_output_format("csv", str(out))]
    if importlib.util.find_spec("tensorboard") is not None:
        formats.append(make_output_format("tensorboard", str(out / "tensorboard")))
    if progress_lines:
        formats.append(_progress_writer(total, repeat))
    return Logger(folder=str(out), output_formats=formats)


def make_callbacks(cfg: dict[str, Any], out: Path, num_envs: int, total: int):
    """Checkpoints every ``train.checkpoint_freq`` robot-steps and a tqdm bar over the real ``total``
    robot-steps (``num_envs`` robot-steps per callback call: rows x action repeat)."""
    from stable_baselines3.common.callbacks import BaseCallback, CallbackList, CheckpointCallback

    callbacks = []
    freq = cfg["train"]["checkpoint_freq"]
    if freq > 0:
        callbacks.append(CheckpointCallback(save_freq=max(1, freq // num_envs), save_path=str(out / "checkpoints"), name_prefix="ppo"))
    if progress_bar_on(cfg["train"]["progress_bar"]):

        class TqdmCallback(BaseCallback):
            """Progress bar over robot-steps with the latest mean episode return."""

            bar = None

            def _on_training_start(self) -> None:
                from tqdm import tqdm

                self.bar = tqdm(total=total, desc="PPO", unit="step", dynamic_ncols=True)

            def _on_step(self) -> bool:
                self.bar.update(num_envs)
                buf = self.model.ep_info_buffer
                if buf and self.n_calls % 50 == 0:
                    self.bar.set_postfix(ep_rew=f"{np.mean([e['r'] for e in buf]):.3g}")
                return True

            def _on_training_end(self) -> None:
                self.close()

            def close(self) -> None:
                if self.bar is not None:
                    self.bar.close()
                    self.bar = None

        callbacks.append(TqdmCallback())
    return CallbackList(callbacks)
