"""BenchMARL: the swarm task family builds the batched env, its specs fit BenchMARL, MAPPO and IPPO train and log."""

import importlib.util
import math
import sys
from pathlib import Path

import pytest

pytest.importorskip("benchmarl", reason="benchmarl is not installed: pip install -e '.[benchmarl]'")
import torch  # noqa: E402
from torchrl.envs import Compose, TransformedEnv  # noqa: E402
from torchrl.envs.utils import check_env_specs  # noqa: E402

from swarm_envs.adapters.benchmarl_tasks import GROUP, TASK_DEFAULTS, SwarmTask  # noqa: E402
from swarm_envs.adapters.torchrl_env import SwarmTorchRLEnv  # noqa: E402

pytestmark = pytest.mark.filterwarnings("ignore::DeprecationWarning")
EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "benchmarl_mappo.py"
CONFIGS = sorted((Path(__file__).resolve().parents[2] / "configs" / "benchmarl").glob("*.yaml"))


def load_example():
    spec = importlib.util.spec_from_file_location("benchmarl_mappo", EXAMPLE)
    example = importlib.util.module_from_spec(spec)
    # registered, so that BenchMARL can pickle the example's task class (NeighbourSetTask) by reference
    sys.modules["benchmarl_mappo"] = example
    spec.loader.exec_module(example)
    return example


@pytest.mark.parametrize("task", list(SwarmTask))
@pytest.mark.parametrize("flatten", [False, True])
def test_task_family_specs(task, flatten):
    swarm_task = task.get_task(config={"max_steps": 7, "n_robots": 3, "sensing": "ideal", "flatten": flatten})
    base = swarm_task.get_env_fun(num_envs=2, continuous_actions=True, seed=0, device="cpu")()
    assert isinstance(base, SwarmTorchRLEnv) and base.batch_size == (2,) and base.max_cycles == 7
    env = TransformedEnv(base, Compose(*swarm_task.get_env_transforms(base)))
    check_env_specs(env)
    assert swarm_task.max_steps(env) == 7
    assert swarm_task.group_map(env) == {GROUP: ["robot_0", "robot_1", "robot_2"]}
    obs = swarm_task.observation_spec(env)
    assert set(obs.keys()) == {GROUP} and set(obs[GROUP].keys()) == {"observation"}
    # BenchMARL's MLP takes every observation leaf with one feature dimension after the agent dimension
    leaves = list(obs.values(True, True))
    assert leaves and all(len(leaf.shape) == 2 and leaf.shape[0] == 3 for leaf in leaves)
    size = sum(leaf.shape[-1] for leaf in leaves)
    assert size == base.vec.agent_observation_space.shape[0] if flatten else size == sum(
        int(torch.tensor(s.shape).prod()) for s in base.vec.agent_observation_space.spaces.values()
    )
    assert list(swarm_task.state_spec(env).keys()) == ["state"]
    info = swarm_task.info_spec(env)
    assert "ground_truth_position" in info[GROUP, "info"].keys() and "episode_step" in info["info"].keys()
    assert swarm_task.action_spec(env)[GROUP, "action"].shape == (3, base.vec.layout.action_size)
    assert swarm_task.supports_continuous_actions() and not swarm_task.supports_discrete_actions()
    with pytest.raises(ValueError, match="continuous"):
        swarm_task.get_env_fun(2, False, 0, "cpu")


def test_every_suite_task_is_a_member_and_a_registered_id_of_your_own_runs():
    import swarm_envs
    from swarm_envs.adapters.benchmarl_tasks import TASK_IDS

    assert set(TASK_IDS.values()) == {i for i in swarm_envs.list_envs() if i.startswith("swarm_envs/")}
    assert set(TASK_IDS) == {t.name for t in SwarmTask} == set(TASK_DEFAULTS)
    spec = importlib.util.spec_from_file_location("custom_task", EXAMPLE.parent / "custom_task.py")
    spec.loader.exec_module(importlib.util.module_from_spec(spec))  # registers swarm_examples/Dispersion-v0
    task = SwarmTask.AGGREGATION.get_task(config={"env_id": "swarm_examples/Dispersion-v0", "max_steps": 5, "n_robots": 3, "sensing": "ideal"})
    base = task.get_env_fun(num_envs=2, continuous_actions=True, seed=0, device="cpu")()
    assert task.env_id == "swarm_examples/Dispersion-v0" and type(base.vec.task).__name__ == "Dispersion"
    check_env_specs(TransformedEnv(base, Compose(*task.get_env_transforms(base))))


def test_defaults_and_yaml(tmp_path):
    task = SwarmTask.AGGREGATION.get_task()
    assert task.config == TASK_DEFAULTS["AGGREGATION"]
    path = tmp_path / "aggregation.yaml"
    path.write_text("max_steps: 20\nn_robots: 4\n")
    task = SwarmTask.AGGREGATION.get_from_yaml(str(path))
    assert task.config["max_steps"] == 20 and task.config["n_robots"] == 4 and task.config["sensing"] == "full"
    with pytest.raises(ValueError, match="max_steps"):
        SwarmTask.FLOCKING.get_task(config={"max_cycles": 5}).get_env_fun(1, True, 0, "cpu")


@pytest.mark.parametrize("algorithm", ["mappo", "ippo"])
def test_example_trains_and_logs(algorithm, tmp_path):
    example = load_example()
    result = example.run(
        algorithm, "aggregation", frames=120, frames_per_batch=60, num_envs=3, n_robots=3, max_steps=10,
        sensing="ideal", torch_threads=1, log_dir=str(tmp_path),
    )
    assert {"episode_reward", "mean_reward_per_step", "mean_distance_to_centroid", "largest_cluster_fraction"} <= set(result)
    assert all(math.isfinite(v) for v in result.values())
    # BenchMARL's csv logger wrote the task's infos (flat keys under the group and the root)
    logged = {p.stem for p in tmp_path.rglob("*.csv")}
    expected = {"collection_agents_info_ground_truth_position", "collection_info_mean_distance_to_centroid", "eval_reward_episode_reward_mean"}
    assert expected <= logged, sorted(logged)


def test_example_main_with_the_flat_observation():
    example = load_example()
    results = example.main(
        ["--task", "flocking", "--algorithms", "mappo", "--frames", "60", "--frames-per-batch", "60", "--num-envs", "2",
         "--n-robots", "3", "--max-steps", "10", "--sensing", "full", "--flatten", "--torch-threads", "1"]
    )
    assert set(results) == {"mappo"} and math.isfinite(results["mappo"]["episode_reward"])


# --- models: the ready configs (configs/benchmarl/) and the example's --model ---

TINY = ["--task", "aggregation", "--frames", "2000", "--frames-per-batch", "1000", "--num-envs", "10", "--n-robots", "3",
        "--max-steps", "20", "--sensing", "ideal", "--torch-threads", "1"]


def test_the_configs_are_there():
    assert {p.stem for p in CONFIGS} >= {"mlp", "gru", "deepsets", "gnn", "gnn_gru"}


@pytest.mark.parametrize("config", CONFIGS, ids=[p.stem for p in CONFIGS])
def test_config_trains_mappo_and_ippo(config, capsys):
    """Each ready config builds and trains MAPPO and IPPO on a tiny budget (its own model, the command line's
    budget); the returned and the printed evaluation metrics are finite."""
    example = load_example()
    options = example.load_config(str(config))
    assert set(options) <= set(vars(example.parse_args([]))) and options["algorithms"] == ["mappo", "ippo"]
    if "gnn" in options["model"].split("+"):
        pytest.importorskip("torch_geometric", reason="the gnn model needs torch_geometric")
    results = example.main(["--config", str(config), *TINY])
    assert set(results) == {"mappo", "ippo"}
    printed = [line for line in capsys.readouterr().out.splitlines() if line.startswith(("mappo", "ippo"))]
    assert len(printed) == 2
    for algorithm, line in zip(["mappo", "ippo"], printed):
        result = results[algorithm]
        assert {"episode_reward", "largest_cluster_fraction", "mean_distance_to_centroid"} <= set(result)
        assert all(math.isfinite(v) for v in result.values()), result
        assert line.startswith(f"{algorithm:5s} {options['model']} aggregation: ")
        values = [float(v) for v in line.split(": ", 1)[1].split()[1::2]]
        assert len(values) == len(result) and all(math.isfinite(v) for v in values)


def test_config_file_and_command_line(tmp_path):
    example = load_example()
    config = tmp_path / "c.yaml"
    config.write_text("task: sorted_following\nalgorithms: [ippo]\nmodel: deepsets+gru\nframes: 10\nn_robots: null\n")
    args = example.parse_args(["--config", str(config), "--frames", "20"])
    got = (args.task, args.algorithms, args.model, args.frames, args.n_robots)
    assert got == ("sorted_following", ["ippo"], "deepsets+gru", 20, None)
    assert example.parse_args([]).model == "mlp"  # without a file: the defaults
    for text in ("modle: gru\n", "model: gru+rnn\n", "task: nowhere\n", "algorithms: [mappo, qmix]\n"):
        config.write_text(text)
        with pytest.raises(SystemExit):
            example.parse_args(["--config", str(config)])


def test_model_chains_and_critics():
    from benchmarl.models import DeepsetsConfig, GruConfig, MlpConfig, SequenceModelConfig

    example = load_example()
    chain = example.model_config("deepsets+gru", hidden=16)
    assert isinstance(chain, SequenceModelConfig) and chain.intermediate_sizes == [16] and chain.is_rnn
    assert [type(c) for c in chain.model_configs] == [DeepsetsConfig, GruConfig]
    with pytest.raises(ValueError, match="first"):
        example.model_config("gru+deepsets")
    with pytest.raises(ValueError, match="unknown"):
        example.model_config("transformer")
    # the critic: MAPPO's an MLP on the state; IPPO's a DeepSets when the observation keeps the neighbour rows
    assert isinstance(example.critic_config("mappo", "deepsets"), MlpConfig)
    assert isinstance(example.critic_config("ippo", "deepsets+gru"), DeepsetsConfig)
    assert isinstance(example.critic_config("ippo", "gru"), MlpConfig)


@pytest.mark.parametrize("task", ["aggregation", "sorted_following"])
def test_neighbour_set_task_keeps_the_range_bearing_rows(task):
    example = load_example()
    swarm_task = example.make_task(task, "deepsets", max_steps=5, n_robots=None, sensing="ideal")
    assert isinstance(swarm_task, example.NeighbourSetTask) and swarm_task.config["max_steps"] == 5
    base = swarm_task.get_env_fun(num_envs=2, continuous_actions=True, seed=0, device="cpu")()
    env = TransformedEnv(base, Compose(*swarm_task.get_env_transforms(base)))
    check_env_specs(env)
    parts = dict(swarm_task.observation_spec(env)[GROUP, "observation"].items())
    n, sets = base.n_agents, ["range_bearing"] + (["range_bearing_ids"] if "range_bearing_ids" in parts else [])
    assert (task == "sorted_following") == ("range_bearing_ids" in parts)  # the r-one task observes ids
    assert [tuple(parts[k].shape[:2]) for k in sets] == [(n, 8)] * len(sets)
    assert all(len(p.shape) == 2 for k, p in parts.items() if k not in sets)  # the other parts flattened to vectors
    flat = example.make_task(task, "deepsets", max_steps=5, sensing="ideal", flatten=True)
    with pytest.raises(ValueError, match="flatten"):
        flat.get_env_transforms(flat.get_env_fun(1, True, 0, "cpu")())
    assert type(example.make_task(task, "gnn+gru")) is type(SwarmTask.AGGREGATION.get_task())


def test_example_takes_an_imported_id(forget_registered_ids):
    """A registered id of your own (``--import``) runs under the task family with ``env_id`` in its config."""
    sys.modules.pop("custom_task", None)
    try:
        results = load_example().main(
            ["--import", str(EXAMPLE.parent / "custom_task.py"), "--task", "swarm_examples/Dispersion-v0", "--algorithms", "mappo",
             "--frames", "40", "--frames-per-batch", "20", "--num-envs", "2", "--n-robots", "3", "--max-steps", "10",
             "--sensing", "ideal", "--torch-threads", "1"]
        )
    finally:
        sys.modules.pop("custom_task", None)
    assert {"episode_reward", "mean_spacing", "connected_fraction"} <= set(results["mappo"])


def test_the_docs_snippet_runs_as_written(tmp_path, monkeypatch):
    """docs/torchrl_benchmarl.md's BenchMARL snippet, verbatim, in a fresh folder: no wandb, a short budget."""
    import re

    page = (Path(__file__).resolve().parents[2] / "docs" / "torchrl_benchmarl.md").read_text()
    snippet = next(b for b in re.findall(r"```python\n(.*?)```", page, flags=re.S) if "ExperimentConfig" in b)
    monkeypatch.chdir(tmp_path)
    exec(compile(snippet, "docs/torchrl_benchmarl.md", "exec"), {"__name__": "__docs__"})
    assert list((tmp_path / "runs" / "benchmarl").rglob("eval_reward_episode_reward_mean.csv"))
