"""swarm_envs.ir"""
