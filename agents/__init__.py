"""Baseline agents: scripted swarm behaviours and stable-baselines3 RL.

- :mod:`agents.base`: the :class:`~agents.base.Policy` interface (``act``, ``act_batch``, ``reset``) and the random policy;
- :mod:`agents.scripted`: [T20] Alg. 1 random walk, [L] Algs. 5-7 and Sec. 6.2 controllers;
- :mod:`agents.sb3_vec_env`: the ParallelEnv -> SB3 ``VecEnv`` adapter (one row per robot) and ``SB3Policy``;
- :mod:`agents.evaluation`: seeded episodes, task metrics, 95 % confidence intervals, results tables;
- :mod:`agents.config`: YAML training configs for ``train.py``;
- :mod:`agents.benchmark`: ``python -m agents.benchmark`` scripted vs random on every task.
"""
