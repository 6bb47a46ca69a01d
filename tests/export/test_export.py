"""swarm-export: the exported C99 policy and action decoder against the torch policy and the env.

Each platform's run is an SB3 model built by train.py's own machinery on the config's env and not trained
(random weights are a valid forward pass; the action head is scaled up so actions span [-1, 1] and the clip
is exercised). Observations are recorded from the simulator over two episodes (a reset between them) and
include empty rows. The C is compiled with the host compiler (strict C99, warnings as errors) and called
through ctypes.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml

pytest.importorskip("torch")
pytest.importorskip("stable_baselines3")

from swarm_envs.export.host import compiler  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
needs_cc = pytest.mark.skipif(compiler() is None, reason="no C compiler (cc, gcc or clang) on this machine to build the exported C")

#: platform -> (config, overrides): one task per platform
RUNS = {
    "epuck": ("configs/aggregation.yaml", []),
    "rone": ("configs/sorted_following.yaml", ["agent.encoder=mlp"]),  # the flat MLP with odometry
    "droplet": ("configs/aggregation.yaml", ["env.platform=droplet", "env.message_bits=3", "agent.net_arch=[32, 16]", "agent.activation=relu"]),
}
TOLERANCE = 1e-5  # float32 C vs torch, per action component


def make_run(out: Path, config: str, overrides: list[str]) -> Path:
    """A run folder as train.py writes it (resolved config.yaml + model.zip), the model built but untrained."""
    import torch

    from swarm_envs.agents.config import load_config, resolve
    from swarm_envs.agents.policies import PolicySpec, build_model, wrap_training_env
    from swarm_envs.agents.sb3_vec_env import SwarmVecEnv
    from swarm_envs.agents.tasks import env_id
    from swarm_envs.agents.config import env_kwargs_of

    cfg = load_config(ROOT / config, ["train.n_envs=1", "agent.batch_size=8", *overrides])
    venv = SwarmVecEnv(env_id(cfg["task"]), 1, env_kwargs_of(cfg))
    try:
        spec = PolicySpec.from_agent(cfg["agent"])
        model = build_model(cfg["agent"], wrap_training_env(venv, spec, venv.layout, venv.platform), venv.layout, 0)
    finally:
        venv.close()
    with torch.no_grad():
        model.policy.action_net.weight.mul_(100.0)
    out.mkdir(parents=True, exist_ok=True)
    model.save(out / "model.zip")
    (out / "config.yaml").write_text(yaml.safe_dump(resolve(cfg)), encoding="utf-8")
    return out


def export_case(name: str, run: tuple, tmp_path_factory) -> tuple:
    """(name, loaded run, float export folder) of a quick run made from ``run`` = (config, overrides)."""
    from swarm_envs.export import export_run
    from swarm_envs.export.run import load_run

    base = tmp_path_factory.mktemp(name)
    run_dir = make_run(base / "run", *run)
    export_run(run_dir, base / "c", onnx=False)
    return name, load_run(run_dir), base / "c"


@pytest.fixture(scope="module", params=sorted(RUNS))
def exported(request, tmp_path_factory):
    """(platform, loaded run, float export folder) per platform."""
    return export_case(request.param, RUNS[request.param], tmp_path_factory)


@needs_cc
def test_float_policy_matches_torch(exported):
    """The compiled float32 policy gives torch's deterministic actions (within 1e-5 per component) on the
    simulator's observations, over two episodes with resets and empty rows; with odometry, the C odometry
    matters (the model on the raw observations differs), so the check would see it missing."""
    from swarm_envs.export.compare import action_difference
    from swarm_envs.export.host import compile_shared

    platform, run, folder = exported
    assert run.platform.name == platform
    library = compile_shared(folder)
    worst, empty = action_difference(run, library, seeds=[3, 4], steps=40)
    assert empty > 0, "the recorded observations should include robots with no neighbour row"
    assert worst <= TOLERANCE, f"{platform}: C vs torch action difference {worst}"
    if run.spec.odometry:
        from swarm_envs.agents.base import flatten_batch
        from swarm_envs.agents.evaluation import make_env
        from swarm_envs.export.host import CPolicy

        env = make_env(run.cfg["task"], **run.env_kwargs)
        env.reset(seed=3)
        c = CPolicy(library, run.platform, run.layout, run.obs_size, run.action_size)
        c.reset(env.n_agents)
        raw_gap = 0.0
        for _ in range(40):
            parts = {k: v[env.agent_robots] for k, v in env.batched_observations().items()}
            a = c.act_batch(parts)
            raw, _ = run.model.predict(flatten_batch(run.layout, parts), deterministic=True)
            raw_gap = max(raw_gap, float(np.abs(np.clip(raw, -1, 1) - a).max()))
            env.step({agent: a[i] for i, agent in enumerate(env.possible_agents)})
        env.close()
        assert raw_gap > 1e-3, "odometry changed no action: the check cannot tell whether the C applies it"


@needs_cc
def test_action_decoder(exported):
    """actions_decode gives the env's wheel speeds (wheel_limited of the scaled commands) and message bits."""
    import ctypes

    from swarm_envs.export.actions_c import native_factor
    from swarm_envs.export.host import compile_shared

    platform, run, folder = exported
    lib = ctypes.CDLL(str(compile_shared(folder, ("actions.c",), "libactions.so")))

    class Command(ctypes.Structure):
        _fields_ = [("left", ctypes.c_float), ("right", ctypes.c_float), ("left_native", ctypes.c_int16),
                    ("right_native", ctypes.c_int16), ("message", ctypes.c_uint32)]

    p, bits = run.platform, run.action_size - 2
    rng = np.random.default_rng(0)
    actions = rng.uniform(-1.3, 1.3, (200, run.action_size)).astype(np.float32)
    actions[:4, :2] = [[1, 1], [1, -1], [-1, 0], [0, 0]]
    _, factor, _ = native_factor(p)
    for a in actions:
        cmd = Command()
        lib.actions_decode(a.ctypes.data_as(ctypes.c_void_p), ctypes.byref(cmd))
        c = np.clip(a.astype(np.float64), -1, 1)
        linear, angular = c[0] * p.max_speed, c[1] * p.max_angular_speed
        left = np.clip(linear - angular * p.wheel_base / 2, -p.max_speed, p.max_speed)
        right = np.clip(linear + angular * p.wheel_base / 2, -p.max_speed, p.max_speed)
        assert cmd.left == pytest.approx(left, abs=1e-6 * p.max_speed * 10)
        assert cmd.right == pytest.approx(right, abs=1e-6 * p.max_speed * 10)
        assert abs(cmd.left_native - left * factor) <= 0.5 + 1e-3 and abs(cmd.right_native - right * factor) <= 0.5 + 1e-3
        assert cmd.message == sum(1 << i for i in range(bits) if a[2 + i] > 0)
    if p.name == "epuck":  # full speed is the e-puck motors' 1000 steps/s
        cmd = Command()
        lib.actions_decode(np.array([1, 0], np.float32).ctypes.data_as(ctypes.c_void_p), ctypes.byref(cmd))
        assert cmd.left_native == cmd.right_native == 1000


@needs_cc
@pytest.mark.parametrize("mode", ["q15", "int8"])
def test_fixed_point_policy(exported, mode, tmp_path):
    """The integer build equals its numpy model bit for bit on recorded observations (after the numpy
    odometry, for the r-one run), stays near torch (q15 within 2e-3, int8 within 0.1 per component on these
    weights), and compiles smaller than float32."""
    from swarm_envs.agents.base import flatten_batch
    from swarm_envs.agents.evaluation import make_env
    from swarm_envs.export import export_run
    from swarm_envs.export.export import calibration_observations, observation_bound
    from swarm_envs.export.host import CPolicy, compile_shared, object_sizes
    from swarm_envs.export.network import actor_layers
    from swarm_envs.export.quantize import fixed_forward, quantize

    from swarm_envs.agents.policies import Odometry

    platform, run, float_folder = exported
    export_run(run.run_dir, tmp_path, fixed=mode, onnx=False)
    layers = actor_layers(run.model)
    relu = any(layer.activation == "relu" for layer in layers[:-1])
    net = quantize(layers, observation_bound(run), mode, calibration_observations(run) if relu else None)
    c = CPolicy(compile_shared(tmp_path), run.platform, run.layout, run.obs_size, run.action_size)
    env = make_env(run.cfg["task"], **run.env_kwargs)
    env.reset(seed=5)
    c.reset(env.n_agents)
    odometry = Odometry(run.layout, run.platform) if run.spec.odometry else None
    exact, near = 0.0, 0.0
    for _ in range(30):
        parts = {k: v[env.agent_robots] for k, v in env.batched_observations().items()}
        flat = flatten_batch(run.layout, parts)
        if odometry is not None:
            flat = odometry(flat)
        a = c.act_batch(parts)
        exact = max(exact, float(np.abs(a - fixed_forward(net, flat) / 32768.0).max()))
        torch_a, _ = run.model.predict(flat, deterministic=True)
        near = max(near, float(np.abs(a - np.clip(torch_a, -1, 1)).max()))
        env.step({agent: a[i] for i, agent in enumerate(env.possible_agents)})
    env.close()
    assert exact == 0.0
    assert near <= (2e-3 if mode == "q15" else 0.1), f"{platform} {mode}: {near}"
    assert object_sizes(tmp_path)["text"] < object_sizes(float_folder)["text"]


@needs_cc
def test_in_the_loop_metric(exported):
    """The compiled C policy and the torch policy in the loop, 3 evaluation seeds of 60 steps: the headline
    metric per seed agrees within 1e-4 (actions equal up to ~1e-6, and the physics carries such differences on
    without amplifying them over this horizon; the measured difference is printed)."""
    from swarm_envs.export.compare import evaluate_export

    _, run, folder = exported
    result = evaluate_export(run, folder, seeds=[10, 11, 12], max_cycles=60)
    print(result.text())
    assert np.abs(result.torch - result.c).max() <= 1e-4


@pytest.mark.skipif(compiler() is None, reason="no C compiler")
def test_onnx_matches_c(exported, tmp_path):
    """policy.onnx run by onnxruntime and the compiled C give the same actions on recorded observations."""
    pytest.importorskip("onnx")
    ort = pytest.importorskip("onnxruntime")
    from swarm_envs.agents.base import flatten_batch
    from swarm_envs.agents.evaluation import make_env
    from swarm_envs.export.host import CPolicyLibrary, compile_shared
    from swarm_envs.export.network import write_onnx

    _, run, folder = exported
    if run.spec.odometry:
        pytest.skip("the ONNX graph is the network alone; odometry is the C's pre-processing")
    session = ort.InferenceSession(str(write_onnx(run.model, tmp_path / "policy.onnx")))
    c = CPolicyLibrary(compile_shared(folder), run.obs_size, run.action_size)
    env = make_env(run.cfg["task"], **run.env_kwargs)
    env.reset(seed=6)
    rows = []
    for _ in range(20):
        parts = {k: v[env.agent_robots] for k, v in env.batched_observations().items()}
        rows.append(flatten_batch(run.layout, parts))
        env.step({agent: env.action_space(agent).sample() for agent in env.possible_agents})
    env.close()
    flat = np.concatenate(rows)
    c.reset(len(flat))
    onnx_actions = session.run(None, {"observation": flat})[0]
    assert np.abs(onnx_actions - c.step(flat)).max() <= TOLERANCE


def test_cli_errors(tmp_path, capsys):
    """A missing folder, a folder without model.zip and a fixed-point build of a recurrent policy (float32
    only): exit 2, one clear line, nothing written."""
    from swarm_envs.export.cli import main

    assert main([str(tmp_path / "nope"), "--output", str(tmp_path / "out")]) == 2
    assert "not found" in capsys.readouterr().err
    (tmp_path / "run").mkdir()
    assert main([str(tmp_path / "run"), "--output", str(tmp_path / "out")]) == 2
    assert "no config.yaml and no model.zip" in capsys.readouterr().err
    cfg = {"task": "aggregation", "agent": {"algorithm": "recurrent_ppo"}, "env": {"n_robots": 4}}
    (tmp_path / "run" / "config.yaml").write_text(yaml.safe_dump(cfg))
    (tmp_path / "run" / "model.zip").write_bytes(b"")
    for flags, mode in ((["--fixed", "q15"], "q15"), (["--int8"], "int8")):
        assert main([str(tmp_path / "run"), "--output", str(tmp_path / "out"), *flags]) == 2
        err = capsys.readouterr().err
        assert f"--fixed {mode} is not available for algorithm recurrent_ppo" in err and "supports" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "out").exists()


def test_cli_writes_folder(tmp_path, capsys):
    """``swarm-export RUN --output DIR --fixed q15`` writes the C sources and a README with the layout;
    ``python -m swarm_envs.export --help`` runs."""
    import subprocess
    import sys

    from swarm_envs.export.cli import main

    run_dir = make_run(tmp_path / "run", "configs/aggregation.yaml", ["env.n_robots=4", "agent.net_arch=[8]"])
    out = tmp_path / "c"
    assert main([str(run_dir), "--output", str(out), "--fixed", "q15", "--no-onnx"]) == 0
    assert "wrote 7 files" in capsys.readouterr().out  # policy, actions, observation (.h, .c) and README.md
    assert {p.name for p in out.iterdir()} >= {"policy.h", "policy.c", "actions.h", "actions.c", "README.md"}
    readme = (out / "README.md").read_text()
    assert "swarm_envs/Aggregation-v0" in readme and "| `messages` | 0 |" in readme and "epuck" in readme
    source = (out / "policy.c").read_text()
    assert "int16_t W0" in source and "float" not in source.split("static void forward(")[0]
    done = subprocess.run([sys.executable, "-m", "swarm_envs.export", "--help"], capture_output=True, text=True, cwd=ROOT)
    assert done.returncode == 0 and "--fixed" in done.stdout


#: cross compilers the C is also built with when present: compiler -> (flags, platforms). The Droplet's
#: ATxmega is an AVR (an object there is at most 32 KiB: the r-one's float32 first layer is larger).
CROSS = {
    "arm-none-eabi-gcc": (["-std=c99", "-mcpu=cortex-m3", "-mthumb"], ("epuck", "rone", "droplet")),
    "avr-gcc": (["-std=gnu99", "-mmcu=atxmega128a3u", "-DPOLICY_ROM=__flash"], ("droplet",)),  # weights in flash on the Harvard AVR
}


@pytest.mark.parametrize("cross", sorted(CROSS))
def test_cross_compiles(exported, cross, tmp_path):
    """policy.c and actions.c compile for a microcontroller (Cortex-M3, the r-one's core; the Droplet's
    ATxmega) without warnings, with no writable data (every table constant)."""
    import shutil
    import subprocess

    if shutil.which(cross) is None:
        pytest.skip(f"{cross} is not installed (apt-get install gcc-arm-none-eabi libnewlib-arm-none-eabi / gcc-avr avr-libc)")
    platform, _, folder = exported
    flags, platforms = CROSS[cross]
    if platform not in platforms:
        pytest.skip(f"{cross} targets {', '.join(platforms)}")
    for source in ("policy.c", "actions.c"):
        obj = tmp_path / (source + ".o")
        done = subprocess.run([cross, *flags, "-Os", "-Wall", "-Wextra", "-Werror", "-c", str(folder / source), "-o", str(obj)],
                              capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
        sections = subprocess.run([cross.replace("gcc", "objdump"), "-h", str(obj)], capture_output=True, text=True).stdout
        sizes = {f[1]: int(f[2], 16) for f in (line.split() for line in sections.splitlines()) if len(f) > 3 and f[0].isdigit()}
        assert sizes.get(".data", 0) == 0 and sizes.get(".bss", 0) == 0, sizes


@needs_cc
def test_firmware_tables_through_observation_builder_and_policy_match_torch(exported):
    """The whole exported chain, as the firmware runs it: the firmware-side tables (filled from the
    simulator's sensing state) -> ``obs_build`` -> ``policy_step`` gives torch's deterministic actions on
    the env's own observations (within 1e-5), over an episode with a reset."""
    import ctypes

    from swarm_envs.agents.evaluation import make_env
    from swarm_envs.export.compare import _torch_policy
    from swarm_envs.export.host import CPolicyLibrary, compile_shared
    from swarm_envs.export.observation_c import builder_constants, firmware_tables
    from tests.export.test_export_observation import _ctypes_tables, _fill

    platform, run, folder = exported
    library = compile_shared(folder, sources=("policy.c", "actions.c", "observation.c"), name="libchain.so")
    chain = CPolicyLibrary(library, run.obs_size, run.action_size)
    env = make_env(run.cfg["task"], **run.env_kwargs)
    Tables = _ctypes_tables(builder_constants(env))
    reference = _torch_policy(run, env)
    flat = (ctypes.c_float * run.obs_size)()
    worst = 0.0
    try:
        for seed in (5, 6):
            env.reset(seed=seed)
            reference.reset(env.n_agents)
            chain.reset(env.n_agents)
            for _ in range(25):
                parts = {k: v[env.agent_robots] for k, v in env.batched_observations().items()}
                want = reference.act_batch(parts)
                built = np.zeros((env.n_agents, run.obs_size), np.float32)
                for i, agent in enumerate(env.possible_agents):
                    chain.lib.obs_build(ctypes.byref(_fill(Tables, firmware_tables(env, agent))), flat)
                    built[i] = np.frombuffer(flat, np.float32)
                got = chain.step(built)
                worst = max(worst, float(np.abs(got - want).max()))
                env.step({agent: want[i] for i, agent in enumerate(env.possible_agents)})
    finally:
        env.close()
    assert worst <= TOLERANCE, f"{platform}: tables -> C observation -> C policy vs torch: {worst}"
