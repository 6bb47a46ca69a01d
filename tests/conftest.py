"""Shared test helpers."""

from __future__ import annotations

import os
import warnings
from typing import Any

import numpy as np
import pytest

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("PYGAME_HIDE_SUPPORT_PROMPT", "1")
# no background compile processes from the suite's subprocesses on fresh numba caches (they would race with
# tests that corrupt or time a cache); tests/compile/test_first_run.py turns it on where it tests it
os.environ.setdefault("SWARM_ENVS_BACKGROUND_COMPILE", "0")


@pytest.fixture(scope="session", autouse=True)
def _sb3_logs_in_the_test_tmp(tmp_path_factory):
    """SB3 models made without a logger (``model.learn`` in tests and doc blocks) log to ``SB3_LOGDIR``,
    by default a new folder in the system's temporary directory per call: here pytest's temporary tree."""
    if "SB3_LOGDIR" not in os.environ:
        os.environ["SB3_LOGDIR"] = str(tmp_path_factory.mktemp("sb3_logs"))


@pytest.fixture(scope="session", autouse=True)
def _share_the_kernel_compile():
    """Under pytest-xdist, each worker first compiles its share of the recorded numba kernels of every
    scenario (:func:`swarm_envs._compile._first_run.compile_share`: the workers claim kernels longest first, so none
    is compiled twice on a cold cache, then load the others' from the shared disk cache). On a warm cache
    this only reads the cache indexes."""
    if os.environ.get("PYTEST_XDIST_WORKER") is None:
        return
    import swarm_envs._compile._kernel_manifest as manifest
    from swarm_envs._compile._first_run import compile_share

    for task, platform in manifest.SCENARIOS:
        compile_share(task, platform)


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


#: the env's warning when PettingZoo's API tests reset with ``options={"options": 1}`` (to check that ``reset``
#: takes options): the env ignores that unknown key and says so, as it should
UNKNOWN_OPTION_WARNING = r"ignoring unknown reset option\(s\) \['options'\]"


def dotted_keys(node: dict, prefix: str = "") -> list[str]:
    """Every key of a nested config dict as a dotted path (``"train.n_envs"``), parents included."""
    keys = []
    for key, value in node.items():
        keys.append(prefix + key)
        if isinstance(value, dict) and value:
            keys += dotted_keys(value, prefix + key + ".")
    return keys


def parallel_api_check(env: Any, num_cycles: int) -> None:
    """PettingZoo's ``parallel_api_test``, expecting exactly the env's :data:`UNKNOWN_OPTION_WARNING` (any
    other warning is reported)."""
    from pettingzoo.test import parallel_api_test

    with pytest.warns(UserWarning, match=UNKNOWN_OPTION_WARNING):
        parallel_api_test(env, num_cycles=num_cycles)


def aec_api_check(env: Any, num_cycles: int) -> None:
    """PettingZoo's AEC ``api_test``, expecting the env's :data:`UNKNOWN_OPTION_WARNING`, without the test's two
    style notes on dict observations ("Observation is not a NumPy array", "... should be
    gymnasium.spaces.box or gymnasium.spaces.discrete"): the envs' observations are a ``Dict`` space by design
    (``flatten=True`` gives a ``Box``), which the test itself accepts."""
    from pettingzoo.test import api_test

    with pytest.warns(UserWarning, match=UNKNOWN_OPTION_WARNING):  # restores the filters below on exit
        warnings.filterwarnings("ignore", message="Observation is not a NumPy array", category=UserWarning)
        warnings.filterwarnings("ignore", message="Observation space for each agent probably should be", category=UserWarning)
        api_test(env, num_cycles=num_cycles)


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


@pytest.fixture
def unregistered(forget_registered_ids):
    """``unregistered(env_id)`` removes the id from the suite's and PettingZoo's registries for the rest of the
    test, so that the module registering it, imported anew (``--import examples/custom_task.py``), registers
    it afresh instead of replacing an entry (which warns); the removed entries are put back after the test."""
    import pettingzoo

    from swarm_envs import registry

    tables = (registry._REGISTRY, pettingzoo.parallel_registry, pettingzoo.aec_registry)
    saved: list[tuple[dict, str, Any]] = []

    def remove(env_id: str) -> None:
        for table in tables:
            if env_id in table:
                saved.append((table, env_id, table.pop(env_id)))

    yield remove
    for table, env_id, entry in saved:
        table[env_id] = entry
