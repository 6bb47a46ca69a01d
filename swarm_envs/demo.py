"""Watch a swarm task: run one episode of a policy and write it as a GIF.

``swarm-demo`` (``python -m swarm_envs.demo``)::

    swarm-demo --task flocking --out flocking.gif          # the task's scripted baseline (default policy)
    swarm-demo --task aggregation --policy random --overlay
    swarm-demo --task flocking --policy reynolds_flocking  # another scripted controller, by name
    swarm-demo --task swarm_envs/Flocking-v0 --model runs/flocking/model.zip
    swarm-demo --import examples/custom_task.py --task swarm_examples/Dispersion-v0 --policy random
    swarm-demo --all --out-dir docs/img/envs               # one small GIF per task (the docs' pictures)

The frames (:func:`swarm_envs.adapters.render.render_env`) show the robots with their headings, the IR links that
delivered a decoded reading this step, decoded messages, the task's markers, a caption (task, platform,
policy, step, the task's headline metric) and a legend; ``--overlay`` adds where one robot's range & bearing
observation puts its neighbours next to where they are. At the end the headline metric of the episode is
printed next to the random policy's on the same seed (reduced as :func:`swarm_envs.agents.evaluation.run_episode`
reduces it). Settings not given on the command line come from each task's showcase preset
(:data:`SHOWCASE`).
"""

from __future__ import annotations

import argparse
import os
import sys
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from swarm_envs.agents.evaluation import make_env, run_episode
from swarm_envs.agents.scripted import SCRIPTED
from swarm_envs.agents.tasks import SHORT_NAMES, headline, import_modules, metric_reductions
from swarm_envs.adapters.env import DT
from swarm_envs.sim.platforms import PLATFORMS
from swarm_envs.registry import list_envs, task_class
from swarm_envs.adapters.render import VIEWS
from swarm_envs.tasks.settings import Int
from swarm_envs.tasks.settings_cli import cli_type

#: short task name -> registered env id
TASKS = dict(SHORT_NAMES)

#: per task, the settings a demo uses unless the command line gives them: scenes in which the scripted
#: baseline visibly does its task (docs/environments/<task>.md and the README show the GIFs they make;
#: ``"env"``: further env settings; ``"policy"``: the scripted controller ``--all`` shows instead of the task's
#: baseline). Flocking runs on Droplets, whose top speed, 2 cm/s, is the forward speed of the thesis's flocking
#: robots (20 mm/s [L Alg. 5]), in a 1 m arena (23 body diameters: room to move as a group between walls) for
#: 90 s, time to align, with the Reynolds flocker: alignment alone ([L] Alg. 5) does not keep the group together.
SHOWCASE: dict[str, dict[str, Any]] = {
    "aggregation": {"platform": "epuck", "n_robots": 10, "steps": 300, "seed": 0, "overlay": 0, "frame_skip": 5},
    "flocking": {"platform": "droplet", "n_robots": 16, "steps": 900, "seed": 0, "overlay": None, "frame_skip": 9, "env": {"arena_size": 1.0},
                 "policy": "reynolds_flocking"},
    "centroid_seeking": {"platform": "rone", "n_robots": 1, "steps": 300, "seed": 0, "overlay": 0},
    "sorted_following": {"platform": "rone", "n_robots": None, "steps": 600, "seed": 0, "overlay": None},
    "parity_clustering": {"platform": "rone", "n_robots": None, "steps": 600, "seed": 0, "overlay": None, "frame_skip": 6},
    "mid_angle_navigation": {"platform": "rone", "n_robots": None, "steps": 600, "seed": 1, "overlay": None},
}

#: the settings of a task without a showcase (None: the task's own default)
DEFAULT_SHOWCASE: dict[str, Any] = {"platform": None, "n_robots": None, "steps": 300, "seed": 0, "overlay": None}


def showcase_settings(
    task: str, sensing: str = "full", platform: str | None = None, n_robots: int | None = None, steps: int | None = None,
    env: Any = (),
) -> tuple[dict[str, Any], str, int]:
    """(env settings, shown policy, seed) of ``task``'s showcase scene (:data:`SHOWCASE`, else
    :data:`DEFAULT_SHOWCASE`), with the command line's ``platform``, ``n_robots``, ``steps`` (control steps)
    and further ``env`` settings (pairs) in place of the preset's where given; settings left None are the
    task's own defaults and are dropped."""
    preset = {**DEFAULT_SHOWCASE, **SHOWCASE.get(task, {})}
    env_kwargs: dict[str, Any] = {
        "platform": preset["platform"] if platform is None else platform,
        "sensing": sensing,
        "n_robots": n_robots or preset["n_robots"],
        "max_cycles": steps or preset["steps"],
        **preset.get("env", {}),
        **dict(env),
    }
    return {k: v for k, v in env_kwargs.items() if v is not None}, preset.get("policy", "scripted"), preset["seed"]


#: image settings of ``--all`` unless given: small GIFs for the documentation
DOCS_IMAGE = {"pixels": 320, "frame_skip": 4}
#: image settings of a single demo unless given
IMAGE = {"pixels": 480, "frame_skip": 1}


class DemoError(Exception):
    """A bad demo input, reported as one line (exit code 2)."""


@dataclass
class DemoResult:
    """What one demo episode produced."""

    task: str
    policy: str
    frames: list = field(repr=False)
    steps: int = 0
    metrics: dict[str, float] = field(default_factory=dict)  # reduced as run_episode reduces them


def resolve_task(name: str) -> tuple[str, str]:
    """(task label, env id) of a short name or a registered env id (the label is the short name of the
    suite's first tasks, else the id); :class:`DemoError` otherwise."""
    if name in TASKS:
        return name, TASKS[name]
    if name in list_envs():
        return next((task for task, env_id in TASKS.items() if env_id == name), name), name
    raise DemoError(f"unknown task {name!r}; use one of {sorted(TASKS)} or a registered env id {list_envs()}")


def demo_tasks() -> list[str]:
    """The tasks ``--all`` draws: the suite's own registered tasks that have a scripted baseline."""
    labels = [resolve_task(env_id)[0] for env_id in list_envs() if env_id.startswith("swarm_envs/")]
    return [label for label in labels if task_class(resolve_task(label)[1]).SCRIPTED_POLICY is not None]


def gif_name(task: str) -> str:
    """File name of a task's GIF: ``flocking.gif``, ``sorted_following.gif`` for ``swarm_envs/SortedFollowing-v0``."""
    if task in TASKS:
        return f"{task}.gif"
    name = task.rsplit("/", 1)[-1].rsplit("-v", 1)[0]
    return "".join(f"_{c.lower()}" if c.isupper() and i else c.lower() for i, c in enumerate(name)) + ".gif"


def _headline(task: str, metrics: Any) -> tuple[str, int]:
    """The task's headline metric and sign, or its first metric (higher better) when it declares none."""
    return headline(task) or (next(iter(metrics)), +1)


def _reductions(task: str, metrics: Any) -> dict[str, str]:
    return metric_reductions(task) or dict.fromkeys(metrics, "mean")


def _scripted_policy(env: Any):
    """The scripted baseline of ``env``'s task (its ``Task.SCRIPTED_POLICY``)."""
    from swarm_envs.agents.scripted import make_scripted

    name = type(env.task).SCRIPTED_POLICY
    if name is None:
        raise DemoError(f"task {type(env.task).__name__} has no scripted baseline; use --policy random or --model")
    return make_scripted(name, env)


def load_model_policy(path: str | Path, env: Any):
    """A trained SB3 model ``.zip`` (as ``train.py`` saves it) as a policy for ``env``, run through the policy
    variant of the run's ``config.yaml`` (beside the model, or beside its ``checkpoints/`` folder: odometry,
    action repeat, frame stacking, RecurrentPPO); the plain PPO without one.

    :class:`DemoError` (one line) when the file is not such a model or does not fit the env's flat
    observation or action size."""
    path = Path(path)
    try:
        if not path.exists():
            raise DemoError(f"--model '{path}' does not exist")
        if not path.is_file():
            raise DemoError(f"--model '{path}' is {'a directory' if path.is_dir() else 'not a regular file'}, not a model .zip")
        if not zipfile.is_zipfile(path):
            raise DemoError(f"--model '{path}' is not a zip archive (truncated, or not a stable-baselines3 model)")
    except OSError as err:  # e.g. a name too long for the file system, or a file that cannot be read
        raise DemoError(f"--model '{path}' cannot be read ({err.strerror or err})") from None
    try:
        from swarm_envs.agents.policies import TrainedPolicy, algorithm_class
    except ImportError as err:
        raise DemoError(f"--model needs stable-baselines3 ({err}); pip install 'swarm_envs[rl]'") from None
    from gymnasium.spaces import flatdim

    from swarm_envs.adapters.torch_threads import set_torch_threads

    set_torch_threads()  # 1 thread on <= 2 cores (OMP_NUM_THREADS overrides): inference beside the simulation
    spec = _run_policy_spec(path)
    kind = "RecurrentPPO" if spec.algorithm == "recurrent_ppo" else "PPO"
    try:
        model = algorithm_class(spec).load(path, device="cpu")
    except Exception as err:  # SB3 raises many kinds (KeyError, BadZipFile, ValueError, pickle errors)
        detail = str(err).strip().splitlines()[0] if str(err).strip() else ""
        raise DemoError(f"--model '{path}' cannot be loaded as a {kind} model ({type(err).__name__}{': ' + detail if detail else ''})") from None
    obs_size, act_size = flatdim(env.layout.dict_space()) * spec.frame_stack, env.layout.action_size
    if model.observation_space.shape != (obs_size,):
        raise DemoError(
            f"--model '{path}' expects observations of size {_size(model.observation_space.shape)} but this env gives "
            f"{obs_size}; pass the env settings it was trained with (--env n_neighbours=.. / n_messages=.. / message_bits=..)"
        )
    if model.action_space.shape != (act_size,):
        raise DemoError(f"--model '{path}' gives actions of size {_size(model.action_space.shape)} but this env expects {act_size}")
    return TrainedPolicy(model, env.platform, env.layout, spec, deterministic=True)


def _run_policy_spec(path: Path):
    """The policy variant of the run that saved the model at ``path`` (its ``config.yaml``'s ``agent``
    section; the run directory for ``checkpoints/*.zip``), or the plain PPO's when there is none."""
    import yaml

    from swarm_envs.agents.config import run_config_path
    from swarm_envs.agents.policies import PolicySpec

    config = run_config_path(path)
    if config is None:  # a model saved elsewhere
        return PolicySpec()
    try:
        agent = (yaml.safe_load(config.read_text()) or {}).get("agent") or {}
        return PolicySpec.from_agent(agent)
    except (OSError, UnicodeDecodeError, yaml.YAMLError, AttributeError, TypeError):  # not a run's config
        return PolicySpec()


def _size(shape: tuple[int, ...] | None) -> str:
    return "x".join(str(s) for s in shape) if shape else "?"


def make_policy(kind: str, env: Any, model: str | None = None):
    """The policy of a demo: ``"scripted"`` (the task's baseline), ``"random"``, a scripted controller's name
    (:data:`swarm_envs.agents.scripted.SCRIPTED`) or a PPO ``model`` path."""
    from swarm_envs.agents.scripted import make_scripted

    if model is not None:
        return load_model_policy(model, env)
    if kind == "scripted":
        return _scripted_policy(env)
    if kind == "random":
        from swarm_envs.agents.base import RandomPolicy

        return RandomPolicy(env.platform, env.layout)
    if kind in SCRIPTED:
        try:
            return make_scripted(kind, env)
        except ValueError as err:  # e.g. a controller that needs ids or message bits this env does not give
            raise DemoError(f"--policy {kind}: {err}") from None
    raise DemoError(f"unknown policy {kind!r}; use 'scripted', 'random' or one of {sorted(SCRIPTED)}")


def run_demo(
    task: str,
    env_kwargs: dict[str, Any],
    policy: Any,
    seed: int,
    frame_skip: int = 1,
    pixels: int = 480,
    overlay_agent: int | None = None,
    view: str = "swarm",
) -> DemoResult:
    """One episode of ``policy`` on ``task`` from ``reset(seed=seed)``, drawn every ``frame_skip`` steps.

    The episode is driven as :func:`swarm_envs.agents.evaluation.run_episode` drives it (the policy sees the
    agents' named batched observations; its generator is derived from ``seed`` the same way), so the
    reduced metrics are the same numbers. Frames: the reset, every ``frame_skip``-th step and the last step,
    in the renderer's ``view`` (:data:`swarm_envs.adapters.render.VIEWS`; ``"swarm"`` follows the robots).
    """
    from swarm_envs.adapters.render import Renderer, render_env

    env = make_env(task, **env_kwargs)
    if overlay_agent is not None and not 0 <= overlay_agent < env.n_agents:
        env.close()
        raise ValueError(f"overlay_agent must be in [0, {env.n_agents}), got {overlay_agent}")
    renderer = Renderer(
        env.arena, env.platform, pixels=pixels, fps=env.metadata["render_fps"], obstacles=env.task.obstacle_segments, view=view
    )
    title = (
        f"{resolve_task(task)[1].split('/')[-1]} | {env.platform.name} x {env.n_agents}, {env.config['sensing']} sensing"
        f"\n{getattr(policy, 'name', 'policy')}"
    )
    policy.reset(env.n_agents, rng=np.random.default_rng([seed, 7919]))
    _, infos = env.reset(seed=seed)
    first = infos[env.possible_agents[0]]["metrics"]
    best, _ = _headline(task, first)
    reductions = _reductions(task, first)

    def draw(metrics: dict[str, float]) -> np.ndarray:
        caption = f"{title} | t {env.num_cycles * DT:.1f} / {env.max_cycles * DT:.0f} s | {best} {metrics[best]:.2f}"
        return render_env(env, renderer, caption=caption, overlay_agent=overlay_agent)

    frames = [draw(first)]
    sums = dict.fromkeys(reductions, 0.0)
    last: dict[str, float] = {}
    steps = 0
    while env.agents:
        parts = {k: v[env.agent_robots] for k, v in env.batched_observations().items()}
        actions = np.asarray(policy.act_batch(parts), dtype=np.float64)
        _, _, _, _, infos = env.step({a: actions[i] for i, a in enumerate(env.possible_agents)})
        last = infos[env.possible_agents[0]]["metrics"]
        for name in reductions:
            sums[name] += last[name]
        steps += 1
        if steps % frame_skip == 0 or not env.agents:
            frames.append(draw(last))
    renderer.close()
    env.close()
    metrics = {name: float(last[name] if how == "final" else sums[name] / max(steps, 1)) for name, how in reductions.items()}
    return DemoResult(task, getattr(policy, "name", "policy"), frames, steps, metrics)


def random_baseline(task: str, env_kwargs: dict[str, Any], seed: int) -> dict[str, float]:
    """The random policy's reduced metrics on the same env and seed (no rendering)."""
    from swarm_envs.agents.base import RandomPolicy

    env = make_env(task, **env_kwargs)
    try:
        return run_episode(env, RandomPolicy(env.platform, env.layout), seed, task)
    finally:
        env.close()


def write_gif(frames: list[np.ndarray], path: str | Path, frame_ms: float) -> int:
    """Write RGB frames as a looping GIF with one palette (the renderer's colours), ``frame_ms`` per frame.

    The renderer draws nothing antialiased, so the palette keeps every frame exact; Pillow (``optimize``)
    stores only the changed pixels of each frame. Returns the file size in bytes."""
    from PIL import Image

    from swarm_envs.adapters.render import PALETTE

    palette = Image.new("P", (1, 1))
    palette.putpalette([c for colour in PALETTE for c in colour])
    images = [Image.fromarray(np.asarray(f, np.uint8)).quantize(palette=palette, dither=Image.Dither.NONE) for f in frames]
    images[0].save(path, format="GIF", save_all=True, append_images=images[1:], duration=frame_ms, loop=0, optimize=True)
    return Path(path).stat().st_size


# -- command line ---------------------------------------------------------------------------------------
def _int_at_least(low: int):
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer >= {low}, got {text!r}") from None
        if value < low:
            raise argparse.ArgumentTypeError(f"must be >= {low}, got {value}")
        return value

    return parse


def _env_setting(text: str) -> tuple[str, Any]:
    import yaml

    key, sep, value = text.partition("=")
    key = key.strip()
    if not sep or not key:
        raise argparse.ArgumentTypeError(f"expected KEY=VALUE, got {text!r}")
    own = {"render_mode": "the demo", "platform": "--platform", "sensing": "--sensing", "n_robots": "--n-robots", "max_cycles": "--steps"}
    if key in own:
        raise argparse.ArgumentTypeError(f"{key} is set by {own[key]}")
    try:
        return key, yaml.safe_load(value)
    except yaml.YAMLError as err:
        problem = " ".join(str(getattr(err, "problem", None) or "not valid YAML").split())
        raise argparse.ArgumentTypeError(f"{key}={value!r}: the value is not valid YAML ({problem})") from None


class _Parser(argparse.ArgumentParser):
    """argparse with one-line errors: ``swarm-demo: error: <message>`` and exit code 2 (line breaks in the
    message, e.g. in a path given, become spaces)."""

    def error(self, message: str):
        self.exit(2, f"{self.prog}: error: {' '.join(message.split())} (see {self.prog} --help)\n")


def _parser() -> argparse.ArgumentParser:
    parser = _Parser(prog="swarm-demo", description=__doc__.split("\n\n")[0])
    parser.add_argument("--task", default=None, help=f"short name {sorted(TASKS)} or a registered env id (default flocking)")
    parser.add_argument("--import", dest="imports", action="append", default=[], metavar="MODULE",
                        help="import a module or .py file first, e.g. one that registers a task of your own (repeatable)")
    parser.add_argument("--all", action="store_true", help="one GIF per task, <task>.gif in --out-dir (small documentation GIFs)")
    parser.add_argument("--policy", choices=["scripted", "random", *SCRIPTED], default=None, metavar="POLICY",
                        help=f"scripted (the task's baseline), random, or a scripted controller {sorted(SCRIPTED)}; "
                        "default: the task's scripted baseline (--all: the showcase's)")
    parser.add_argument(
        "--model", default=None, metavar="PATH",
        help="a trained PPO .zip (train.py's model.zip) instead of --policy; torch runs on 1 thread on <= 2 cores (OMP_NUM_THREADS overrides)",
    )
    parser.add_argument("--out", default=None, help="GIF path (default demo.gif); its directory must exist")
    parser.add_argument("--out-dir", default=None, help="with --all: folder for the GIFs (created; default .)")
    parser.add_argument("--platform", default=None, choices=sorted(PLATFORMS), help="droplet, epuck or rone (default: the task's showcase)")
    parser.add_argument("--sensing", default="full", choices=["full", "ideal"])
    parser.add_argument("--n-robots", type=_int_at_least(1), default=None)
    parser.add_argument("--steps", type=_int_at_least(1), default=None, help="episode length in 0.1 s steps")
    parser.add_argument("--seed", type=_int_at_least(0), default=None)
    parser.add_argument("--env", type=_env_setting, action="append", default=[], metavar="KEY=VALUE",
                        help="another env setting, e.g. message_bits=4 (repeatable)")
    parser.add_argument("--overlay", type=_int_at_least(0), nargs="?", const=0, default=None, metavar="AGENT",
                        help="show where agent AGENT's (default 0) range & bearing rows put its neighbours (default: the showcase's)")
    parser.add_argument("--no-overlay", action="store_true", help="no overlay, whatever the showcase")
    parser.add_argument("--frame-skip", type=cli_type(Int(1, low=1, high=1_000_000), "--frame-skip"), default=None,
                        help="draw every k-th step; the GIF shows 10 frames/s, so k x real time (default 1; --all: 4)")
    # at most 4096 pixels: one frame is pixels^2 x 3 bytes (48 MB at 4096), and the GIF keeps every frame
    parser.add_argument("--view", choices=list(VIEWS), default="swarm",
                        help="swarm: a square that follows the robots (default); arena: the whole arena in every frame")
    parser.add_argument("--pixels", type=cli_type(Int(480, low=160, high=4096), "--pixels"), default=None,
                        help="image size, 160-4096 (default 480; --all: 320)")
    return parser


def _check_writable_dir(folder: Path, what: str) -> str | None:
    if not folder.is_dir():
        return f"{what} directory '{folder}' does not exist"
    if not os.access(folder, os.W_OK):
        return f"{what} directory '{folder}' is not writable"
    return None


def _check_writable_file(path: Path, what: str, parser: argparse.ArgumentParser) -> None:
    """A usage error naming ``path`` unless it can be opened for writing (checked before the episode runs, e.g.
    ``/proc/x.gif``, which a directory check passes as root); a file this check creates is removed again."""
    try:
        existed = path.exists()
        with open(path, "ab"):
            pass
        if not existed:
            path.unlink(missing_ok=True)
    except OSError as err:
        parser.error(f"{what} '{path}' cannot be written ({err.strerror or err})")


def _jobs(args: argparse.Namespace, parser: argparse.ArgumentParser) -> list[tuple[str, Path]]:
    """(task, output path) of every GIF the command asks for; argparse errors for bad combinations."""
    if args.all:
        if args.task is not None or args.out is not None:
            parser.error("--all writes every task to --out-dir; leave out --task and --out")
        if args.model is not None:
            parser.error("--model fits one env; use --task with it, not --all")
        if args.out_dir is not None and not args.out_dir.strip():
            parser.error(f"--out-dir {args.out_dir!r} names no folder; leave it out for the current folder")
        out_dir = Path(args.out_dir or ".")
        try:
            out_dir.mkdir(parents=True, exist_ok=True)
        except OSError as err:
            parser.error(f"--out-dir '{out_dir}' cannot be created ({err.strerror or err})")
        problem = _check_writable_dir(out_dir, "--out-dir")
        if problem:
            parser.error(problem)
        jobs = [(task, out_dir / gif_name(task)) for task in demo_tasks()]
        for _, path in jobs:
            _check_writable_file(path, "--out-dir", parser)
        return jobs
    if args.out_dir is not None:
        parser.error("--out-dir goes with --all; give a single demo's path with --out")
    try:
        import_modules(args.imports)
    except ImportError as err:
        parser.error(str(err))
    if args.model is not None and args.policy is not None:
        parser.error("give either --policy or --model, not both")
    try:
        task, _ = resolve_task("flocking" if args.task is None else args.task)  # --task '' is an unknown task, not the default
    except DemoError as err:
        parser.error(str(err))
    if args.out is not None and not args.out.strip():
        parser.error(f"--out {args.out!r} names no file; give a GIF path such as demo.gif")
    out = Path(args.out or "demo.gif")
    try:
        if out.is_dir():
            parser.error(f"--out '{out}' is a directory; give a file path such as {out / 'demo.gif'}")
        problem = _check_writable_dir(out.parent if str(out.parent) else Path("."), "--out")
        if problem:
            parser.error(problem)
        _check_writable_file(out, "--out", parser)
    except OSError as err:  # e.g. a name too long for the file system, which even is_dir() raises for
        parser.error(f"--out '{out}' cannot be written ({err.strerror or err})")
    return [(task, out)]


def main(argv: list[str] | None = None) -> int:
    """Command line of ``swarm-demo``; returns 0, or exits with code 2 and one error line for bad input."""
    parser = _parser()
    args = parser.parse_args(argv)
    jobs = _jobs(args, parser)
    image = DOCS_IMAGE if args.all else IMAGE
    pixels = args.pixels or image["pixels"]
    for task, out in jobs:
        preset = {**DEFAULT_SHOWCASE, **SHOWCASE.get(task, {})}
        # a showcase may draw fewer frames (a busy scene keeps its GIF small)
        frame_skip = args.frame_skip or (preset.get("frame_skip", image["frame_skip"]) if args.all else image["frame_skip"])
        env_kwargs, preset_policy, preset_seed = showcase_settings(task, args.sensing, args.platform, args.n_robots, args.steps, args.env)
        seed = preset_seed if args.seed is None else args.seed
        overlay = None if args.no_overlay else preset["overlay"] if args.overlay is None else args.overlay
        try:
            probe = make_env(task, **env_kwargs)  # checks every setting before anything runs
        except (TypeError, ValueError) as err:  # unknown keys, bad values (SettingsError is a ValueError)
            parser.error(f"bad env setting: {str(err).splitlines()[0]}")
        try:
            if overlay is not None and overlay >= probe.n_agents:
                raise DemoError(f"--overlay {overlay}: this env has agents 0 .. {probe.n_agents - 1}")
            shown_policy = args.policy or (preset_policy if args.all else "scripted")
            policy = make_policy(shown_policy, probe, args.model)
        except DemoError as err:
            parser.error(str(err))
        finally:
            probe.close()
        result = run_demo(task, env_kwargs, policy, seed, frame_skip, pixels, overlay, args.view)
        try:
            size = write_gif(result.frames, out, 1000.0 * DT)  # one frame per 0.1 s: frame_skip x real time
        except OSError as err:  # e.g. the disk filled up, or the folder went away during the episode
            parser.error(f"{'--out-dir' if args.all else '--out'} '{out}' cannot be written ({err.strerror or err})")
        _report(result, out, size, frame_skip, env_kwargs, seed)
    return 0


def _report(result: DemoResult, out: Path, size: int, frame_skip: int, env_kwargs: dict[str, Any], seed: int) -> None:
    name, sign = _headline(result.task, result.metrics)
    how = _reductions(result.task, result.metrics)[name]
    every = f", every {frame_skip} steps" if frame_skip > 1 else ""
    print(f"wrote {out}: {len(result.frames)} frames ({result.steps} steps{every}), {size / 1000:.0f} kB")
    print("  settings: " + ", ".join(f"{k}={v}" for k, v in env_kwargs.items()))
    text = f"{name} ({'mean over the episode' if how == 'mean' else 'at the end'}, {'higher' if sign > 0 else 'lower'} is better), seed {seed}: "
    text += f"{result.policy} {result.metrics[name]:.3f}"
    if result.policy != "random":
        text += f", random {random_baseline(result.task, env_kwargs, seed)[name]:.3f}"
    print(text)
    print("  " + ", ".join(f"{k}={v:.3f}" for k, v in result.metrics.items()))


if __name__ == "__main__":
    sys.exit(main())
