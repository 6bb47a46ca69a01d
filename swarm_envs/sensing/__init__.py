"""swarm_envs.sensing"""
