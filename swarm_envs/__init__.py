"""swarm_envs: PettingZoo swarm-robotics environments with a physically modelled infrared sensing stack."""

__version__ = "0.1.0"
