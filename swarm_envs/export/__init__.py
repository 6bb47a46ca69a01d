"""Export a trained policy and its observation builder as dependency-free C99 for the robot's firmware
(``swarm-export``, docs/export.md)."""

from swarm_envs.export.export import export_run
from swarm_envs.export.run import ExportError

__all__ = ["export_run", "ExportError"]
