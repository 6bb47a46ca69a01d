"""TorchRL: the stock PettingZooWrapper works on every env in ``FlatInfos`` (Dict and flat observations, infos, global state)."""

import importlib.util
import math
import sys
from pathlib import Path

import numpy as np
import pytest

import swarm_envs
from swarm_envs.adapters.env import FlatInfos, flat_info

pytest.importorskip("torchrl", reason="torchrl is not installed: pip install -e '.[torchrl]'")
import torch  # noqa: E402
from torchrl.envs.libs.pettingzoo import PettingZooWrapper  # noqa: E402
from torchrl.envs.utils import check_env_specs  # noqa: E402

pytestmark = pytest.mark.filterwarnings("ignore:PettingZoo in TorchRL is tested")

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "torchrl_mappo.py"


@pytest.mark.parametrize("env_id", swarm_envs.list_envs())
@pytest.mark.parametrize("flatten", [False, True])
def test_wrapper_on_flat_infos_passes_check_env_specs(env_id, flatten):
    env = swarm_envs.make(env_id, n_robots=3, max_cycles=6, flatten=flatten)
    wrapped = PettingZooWrapper(FlatInfos(env))  # no wrapper options: must work as is
    check_env_specs(wrapped)
    obs_spec = wrapped.observation_spec["robot", "observation"]
    if flatten:
        assert obs_spec.shape == (3, env.observation_space("robot_0").shape[0])
    else:
        assert set(obs_spec.keys()) == set(env.observation_space("robot_0").spaces)
    # every info group arrives as a nested tensordict, with the same names as the env's infos
    _, infos = env.reset(seed=0)
    info_keys = set(wrapped.observation_spec["robot", "info"].keys(include_nested=True, leaves_only=True))
    assert info_keys == set(flat_info(infos["robot_0"]))
    # rollout across an episode end (auto-reset), values match the env's own infos at the last step
    td = wrapped.rollout(8, break_when_any_done=False)
    assert td["next", "robot", "done"][5].all()  # max_cycles=6: the 6th step truncates
    last = td[-1]["next", "robot", "info"]
    gt = np.stack([env.world.positions[r] for r in env.agent_robots])
    np.testing.assert_allclose(last["ground_truth", "position"].numpy(), gt, atol=1e-6)


@pytest.mark.parametrize("env_id", swarm_envs.list_envs())
def test_return_state_gives_the_global_state(env_id):
    env = swarm_envs.make(env_id, n_robots=2, max_cycles=10, sensing="ideal")
    wrapped = PettingZooWrapper(FlatInfos(env), return_state=True)
    assert wrapped.observation_spec["state"].shape == env.state_space.shape
    check_env_specs(wrapped)
    td = wrapped.rollout(4)
    assert td["next", "state"].shape == (4, *env.state_space.shape)
    np.testing.assert_array_equal(td["next", "state"][-1].numpy(), env.state())
    assert not torch.equal(td["state"][0], td["next", "state"][-1]), "random actions must move the robots"


@pytest.mark.parametrize("wrapper", ["batched", "pettingzoo"])
def test_mappo_example_trains_a_few_iterations(wrapper):
    spec = importlib.util.spec_from_file_location("torchrl_mappo", EXAMPLE)
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    log = example.main(
        ["--frames", "80", "--frames-per-batch", "40", "--minibatch", "20", "--epochs", "1", "--n-robots", "3", "--max-cycles", "20", "--sensing", "ideal"]
        + ["--wrapper", wrapper, "--num-envs", "4", "--torch-threads", "1"]
    )
    assert {"reward_per_step", "mean_distance_to_centroid", "largest_cluster_fraction"} <= set(log)
    assert all(math.isfinite(v) for v in log.values())


# --- a registered id of your own (--import) ---
CUSTOM_TASK = str(Path(__file__).resolve().parents[2] / "examples" / "custom_task.py")
DISPERSION = "swarm_examples/Dispersion-v0"


def _load_mappo_example():
    spec = importlib.util.spec_from_file_location("torchrl_mappo", EXAMPLE)
    example = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(example)
    return example


def test_mappo_example_takes_an_imported_id(unregistered):
    unregistered(DISPERSION)
    sys.modules.pop("custom_task", None)  # imported anew through --import: the id it registers is forgotten after
    try:
        log = _load_mappo_example().main(
            ["--import", CUSTOM_TASK, "--task", DISPERSION, "--frames", "40", "--frames-per-batch", "20", "--minibatch", "10",
             "--epochs", "1", "--n-robots", "3", "--max-cycles", "10", "--sensing", "ideal", "--num-envs", "2", "--torch-threads", "1"]
        )
    finally:
        sys.modules.pop("custom_task", None)
    assert {"reward_per_step", "mean_spacing", "connected_fraction"} <= set(log)
    assert all(math.isfinite(v) for v in log.values())


def test_mappo_example_refuses_an_unregistered_id(capsys):
    with pytest.raises(SystemExit) as exit_info:
        _load_mappo_example().main(["--task", "my_lab/Nothing-v0"])
    assert exit_info.value.code == 2 and "not a registered env id" in capsys.readouterr().err
