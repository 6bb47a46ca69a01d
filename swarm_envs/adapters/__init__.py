"""The APIs that view the batched core: PettingZoo parallel env, vector env, TorchRL, BenchMARL, rendering."""
