"""``python -m swarm_envs.export``: the ``swarm-export`` command."""

import sys

from swarm_envs.export.cli import main

if __name__ == "__main__":
    sys.exit(main())
