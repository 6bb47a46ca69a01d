"""[F14 Sec. V] range & bearing validation run in the env, and the settings it forwards."""

import pytest

from swarm_envs.validate.range_bearing import env_sweep, parse_variation, unknown_settings


def test_env_sweep_measures_through_the_env_and_forwards_settings():
    quiet = env_sweep("droplet", {"rb_noise": 0.0}, seed=1, steps=4, pairs_per_distance=8)
    noisy = env_sweep("droplet", {"rb_noise": 8.0}, seed=1, steps=4, pairs_per_distance=8)
    assert quiet["pairs"] == 14 * 8 and quiet["readings"] > quiet["pairs"]  # several fresh readings per pair
    assert quiet["settings"]["rb_noise"] == 0.0 and noisy["settings"]["rb_noise"] == 8.0
    assert quiet["worst_range_bound"] < 4.4  # within one Droplet diameter [F14 Fig. 5]
    assert 2.0 < quiet["bearing_std"] < quiet["heading_std"] < 20.0
    # the forwarded setting reaches the sensor: with 8 counts of ADC noise most requests are not decoded
    assert noisy["readings"] < 0.5 * quiet["readings"]


def test_variation_settings_are_parsed_and_unknown_ones_named():
    assert parse_variation(["rb_noise=3", "rb_near_model=True", "name=abc"]) == {"rb_noise": 3, "rb_near_model": True, "name": "abc"}
    with pytest.raises(ValueError, match="KEY=VALUE"):
        parse_variation(["rb_noise"])
    assert unknown_settings({"rb_noise": 1.0, "no_such_spread": 0.1}) == ["no_such_spread"]
    assert unknown_settings({"rb_noise": 1.0}) == []
