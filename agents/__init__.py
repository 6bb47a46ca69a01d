"""Baseline agents: scripted swarm behaviours and stable-baselines3 RL.

The repository keeps this folder at the top level (``agents/``); it installs as ``swarm_envs.agents``
(see ``pyproject.toml``), so import it as ``swarm_envs.agents``.

- :mod:`swarm_envs.agents.base`: the :class:`~swarm_envs.agents.base.Policy` interface (``act``, ``act_batch``, ``reset``) and the random policy;
- :mod:`swarm_envs.agents.scripted`: [T20] Alg. 1 random walk, [L] Algs. 5-7 and Sec. 6.2 controllers;
- :mod:`swarm_envs.agents.sb3_vec_env`: the ``make_vec`` -> SB3 ``VecEnv`` adapter (one row per robot of every copy) and ``SB3Policy``;
- :mod:`swarm_envs.agents.evaluation`: seeded episodes, task metrics, 95 % bootstrap confidence intervals, results tables;
- :mod:`swarm_envs.agents.policies`: the policy variants ``train.py`` builds (RecurrentPPO, a DeepSets encoder, odometry, action repeat, frame stacking);
- :mod:`swarm_envs.agents.train`: ``train.py`` / ``swarm-train`` (PPO training, learning curves, evaluation);
- :mod:`swarm_envs.agents.suite`: the benchmark table over training seeds (``python -m swarm_envs.agents.suite``);
- :mod:`swarm_envs.agents.config`: YAML training configs for ``train.py``;
- :mod:`swarm_envs.agents.benchmark`: ``swarm-benchmark`` (``python -m swarm_envs.agents.benchmark``) scripted vs random on every task.
"""
