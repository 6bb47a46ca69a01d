"""Every validation command ends with one row per figure: ours, the paper's value and the paper's setup."""

import json

import numpy as np
import pytest

from swarm_envs.validate.__main__ import main


def _rows(capsys, argv):
    assert main(argv) == 0
    out = json.loads(capsys.readouterr().out)
    rows = out["rows"]
    assert rows, argv
    for r in rows:
        assert r["figure"].startswith("[") and r["quantity"] and r["ours"] and r["paper"] and r["paper_setup"], r
    return out, rows


def test_centroid_rows_put_the_env_run_first(capsys):
    out, rows = _rows(capsys, ["centroid", "--polygons", "1", "--starts", "2", "--rounds", "3", "--no-plots", "--json"])
    assert "in the env" in rows[0]["how"] and rows[0]["paper"] == "14.03 cm"
    assert any("kinematic" in r["how"] for r in rows)
    assert out["env"]["trials_complete"] == 2


def test_scale_free_rows_have_both_metrics_and_the_env_path(capsys):
    out, rows = _rows(capsys, ["scale-free", "--trials", "2", "--populations", "20", "--configs", "6", "--no-plots", "--json"])
    edge = [r for r in rows if r["figure"] == "[L Fig. 6.2]"]
    assert any("one fully connected robot" in r["quantity"] for r in edge)
    assert any("every rigid robot" in r["quantity"] for r in edge)
    assert any("in the env" in r["how"] for r in edge)
    assert out["edge_error_env"]["configs"] == 6


def test_range_bearing_refuses_a_variation_without_a_value(capsys):
    with pytest.raises(SystemExit):
        main(["range-bearing", "--variation", "no_equals_sign"])
    assert "KEY=VALUE" in capsys.readouterr().err


@pytest.mark.slow
def test_range_bearing_rows_name_the_skipped_variation(capsys):
    out, rows = _rows(capsys, ["range-bearing", "--no-plots", "--json", "--variation", "no_such_spread=0.1"])
    assert "no_such_spread" in out["env_variation"]["skipped"]
    assert any("not measured" in r["ours"] and "no_such_spread" in r["ours"] for r in rows)
    assert out["env"]["worst_range_bound"] < 4.4


@pytest.mark.slow
def test_swarmcom_channels_quick_detector_below_noiseless(capsys):
    out, rows = _rows(capsys, ["swarmcom", "--experiment", "b", "--quick", "--json", "--out", "/tmp/swarm_envs_test_validate"])
    b = out["results"]["b"]
    assert b["detector_peak_mean"] < b["peak_mean"]
    assert 4.0 <= b["detector_densest_mean"] <= 7.0  # [T20 Fig. 20a]: 6 at the densest packing
    for n, arena in b["arena"].items():
        assert arena["walk_detector_mtr5"]["mean"] <= arena["walk_ray_mtr5"]["mean"]
    assert any(r["figure"] == "[T20 Fig. 21]" and "detector" in r["quantity"] for r in rows)
    assert any(r["figure"] == "[T20 Fig. 21]" and "moving" in r["quantity"] for r in rows)
    for n, arena in b["arena"].items():  # lit listeners, robots moving: at most the n - 1 listeners
        assert 0 <= arena["moving_mtr10"]["min"] <= arena["moving_mtr10"]["max"] <= int(n) - 1


@pytest.mark.slow
def test_centroid_in_env_stays_within_two_steps():
    from swarm_envs.sensing.full import BEACON_PERIOD
    from swarm_envs.validate.centroid import D_STEP, experiment_env

    res = experiment_env(seed=5, polygons=3, starts=4, rounds=16, r_range=(0.3, 0.5), pause_steps=BEACON_PERIOD)
    assert res["trials_complete"] == 12
    assert res["mean_second_half_cm"] < 2 * D_STEP * 100  # [L Sec. 6.2.2]: within 2 d_step
    assert np.isfinite(res["mean_inside_cm"])
