"""Bootstrap percentile confidence intervals of the results tables (agents.evaluation)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from swarm_envs.agents.evaluation import confidence_interval, markdown_table, summarise


def test_fraction_interval_stays_in_range():
    # the case of the issue: a t-interval of [0.8, 1.0] is 0.9 [-0.37, 2.17]
    mean, lo, hi = confidence_interval([0.8, 1.0])
    assert mean == pytest.approx(0.9) and 0.8 <= lo <= mean <= hi <= 1.0
    mean, lo, hi = confidence_interval([1.0, 1.0, 1.0, 1.0, 0.1])  # skewed, bounded above by 1
    assert 0.0 <= lo < mean < hi <= 1.0


def test_known_sample_contains_mean_and_is_reproducible():
    x = np.random.default_rng(3).beta(2.0, 5.0, size=20)  # values in [0, 1], mean 2/7
    mean, lo, hi = confidence_interval(x, seed=7)
    assert mean == pytest.approx(x.mean())
    assert x.min() <= lo < mean < hi <= x.max()
    assert hi - lo < 0.2  # sd of Beta(2, 5) is 0.16: the 95 % interval of a 20-sample mean is ~0.14 wide
    assert confidence_interval(x, seed=7) == (mean, lo, hi)
    # a different bootstrap seed moves the bounds only a little
    _, lo2, hi2 = confidence_interval(x, seed=8)
    assert lo2 == pytest.approx(lo, abs=0.01) and hi2 == pytest.approx(hi, abs=0.01)


def test_widths_shrink_with_n():
    population = np.random.default_rng(11).normal(0.5, 0.1, size=400)
    widths = []
    for n in (5, 20, 80, 320):
        _, lo, hi = confidence_interval(population[:n], seed=0)
        widths.append(hi - lo)
    assert all(a > b for a, b in zip(widths, widths[1:])), widths
    # roughly 1/sqrt(n): 4x the seeds, about half the width
    assert 0.3 < widths[3] / widths[2] < 0.7


def test_one_seed_has_no_interval_and_equal_values_a_point():
    mean, lo, hi = confidence_interval([0.7])
    assert mean == 0.7 and math.isnan(lo) and math.isnan(hi)
    assert confidence_interval([4.0, 4.0]) == (4.0, 4.0, 4.0)
    assert all(math.isnan(v) for v in confidence_interval([]))
    mean, lo, hi = confidence_interval([1.0, np.nan, 3.0])  # non-finite values are dropped
    assert mean == 2.0 and 1.0 <= lo < 2.0 < hi <= 3.0


def test_table_says_how_many_seeds():
    rows = summarise({"a": {"m": np.array([0.2, 0.4, 0.9])}, "b": {"m": np.array([0.5, 0.5, 0.5])}}, seed=1)
    assert [r["n"] for r in rows] == [3, 3]
    table = markdown_table(rows, n_seeds=3)
    assert "n=3 seeds" in table and "bootstrap" in table and "(all equal)" in table and "too narrow" in table
    many = markdown_table(summarise({"a": {"m": np.linspace(0.0, 1.0, 20)}}), n_seeds=20)
    assert "n=20 seeds" in many and "too narrow" not in many
    single = markdown_table(summarise({"a": {"m": np.array([0.25])}}), n_seeds=1)
    assert "0.25 (n=1)" in single and "[" not in single.split("\n")[2] and "no confidence interval" in single
    partial = markdown_table(summarise({"a": {"m": np.array([0.2, np.nan, 0.4])}}), n_seeds=3)
    assert "(n=2)" in partial


@pytest.mark.slow
def test_coverage_of_the_bootstrap_interval():
    """The numbers quoted in the tables' few-seeds warning: real coverage of the nominal 95 % interval of the
    mean of normal data (400 samples per n; binomial standard error ~2.3 points)."""
    rng = np.random.default_rng(0)
    coverage = {}
    for n in (2, 3, 5, 20):
        hits = 0
        for t in range(400):
            _, lo, hi = confidence_interval(rng.normal(0.0, 1.0, n), seed=t, n_resamples=2000)
            hits += lo <= 0.0 <= hi
        coverage[n] = hits / 400
    assert 0.45 < coverage[2] < 0.6 and 0.64 < coverage[3] < 0.78 and 0.79 < coverage[5] < 0.9, coverage
    assert coverage[20] > 0.9, coverage
