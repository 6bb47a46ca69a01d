"""The registry (swarm_envs.registry): ids, entry points, re-registration, lookups and their errors."""

from __future__ import annotations

import warnings

import pettingzoo
import pytest

import swarm_envs
from swarm_envs.adapters.env import SwarmEnv
from swarm_envs.adapters.vector import AgentsAsEnvs, SwarmVectorEnv
from swarm_envs.registry import EnvSpec, list_envs, register, resolve, spec, task_class
from swarm_envs.tasks.aggregation_v0 import AggregationEnv, AggregationTask

pytestmark = pytest.mark.usefixtures("forget_registered_ids")


def test_the_six_built_in_ids_come_first_and_are_in_pettingzoo():
    ids = list_envs()
    assert ids[:6] == [
        "swarm_envs/Aggregation-v0", "swarm_envs/Flocking-v0", "swarm_envs/CentroidSeeking-v0",
        "swarm_envs/SortedFollowing-v0", "swarm_envs/ParityClustering-v0", "swarm_envs/MidAngleNavigation-v0",
    ]
    for env_id in ids:
        assert env_id in pettingzoo.parallel_registry and env_id in pettingzoo.aec_registry


def test_a_registered_task_class_is_made_by_every_entry_point():
    returned = register("test_registry/Gather-v0", AggregationTask, kwargs={"n_robots": 5, "sensing": "ideal"})
    assert isinstance(returned, EnvSpec) and spec("test_registry/Gather-v0") is returned
    assert "test_registry/Gather-v0" in list_envs()
    env = swarm_envs.make("test_registry/Gather-v0")
    assert isinstance(env, SwarmEnv) and len(env.possible_agents) == 5
    assert len(swarm_envs.make("test_registry/Gather-v0", n_robots=7).possible_agents) == 7  # kwargs override defaults
    vec = swarm_envs.make_vec("test_registry/Gather-v0", 3)
    assert isinstance(vec, SwarmVectorEnv) and vec.num_envs == 3
    assert isinstance(swarm_envs.make_vec("test_registry/Gather-v0", 2, agents_as_envs=True), AgentsAsEnvs)
    assert len(pettingzoo.make("parallel", "test_registry/Gather-v0").possible_agents) == 5
    assert task_class("test_registry/Gather-v0") is AggregationTask


def test_a_string_entry_point_is_imported_when_first_made():
    register("test_registry/Lazy-v0", "swarm_envs.tasks.aggregation_v0:AggregationEnv")
    assert resolve("test_registry/Lazy-v0") == (AggregationEnv, {})
    assert task_class("test_registry/Lazy-v0") is AggregationTask


def test_registering_again_is_silent_when_equal_and_warns_when_replacing():
    first = register("test_registry/Again-v0", AggregationTask, kwargs={"n_robots": 5})
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert register("test_registry/Again-v0", AggregationTask, kwargs={"n_robots": 5}) is first
    with pytest.warns(UserWarning, match="re-registering 'test_registry/Again-v0'"):
        replaced = register("test_registry/Again-v0", AggregationTask, kwargs={"n_robots": 6})
    assert spec("test_registry/Again-v0") is replaced and replaced.kwargs["n_robots"] == 6


@pytest.mark.parametrize("bad", ["Gather", "test_registry/Gather", "a b/Gather-v0", "test_registry/Gather-v01", ".x/Gather-v0", 3])
def test_malformed_ids_are_refused(bad):
    with pytest.raises(ValueError, match="env id must look like"):
        register(bad, AggregationTask)


def test_an_id_differing_only_in_case_is_refused():
    with pytest.raises(ValueError, match="only in letter case"):
        register("swarm_envs/aggregation-v0", AggregationTask)


@pytest.mark.parametrize("entry", ["no_colon", ":Class", "module:"])
def test_malformed_string_entry_points_are_refused(entry):
    with pytest.raises(ValueError, match="'module:Class'"):
        register("test_registry/Bad-v0", entry)


def test_unknown_ids_name_close_matches():
    with pytest.raises(ValueError, match=r"did you mean \[.swarm_envs/Aggregation-v0."):
        spec("swarm_envs/Agregation-v0")
    with pytest.raises(ValueError, match="unknown environment id"):
        swarm_envs.make("nothing/Like-v0")


def test_task_class_refuses_what_is_not_a_task():
    with pytest.raises(TypeError, match="expected an env id"):
        task_class(object)
    with pytest.raises(TypeError, match="agents_as_envs must be True or False"):
        swarm_envs.make_vec("swarm_envs/Aggregation-v0", 1, agents_as_envs="yes")
