"""swarm-export for the policy variants beyond the flat MLP: the DeepSets encoder, RecurrentPPO's LSTM, action
repeat and frame stacking (with odometry), alone and combined.

Each run is a model built by train.py's own machinery (``tests/export/test_export.py``'s ``make_run``: untrained, the
action head scaled up so the clip is exercised), with small networks. The reference is the torch policy through
the pipeline train.py evaluates with (:class:`swarm_envs.agents.policies.TrainedPolicy`: odometry every step, a
decision every ``action_repeat`` steps, SB3's frame stacking, ``model.predict(obs, state, episode_start)`` for
the LSTM), on observations recorded from the simulator over two episodes with a reset between them.
"""

from __future__ import annotations

import numpy as np
import pytest

pytest.importorskip("torch")
pytest.importorskip("stable_baselines3")
pytest.importorskip("sb3_contrib")

from swarm_envs.export.host import compiler  # noqa: E402
from tests.export.test_export import TOLERANCE, export_case  # noqa: E402

needs_cc = pytest.mark.skipif(compiler() is None, reason="no C compiler (cc, gcc or clang) on this machine to build the exported C")

SMALL = ["agent.net_arch=[16]", "agent.set_embedding=8", "agent.lstm_hidden=8"]
#: variant -> (config, overrides)
VARIANTS = {
    "deepsets_stack2": ("configs/aggregation.yaml", [*SMALL, "agent.encoder=deepsets", "agent.frame_stack=2", "agent.activation=relu"]),
    "recurrent": ("configs/aggregation.yaml", [*SMALL, "agent.algorithm=recurrent_ppo"]),
    "stack3_repeat2_odometry": ("configs/sorted_following.yaml", [*SMALL, "agent.encoder=mlp", "agent.frame_stack=3", "agent.action_repeat=2"]),
    "all_droplet": ("configs/aggregation.yaml", [*SMALL, "env.platform=droplet", "env.message_bits=3", "agent.activation=relu",
                                                 "agent.encoder=deepsets", "agent.algorithm=recurrent_ppo", "agent.odometry=true",
                                                 "agent.frame_stack=2", "agent.action_repeat=3"]),
}


@pytest.fixture(scope="module", params=sorted(VARIANTS))
def exported(request, tmp_path_factory):
    """(variant, loaded run, float export folder)."""
    return export_case(request.param, VARIANTS[request.param], tmp_path_factory)


def _episodes(run, policies, seeds, steps, reset=None):
    """Drive the env with the first policy's actions over ``seeds`` (an episode each); ``reset[i]``: reset policy i
    at every episode start (else only at the first). Returns per policy the actions (episode, step, N, A) and the
    count of robots seen with no neighbour row."""
    from swarm_envs.agents.evaluation import make_env

    reset = reset or [True] * len(policies)
    env = make_env(run.cfg["task"], **run.env_kwargs)
    out, empty = [[] for _ in policies], 0
    try:
        for e, seed in enumerate(seeds):
            env.reset(seed=seed)
            for policy, again in zip(policies, reset, strict=True):
                if e == 0 or again:
                    policy.reset(env.n_agents)
            for lst in out:
                lst.append([])
            for _ in range(steps):
                parts = {k: v[env.agent_robots] for k, v in env.batched_observations().items()}
                empty += int((parts["range_bearing"][..., 0] < 0.5).all(axis=1).sum())
                actions = [p.act_batch(parts) for p in policies]
                for lst, a in zip(out, actions):
                    lst[-1].append(a)
                env.step({agent: actions[0][i] for i, agent in enumerate(env.possible_agents)})
    finally:
        env.close()
    return [np.array(a) for a in out], empty


@needs_cc
def test_variant_matches_torch(exported):
    """The compiled float32 policy gives the torch pipeline's deterministic actions within 1e-5 per component over
    two episodes (a reset between them, rows left empty included); a stateful policy not reset at the second
    episode differs there (so the check sees whether ``policy_reset`` clears the held action, the frames and the
    LSTM state)."""
    from swarm_envs.export.compare import _c_policy, _torch_policy
    from swarm_envs.export.host import compile_shared

    name, run, folder = exported
    library = compile_shared(folder)
    from swarm_envs.agents.evaluation import make_env

    env = make_env(run.cfg["task"], **run.env_kwargs)
    torch_p, c_p, stale = _torch_policy(run, env), _c_policy(run, library, env), _c_policy(run, library, env)
    env.close()
    (a_torch, a_c, a_stale), empty = _episodes(run, [torch_p, c_p, stale], seeds=[3, 4], steps=30, reset=(True, True, False))
    assert empty > 0, "the recorded observations should include robots with no neighbour row"
    worst = float(np.abs(a_torch - a_c).max())
    print(f"{name}: largest |C - torch| {worst:.3g}")
    assert worst <= TOLERANCE, f"{name}: C vs torch action difference {worst}"
    stateful = run.spec.algorithm == "recurrent_ppo" or run.spec.frame_stack > 1 or run.spec.action_repeat > 1
    if stateful:
        assert np.abs(a_stale[0] - a_torch[0]).max() <= TOLERANCE
        assert np.abs(a_stale[1] - a_torch[1]).max() > 1e-3, f"{name}: the episode start changed nothing the check can see"


@needs_cc
def test_action_repeat_holds(exported):
    """With action_repeat k the C returns one action for k control steps, and decides again at every k-th call
    (counted from policy_reset)."""
    from swarm_envs.export.compare import _c_policy
    from swarm_envs.export.host import compile_shared

    _, run, folder = exported
    k = run.spec.action_repeat
    if k == 1:
        pytest.skip("no action repeat in this variant")
    from swarm_envs.agents.evaluation import make_env

    env = make_env(run.cfg["task"], **run.env_kwargs)
    c = _c_policy(run, compile_shared(folder), env)
    env.close()
    (actions,), _ = _episodes(run, [c], seeds=[7], steps=4 * k)
    actions = actions[0]
    for start in range(0, 4 * k, k):
        assert all(np.array_equal(actions[start], actions[start + j]) for j in range(1, k))
    assert any(not np.array_equal(actions[s], actions[s + k]) for s in range(0, 3 * k, k))


@needs_cc
def test_variant_in_the_loop_metric(exported):
    """The compiled C policy and the torch policy in the loop, 2 evaluation seeds of 40 steps: the headline metric
    per seed agrees within 1e-4 (the measured difference is printed)."""
    from swarm_envs.export.compare import evaluate_export

    name, run, folder = exported
    result = evaluate_export(run, folder, seeds=[10, 11], max_cycles=40)
    print(name, result.text())
    assert np.abs(result.torch - result.c).max() <= 1e-4


@needs_cc
def test_onnx_matches_c(exported, tmp_path):
    """policy.onnx run by onnxruntime gives the C's actions on recorded observations (within 1e-5): its input the
    stacked observations (zeros before the first), for the LSTM with h and c carried from step to step and zeroed
    at the episode start."""
    pytest.importorskip("onnx")
    ort = pytest.importorskip("onnxruntime")
    from swarm_envs.agents.base import flatten_batch
    from swarm_envs.agents.evaluation import make_env
    from swarm_envs.export.host import CPolicyLibrary, compile_shared
    from swarm_envs.export.network import write_onnx

    name, run, folder = exported
    if run.spec.odometry or run.spec.action_repeat > 1:
        pytest.skip("the ONNX graph is the network alone; odometry and action repeat are the C's pipeline")
    session = ort.InferenceSession(str(write_onnx(run.model, tmp_path / "policy.onnx")))
    c = CPolicyLibrary(compile_shared(folder), run.obs_size, run.action_size)
    env = make_env(run.cfg["task"], **run.env_kwargs)
    recurrent, k = run.spec.algorithm == "recurrent_ppo", run.spec.frame_stack
    worst, moved = 0.0, 0.0
    try:
        for seed in (6, 7):
            env.reset(seed=seed)
            c.reset(env.n_agents)
            shape = (1, env.n_agents, run.spec.lstm_hidden)
            h, cell = np.zeros(shape, np.float32), np.zeros(shape, np.float32)
            stack = np.zeros((env.n_agents, k * run.obs_size), np.float32)
            for _ in range(20):
                parts = {key: v[env.agent_robots] for key, v in env.batched_observations().items()}
                flat = flatten_batch(run.layout, parts)
                stack = np.concatenate([stack[:, run.obs_size :], flat], axis=1)
                if recurrent:
                    got, h, cell = session.run(None, {"observation": stack, "h": h, "c": cell})
                    moved = max(moved, float(np.abs(h).max()))
                else:
                    got = session.run(None, {"observation": stack})[0]
                worst = max(worst, float(np.abs(got - c.step(flat)).max()))
                env.step({agent: env.action_space(agent).sample() for agent in env.possible_agents})
    finally:
        env.close()
    assert worst <= TOLERANCE, f"{name}: onnxruntime vs C {worst}"
    assert not recurrent or moved > 1e-3


class _FixedModel:
    """A model whose deterministic action is the fixed-point network's (the bit-exact numpy model)."""

    def __init__(self, net) -> None:
        self.net = net

    def predict(self, observation, **_):
        from swarm_envs.export.quantize import fixed_forward

        return (fixed_forward(self.net, observation) / 32768.0).astype(np.float32), None


@needs_cc
@pytest.mark.parametrize("mode", ["q15", "int8"])
def test_fixed_point_variants(exported, mode, tmp_path):
    """The integer builds of the DeepSets policy (frame stack 2, ReLU) and of the MLP policy with odometry, frame
    stack 3 and action repeat 2 equal, bit for bit, the numpy model of their integer network run through the same
    pipeline (TrainedPolicy), and stay near torch (q15 within 2e-3, int8 within 0.1 per component); a recurrent
    policy's fixed-point build is refused with one line."""
    from swarm_envs.agents.evaluation import make_env
    from swarm_envs.agents.policies import TrainedPolicy
    from swarm_envs.export import ExportError, export_run
    from swarm_envs.export.compare import _c_policy, _torch_policy
    from swarm_envs.export.export import fixed_network
    from swarm_envs.export.host import compile_shared
    from swarm_envs.export.network import actor_network

    name, run, _ = exported
    if run.spec.algorithm != "ppo":
        with pytest.raises(ExportError, match=f"--fixed {mode} is not available") as err:
            export_run(run.run_dir, tmp_path, fixed=mode, onnx=False)
        assert "\n" not in str(err.value) and not any(tmp_path.iterdir())
        return
    export_run(run.run_dir, tmp_path, fixed=mode, onnx=False)
    net = fixed_network(run, actor_network(run.model), mode)
    assert (net.features is not None) == (run.spec.encoder == "deepsets")
    env = make_env(run.cfg["task"], **run.env_kwargs)
    c = _c_policy(run, compile_shared(tmp_path), env)
    model_q = TrainedPolicy(_FixedModel(net), env.platform, env.layout, run.spec)
    reference = _torch_policy(run, env)
    env.close()
    (a_c, a_q, a_torch), _ = _episodes(run, [c, model_q, reference], seeds=[5, 6], steps=20)
    assert np.array_equal(a_c, a_q)
    near = float(np.abs(a_c - a_torch).max())
    print(f"{name} {mode}: largest |C - torch| {near:.3g}")
    assert near <= (2e-3 if mode == "q15" else 0.1), f"{name} {mode}: {near}"


def test_readme_describes_state(exported):
    """The folder's README names the variant's state (held action, stacked frames, LSTM) and the network."""
    _, run, folder = exported
    readme = (folder / "README.md").read_text()
    assert run.spec.name in readme
    assert ("held action" in readme) == (run.spec.action_repeat > 1)
    assert ("decision observations" in readme) == (run.spec.frame_stack > 1)
    assert ("LSTM" in readme) == (run.spec.algorithm == "recurrent_ppo")
    assert ("DeepSets" in readme) == (run.spec.encoder == "deepsets")
    header = (folder / "policy.h").read_text()
    assert f"#define POLICY_FRAME_STACK {run.spec.frame_stack}" in header and f"#define POLICY_ACTION_REPEAT {run.spec.action_repeat}" in header


@pytest.mark.parametrize("cross", ["arm-none-eabi-gcc", "avr-gcc"])
def test_variant_cross_compiles(exported, cross, tmp_path):
    """policy.c (float32, and q15 for a PPO run) compiles without warnings for a Cortex-M3 (and, for the Droplet
    run, the ATxmega with the tables in flash), with no writable data: the state is all in the caller's
    policy_state_t."""
    import shutil
    import subprocess

    from swarm_envs.export import export_run
    from tests.export.test_export import CROSS

    if shutil.which(cross) is None:
        pytest.skip(f"{cross} is not installed")
    _, run, folder = exported
    flags, platforms = CROSS[cross]
    if run.platform.name not in platforms:
        pytest.skip(f"{cross} targets {', '.join(platforms)}")
    folders = [folder]
    if run.spec.algorithm == "ppo":
        export_run(run.run_dir, tmp_path / "q15", fixed="q15", onnx=False)
        folders.append(tmp_path / "q15")
    for source in folders:
        obj = tmp_path / "policy.o"
        done = subprocess.run([cross, *flags, "-Os", "-Wall", "-Wextra", "-Werror", "-c", str(source / "policy.c"), "-o", str(obj)],
                              capture_output=True, text=True, check=False)
        assert done.returncode == 0, done.stderr
        sections = subprocess.run([cross.replace("gcc", "objdump"), "-h", str(obj)], capture_output=True, text=True, check=False).stdout
        sizes = {f[1]: int(f[2], 16) for f in (line.split() for line in sections.splitlines()) if len(f) > 3 and f[0].isdigit()}
        assert sizes.get(".data", 0) == 0 and sizes.get(".bss", 0) == 0, (source, sizes)
