"""swarm_envs.comm"""
