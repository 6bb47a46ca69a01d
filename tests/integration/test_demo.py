"""``swarm-demo`` (``python -m swarm_envs.demo``) and the frames it draws (:mod:`swarm_envs.adapters.render`)."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from swarm_envs.adapters import render
from swarm_envs.agents.base import RandomPolicy
from swarm_envs.agents.evaluation import make_env, run_episode
from swarm_envs.agents.tasks import headline, scripted_policy
from swarm_envs.agents.scripted import make_scripted, scripted_class
import swarm_envs
from swarm_envs.demo import SHOWCASE, TASKS, DemoError, _scripted_policy, main
from swarm_envs.sensing.base import MessageReadings, NeighbourReadings, ScaleFreeReadings, SensorFrame

SMALL = ["--sensing", "ideal", "--n-robots", "3", "--pixels", "200"]


def _gif_frames(path) -> tuple[int, list[int]]:
    with Image.open(path) as gif:
        delays = []
        for i in range(gif.n_frames):
            gif.seek(i)
            delays.append(gif.info["duration"])
        return gif.n_frames, delays


def _one_line_error(capsys, argv: list[str], *words: str) -> str:
    with pytest.raises(SystemExit) as exit_info:
        main(argv)
    assert exit_info.value.code == 2
    err = capsys.readouterr().err
    assert "Traceback" not in err
    assert len(err.strip().splitlines()) == 1, err
    for word in words:
        assert word in err, err
    return err


def test_demo_gif_frame_delays_are_100_ms(tmp_path, capsys):
    out = tmp_path / "demo.gif"
    steps = 4
    assert main(["--task", "flocking", "--sensing", "ideal", "--n-robots", "3", "--steps", str(steps), "--out", str(out)]) == 0
    assert f"{steps + 1} frames" in capsys.readouterr().out
    with Image.open(out) as gif:
        assert gif.format == "GIF"
        assert gif.n_frames == steps + 1  # reset frame + one per step, none merged away
        assert gif.info.get("loop") == 0  # loops forever
    _, delays = _gif_frames(out)
    assert delays == pytest.approx([100] * (steps + 1))  # 1000 ms / render_fps (10)


def test_frame_skip_gives_the_expected_frame_count(tmp_path, capsys):
    out = tmp_path / "skip.gif"
    assert main(["--task", "aggregation", *SMALL, "--steps", "7", "--frame-skip", "3", "--out", str(out)]) == 0
    n, delays = _gif_frames(out)
    assert n == 4  # the reset, steps 3 and 6, and the last step 7
    assert delays == [100] * 4  # 10 frames per second: 3 x real time
    with Image.open(out) as gif:
        assert gif.size == (200, 200)


@pytest.mark.parametrize("task", sorted(TASKS))
def test_default_policy_is_the_tasks_scripted_baseline(task, tmp_path, capsys):
    env = make_env(task, sensing="ideal", n_robots=3)
    assert isinstance(_scripted_policy(env), scripted_class(scripted_policy(task)))
    name = scripted_class(scripted_policy(task)).name
    env.close()
    out = tmp_path / f"{task}.gif"
    assert main(["--task", task, *SMALL, "--steps", "6", "--seed", "3", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert name in text and "random" in text
    # the printed numbers are run_episode's for the same seed (the evaluator's reduction of the metrics)
    kwargs = {"platform": SHOWCASE[task]["platform"] or "epuck", "sensing": "ideal", "n_robots": 3, "max_cycles": 6, **SHOWCASE[task].get("env", {})}
    env = make_env(task, **kwargs)
    scripted = run_episode(env, make_scripted(scripted_policy(task), env), 3, task)
    random = run_episode(env, RandomPolicy(env.platform, env.layout), 3, task)
    env.close()
    metric = headline(task)[0]
    assert f"{name} {scripted[metric]:.3f}, random {random[metric]:.3f}" in text


def test_random_policy_and_an_env_id(tmp_path, capsys):
    out = tmp_path / "random.gif"
    assert main(["--task", "swarm_envs/Aggregation-v0", "--policy", "random", *SMALL, "--steps", "3", "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "seed 0: random " in text and "bearing_aggregation" not in text
    assert _gif_frames(out)[0] == 4


def test_bad_arguments_give_one_line_errors(tmp_path, capsys):
    _one_line_error(capsys, ["--steps", "-1", "--out", str(tmp_path / "x.gif")], "--steps", ">= 1")
    _one_line_error(capsys, ["--out", "/nonexistent/dir/x.gif"], "/nonexistent/dir", "does not exist")
    _one_line_error(capsys, ["--task", "herding", "--out", str(tmp_path / "x.gif")], "unknown task 'herding'")
    _one_line_error(capsys, ["--out", str(tmp_path)], "is a directory")
    _one_line_error(capsys, ["--n-robots", "0", "--out", str(tmp_path / "x.gif")], "--n-robots")
    _one_line_error(capsys, ["--env", "rb_noise=-3", *SMALL, "--out", str(tmp_path / "x.gif")], "rb_noise")
    _one_line_error(capsys, ["--overlay", "5", *SMALL, "--steps", "2", "--out", str(tmp_path / "x.gif")], "--overlay")
    _one_line_error(capsys, ["--all", "--task", "flocking"], "--all")
    assert not list(tmp_path.iterdir())  # nothing written


def test_model_runs_and_a_mismatching_model_is_refused(tmp_path, capsys):
    pytest.importorskip("stable_baselines3")
    from stable_baselines3 import PPO

    from swarm_envs.agents.sb3_vec_env import SwarmVecEnv

    def saved_model(path, **env_kwargs):
        vec = SwarmVecEnv("swarm_envs/Flocking-v0", 1, {"sensing": "ideal", "n_robots": 3, **env_kwargs})
        PPO("MlpPolicy", vec, n_steps=8, batch_size=8, seed=0, device="cpu").save(path)  # untrained, the right sizes
        vec.close()
        return path

    good = saved_model(tmp_path / "good.zip")
    out = tmp_path / "ppo.gif"
    import torch

    from swarm_envs.adapters.torch_threads import default_torch_threads

    before = torch.get_num_threads()
    torch.set_num_threads(default_torch_threads() + 1)
    try:
        assert main(["--task", "flocking", "--model", str(good), *SMALL, "--steps", "3", "--out", str(out)]) == 0
        assert torch.get_num_threads() == default_torch_threads()  # the demo sets the thread default
    finally:
        torch.set_num_threads(before)
    assert "seed 0: ppo " in capsys.readouterr().out
    assert _gif_frames(out)[0] == 4

    other = saved_model(tmp_path / "other.zip", n_neighbours=4)
    _one_line_error(capsys, ["--task", "flocking", "--model", str(other), *SMALL, "--out", str(tmp_path / "x.gif")],
                    "expects observations of size", "--env")
    # the same model runs once the env has its settings
    assert main(["--task", "flocking", "--model", str(other), "--env", "n_neighbours=4", *SMALL, "--steps", "2", "--out", str(out)]) == 0
    not_zip = tmp_path / "model.zip"
    not_zip.write_text("not a model")
    _one_line_error(capsys, ["--model", str(not_zip), "--out", str(out)], "not a zip archive")
    _one_line_error(capsys, ["--model", str(good), "--policy", "random", "--out", str(out)], "either --policy or --model")


def test_all_writes_one_gif_per_task(tmp_path, capsys):
    out_dir = tmp_path / "envs"
    assert main(["--all", "--out-dir", str(out_dir), *SMALL, "--steps", "4"]) == 0
    assert sorted(p.name for p in out_dir.iterdir()) == sorted(f"{task}.gif" for task in TASKS)
    for task in TASKS:
        assert _gif_frames(out_dir / f"{task}.gif")[0] == 2  # --all draws every 4th step: the reset and step 4


def test_overlay_runs_with_full_sensing(tmp_path, capsys):
    out = tmp_path / "overlay.gif"
    assert main(["--task", "aggregation", "--n-robots", "5", "--steps", "6", "--overlay", "2", "--pixels", "240", "--out", str(out)]) == 0
    assert _gif_frames(out)[0] == 7


@pytest.mark.parametrize("platform", ["epuck", "rone"])
def test_overlay_puts_ideal_estimates_on_the_true_neighbours(platform):
    """With exact sensing the estimates from the observation rows are where the named robots are."""
    env = make_env("aggregation", sensing="ideal", n_robots=6, platform=platform)
    env.reset(seed=2)
    for _ in range(3):
        env.step({a: np.array([0.5, 0.3]) for a in env.agents})
    for agent in range(env.n_agents):
        overlay = render.overlay_of(env, agent)
        rows = env.batched_observations()["range_bearing"][env.agent_robots[agent]]
        assert len(overlay.estimates) == int((rows[:, 0] > 0.5).sum())
        np.testing.assert_allclose(overlay.estimates, overlay.truths, atol=1e-5)
    assert len(overlay.estimates) > 0
    env.close()


def test_neighbour_overlay_geometry():
    # a robot at (1, 0) facing +y sees a neighbour 0.5 m away on its right (bearing -pi/2), heading back at it
    rows = np.zeros((3, 7))
    rows[0] = [1, 0.5, 0.0, -1.0, 0.0, 1.0, 0]  # its heading, +pi/2 from the robot's, is world pi
    rows[1] = [1, 0.0, 1.0, 0.0, 1.0, 0.0, 4]  # no range (bearing only): straight ahead, at the true distance
    truths = np.array([[1.5, 0.0], [1.0, 2.0], [np.nan, np.nan]])
    overlay = render.neighbour_overlay(7, rows, np.array([1.0, 0.0]), np.pi / 2, truths)
    np.testing.assert_allclose(overlay.estimates, [[1.5, 0.0], [1.0, 2.0]], atol=1e-12)
    np.testing.assert_allclose(np.cos(overlay.headings), [-1.0, 0.0], atol=1e-12)  # first faces -x: back at the robot
    assert overlay.bearing_only.tolist() == [False, True] and overlay.ages.tolist() == [0, 4] and overlay.robot == 7


def test_only_fresh_readings_and_messages_are_drawn_as_links():
    neighbours = NeighbourReadings(
        rx=np.array([0, 1, 2]), tx=np.array([1, 0, 1]), range=np.ones(3), bearing=np.zeros(3), heading=np.zeros(3), age=np.array([0.0, 3.0, 0.0])
    )
    messages = MessageReadings(receiver=np.array([2]), sender=np.array([0]), bearing=np.zeros(1), payload=np.zeros((1, 1)))
    frame = SensorFrame(neighbours, messages, ScaleFreeReadings(np.zeros((3, 1, 2)), np.zeros((3, 1), bool), np.zeros(3, bool)))
    rx, tx = render.fresh_links(frame)
    assert rx.tolist() == [0, 2] and tx.tolist() == [1, 1]
    rx, tx = render.message_links(frame)
    assert rx.tolist() == [2] and tx.tolist() == [0]


def test_frame_shows_links_messages_caption_and_legend_in_the_palette():
    env = make_env("flocking", sensing="ideal", n_robots=4, message_bits=2)
    env.reset(seed=0)
    env.step({a: np.array([0.2, 0.0, 1.0, -1.0]) for a in env.agents})
    renderer = render.Renderer(env.arena, env.platform, pixels=300)
    frame = render.render_env(env, renderer, caption="Flocking-v0 | a caption\nsecond line", overlay_agent=0)
    assert frame.shape == (300, 300, 3) and frame.dtype == np.uint8
    colours = {tuple(c) for c in np.unique(frame.reshape(-1, 3), axis=0)}
    assert colours <= set(render.PALETTE)  # nothing antialiased: a GIF with this palette is exact
    assert {render._LINK, render._MESSAGE, render._ESTIMATE, render._TEXT, render._MARKER} <= colours
    plain = renderer.draw(env.world.positions, env.world.headings)  # no caption, no legend: no text
    assert render._TEXT not in {tuple(c) for c in np.unique(plain.reshape(-1, 3), axis=0)}
    renderer.close()
    env.close()


def test_model_runs_through_its_runs_policy_variant(tmp_path):
    """A model saved by train.py with a policy variant (here odometry and two stacked frames) runs through
    that variant, read from the run's config.yaml (beside the model or its checkpoints/ folder)."""
    pytest.importorskip("stable_baselines3")
    import yaml

    from swarm_envs.agents.config import DEFAULTS
    from swarm_envs.agents.policies import PolicySpec, build_model, wrap_training_env
    from swarm_envs.agents.sb3_vec_env import SwarmVecEnv
    from swarm_envs.demo import load_model_policy

    agent = {**DEFAULTS["agent"], "n_steps": 8, "batch_size": 8, "odometry": True, "frame_stack": 2}
    vec = SwarmVecEnv("swarm_envs/Flocking-v0", 1, {"sensing": "ideal", "n_robots": 3})
    spec = PolicySpec.from_agent(agent)
    model = build_model(agent, wrap_training_env(vec, spec, vec.layout, vec.platform), vec.layout, seed=0)
    (tmp_path / "checkpoints").mkdir()
    model.save(tmp_path / "checkpoints" / "ppo_8_steps.zip")
    vec.close()
    env = swarm_envs.make("swarm_envs/Flocking-v0", sensing="ideal", n_robots=3)
    with pytest.raises(DemoError, match="expects observations of size"):  # no run config: the plain PPO's size
        load_model_policy(tmp_path / "checkpoints" / "ppo_8_steps.zip", env)
    (tmp_path / "config.yaml").write_text(yaml.safe_dump({"agent": agent}))
    policy = load_model_policy(tmp_path / "checkpoints" / "ppo_8_steps.zip", env)
    assert policy.spec == spec and policy.odometry is not None
    assert main(["--task", "flocking", "--model", str(tmp_path / "checkpoints" / "ppo_8_steps.zip"), *SMALL, "--steps", "3",
                 "--out", str(tmp_path / "v.gif")]) == 0
