"""swarm_envs.validate"""
