"""The figures of a run: the learning curve from progress.csv, the results bar chart, and an episode GIF of the
trained policy."""

from __future__ import annotations
import contextlib
import os
from pathlib import Path
from typing import Any
import numpy as np
from swarm_envs.agents.evaluation import make_env, run_episode

from swarm_envs.agents.config import env_kwargs_of

__all__ = ["plot_learning_curve", "plot_results", "write_gif"]


def _read_progress(path: Path) -> dict[str, np.ndarray]:
    import csv

    with open(path, newline="") as fh:
        rows = list(csv.DictReader(fh))
    keys = rows[0].keys() if rows else []
    return {k: np.array([float(r[k]) if r.get(k) not in (None, "") else np.nan for r in rows]) for k in keys}


def _save_figure(fig: Any, path: Path) -> None:
    """Save a matplotlib figure to ``path`` under a temporary name, renamed when complete."""
    tmp = path.with_name(f".tmp-{os.getpid()}-{path.name}")
    try:
        fig.savefig(tmp, dpi=110)
        os.replace(tmp, path)
    finally:
        with contextlib.suppress(OSError):
            tmp.unlink()


def _finish_figure(fig: Any, title: str, path: Path) -> None:
    """Title, layout, save (under a temporary name, :func:`_save_figure`) and close a figure."""
    import matplotlib.pyplot as plt

    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    try:
        _save_figure(fig, path)
    finally:
        plt.close(fig)


def plot_learning_curve(csv_path: str | Path, png_path: str | Path, title: str) -> bool:
    """Plot ``progress.csv`` (mean episode return, episode length, losses vs robot-steps); False if no data.
    The PNG is written under a temporary name and renamed when complete."""
    data = _read_progress(Path(csv_path))
    steps = data.get("time/total_timesteps")
    if steps is None or not np.isfinite(steps).any():
        return False
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.ticker import EngFormatter

    panels = [("rollout/ep_rew_mean", "mean episode return (per robot)"), ("rollout/ep_len_mean", "mean episode length (steps)"),
              ("train/value_loss", "value loss"), ("train/policy_gradient_loss", "policy-gradient loss")]
    panels = [(k, label) for k, label in panels if k in data and np.isfinite(data[k]).any()]
    if not panels:
        return False
    fig, axes = plt.subplots(1, len(panels), figsize=(3.3 * len(panels), 3.0), squeeze=False)
    for ax, (key, label) in zip(axes[0], panels):
        ok = np.isfinite(steps) & np.isfinite(data[key])
        ax.plot(steps[ok], data[key][ok], marker="." if ok.sum() <= 30 else None, lw=1)
        ax.xaxis.set_major_formatter(EngFormatter(sep=""))  # 50k, not 50000 (labels would overlap)
        ax.set_xlabel("robot-steps", fontsize=8)
        ax.set_title(label, fontsize=9)
        ax.tick_params(labelsize=7)
    _finish_figure(fig, title, Path(png_path))
    return True


def plot_results(rows: list[dict[str, Any]], path: Path, title: str) -> None:
    """One bar panel per metric (policies side by side) with bootstrap 95 % CI error bars (none for n=1)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    metrics = list(dict.fromkeys(r["metric"] for r in rows))
    policies = list(dict.fromkeys(r["policy"] for r in rows))
    fig, axes = plt.subplots(1, len(metrics), figsize=(3.2 * len(metrics), 3.2), squeeze=False)
    cell = {(r["policy"], r["metric"]): r for r in rows}
    for ax, m in zip(axes[0], metrics):
        means = [cell[(p, m)]["mean"] for p in policies]
        err = np.array([[cell[(p, m)]["mean"] - cell[(p, m)]["ci_low"], cell[(p, m)]["ci_high"] - cell[(p, m)]["mean"]] for p in policies]).T
        ax.bar(policies, means, yerr=np.nan_to_num(err), capsize=4, color=["tab:blue", "tab:green", "tab:gray"][: len(policies)])
        ax.set_title(m, fontsize=9)
        ax.tick_params(labelsize=8)
    _finish_figure(fig, title, Path(path))


def write_gif(cfg: dict[str, Any], policy_factory, path: Path, seed: int) -> None:
    """One evaluation episode of ``policy_factory`` rendered to a GIF."""
    import imageio.v2 as imageio

    kwargs = {**env_kwargs_of(cfg), "render_mode": "rgb_array"}
    if cfg["eval"]["max_cycles"] is not None:
        kwargs["max_cycles"] = cfg["eval"]["max_cycles"]
    env = make_env(cfg["task"], **kwargs)
    frames: list = []
    run_episode(env, policy_factory(env), seed, cfg["task"], frames=frames)
    env.close()
    tmp = path.with_name(f".tmp-{os.getpid()}-{path.name}")
    try:
        imageio.mimsave(tmp, [np.asarray(f) for f in frames if f is not None], duration=100, loop=0)
        os.replace(tmp, path)
    finally:
        with contextlib.suppress(OSError):
            tmp.unlink()
