"""The task API (Task, settings, metrics, checks), the PettingZoo module factory and the six tasks."""
