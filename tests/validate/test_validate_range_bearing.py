"""[F14 Sec. V] range & bearing validation run in the env, and the settings it forwards."""

import pytest

from swarm_envs.validate.range_bearing import env_sweep, parse_variation, unknown_settings


def test_env_sweep_measures_through_the_env_and_forwards_settings():
    # a robot fires about once per 11 steps (1 s timer plus up to 0.2 s late): 24 steps give ~2 per pair
    quiet = env_sweep("droplet", {"rb_noise": 0.0}, seed=1, steps=24, pairs_per_distance=8)
    noisy = env_sweep("droplet", {"rb_noise": 8.0}, seed=1, steps=24, pairs_per_distance=8)
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


def test_env_sweep_reports_the_error_with_and_without_hardware_variation():
    """The same static pairs, noise-free: with each robot's channels drawn at reset (the default) the
    estimator's nominal calibration no longer matches the light, and the range error spreads more than with
    the nominal channels (hw_variation=False); stronger spreads spread it more."""
    kw = dict(seed=2, steps=24, pairs_per_distance=24)
    nominal = env_sweep("droplet", {"rb_noise": 0.0, "hw_variation": False}, **kw)
    default = env_sweep("droplet", {"rb_noise": 0.0}, **kw)
    strong = env_sweep("droplet", {"rb_noise": 0.0, "hw_emitter_spread": 0.3, "hw_detector_spread": 0.3, "hw_angle_spread": 10.0}, **kw)
    assert nominal["settings"]["hw_variation"] is False and "hw_variation" not in default["settings"]
    assert nominal["range_std"] < default["range_std"] < strong["range_std"]
    assert default["range_std"] > 1.3 * nominal["range_std"]
    assert strong["bearing_std"] > nominal["bearing_std"]
