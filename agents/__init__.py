"""Baseline agents: scripted swarm behaviours and stable-baselines3 RL."""
