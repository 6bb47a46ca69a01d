"""Shared test helpers."""

from __future__ import annotations

import os

import numpy as np
import pytest

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
# no background compile processes from the suite's subprocesses on fresh numba caches (they would race with
# tests that corrupt or time a cache); tests/test_first_run.py turns it on where it tests it
os.environ.setdefault("SWARM_ENVS_BACKGROUND_COMPILE", "0")


def pytest_collection_modifyitems(config, items):
    """Tests marked ``slow`` run only when selected (``pytest -m slow``); the default run skips them."""
    if "slow" in (config.getoption("markexpr") or ""):
        return
    skip = pytest.mark.skip(reason="slow: run with `pytest -m slow`")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip)


def assert_tree_equal(a, b, path: str = "") -> None:
    """Recursively assert two nested dict/list/array structures are identical (NaN == NaN)."""
    if isinstance(a, dict):
        assert isinstance(b, dict) and a.keys() == b.keys(), f"keys differ at {path}"
        for key in a:
            assert_tree_equal(a[key], b[key], f"{path}/{key}")
    elif isinstance(a, (list, tuple)):
        assert len(a) == len(b), f"lengths differ at {path}"
        for i, (x, y) in enumerate(zip(a, b)):
            assert_tree_equal(x, y, f"{path}[{i}]")
    else:
        np.testing.assert_array_equal(np.asarray(a), np.asarray(b), err_msg=f"differ at {path}")


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(12345)


@pytest.fixture
def forget_registered_ids():
    """Env ids registered during a test (or wrongly accepted by the code under test) are removed after it,
    from the suite's registry and PettingZoo's (other tests iterate over the registry)."""
    import pettingzoo

    from swarm_envs import registry

    before = dict(registry._REGISTRY)
    yield
    for env_id in set(registry._REGISTRY) - set(before):
        del registry._REGISTRY[env_id]
        pettingzoo.parallel_registry.pop(env_id, None)
        pettingzoo.aec_registry.pop(env_id, None)
