"""The default torch thread count of the adapters and examples (swarm_envs.adapters.torch_threads)."""

import pytest

from swarm_envs.adapters.torch_threads import default_torch_threads, set_torch_threads


def test_default_rule(monkeypatch):
    monkeypatch.delenv("OMP_NUM_THREADS", raising=False)
    assert [default_torch_threads(cores=c) for c in (1, 2, 3, 4, 8, 16)] == [1, 1, 1, 2, 4, 4]
    monkeypatch.setenv("OMP_NUM_THREADS", "3")
    assert default_torch_threads(cores=2) == 3  # the standard variable wins
    for bad in ("0", "two"):
        monkeypatch.setenv("OMP_NUM_THREADS", bad)
        with pytest.raises(ValueError, match="OMP_NUM_THREADS"):
            default_torch_threads()


def test_set_and_sb3_adapter(monkeypatch):
    torch = pytest.importorskip("torch")
    monkeypatch.delenv("OMP_NUM_THREADS", raising=False)
    before = torch.get_num_threads()
    try:
        assert set_torch_threads(2) == 2 and torch.get_num_threads() == 2
        assert set_torch_threads() == default_torch_threads() == torch.get_num_threads()
        with pytest.raises(ValueError, match="threads"):
            set_torch_threads(0)
        pytest.importorskip("stable_baselines3")
        from swarm_envs.agents.sb3_vec_env import SwarmVecEnv

        torch.set_num_threads(2)
        SwarmVecEnv("swarm_envs/Flocking-v0", 1, {"n_robots": 2, "sensing": "ideal"})
        assert torch.get_num_threads() == default_torch_threads()
        SwarmVecEnv("swarm_envs/Flocking-v0", 1, {"n_robots": 2, "sensing": "ideal"}, torch_threads=2)
        assert torch.get_num_threads() == 2
        torch.set_num_threads(3)
        SwarmVecEnv("swarm_envs/Flocking-v0", 1, {"n_robots": 2, "sensing": "ideal"}, torch_threads=0)
        assert torch.get_num_threads() == 3
    finally:
        torch.set_num_threads(before)
