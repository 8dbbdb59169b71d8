"""Permutation p-values, bootstrap intervals and q-values from per-utterance sums."""
import itertools

import numpy as np
import pytest
from scipy.stats import false_discovery_control

from engine.comparison.design import resolve_design
from engine.comparison.statistics import Family, bh_qvalues, run_families


def _mean_difference(values):
    """A family of one statistic: the difference of the levels' utterance means (|diff| tested)."""
    S = np.column_stack([np.ones(len(values)), values])

    def statistic(sa, sb):
        d = sb[:, 1:2] / sb[:, 0:1] - sa[:, 1:2] / sa[:, 0:1]
        return d, np.abs(d)

    return Family("mean", S, statistic)


def test_exact_p_value_is_the_share_of_arrangements_at_least_as_extreme():
    x = np.array([0.1, 0.4, -0.2, 1.3, 0.9, 1.1])
    d = resolve_design(["a", "a", "a", "b", "b", "b"], "a", "b")
    (r,) = run_families(d, [_mean_difference(x)], n_permutations=1000, n_bootstrap=0)
    assert r.exact and r.n_permutations == 20
    obs = x[3:].mean() - x[:3].mean()
    diffs = [abs(x[list(c)].mean() - np.delete(x, list(c)).mean()) for c in itertools.combinations(range(6), 3)]
    assert r.p[0] == pytest.approx(np.mean(np.asarray(diffs) >= abs(obs) - 1e-12))
    assert r.estimate[0] == pytest.approx(obs)
    assert np.isnan(r.ci_low[0])  # n_bootstrap=0: no interval


def test_random_permutation_p_values_are_uniform_under_no_difference():
    rng = np.random.default_rng(0)
    d = resolve_design(["a"] * 12 + ["b"] * 12, "a", "b")
    ps = []
    for k in range(200):
        (r,) = run_families(d, [_mean_difference(rng.standard_normal(24))], n_permutations=199, n_bootstrap=0,
                            random_state=k)
        ps.append(r.p[0])
    ps = np.asarray(ps)
    assert 0.02 <= np.mean(ps < 0.05) <= 0.09
    assert 0.4 < ps.mean() < 0.6


def test_a_real_difference_gets_a_small_p_and_an_interval_around_it():
    rng = np.random.default_rng(1)
    x = np.r_[rng.normal(0, 1, 15), rng.normal(2, 1, 15)]
    d = resolve_design(["a"] * 15 + ["b"] * 15, "a", "b")
    (r,) = run_families(d, [_mean_difference(x)], n_permutations=999, n_bootstrap=500, random_state=2)
    assert r.p[0] == pytest.approx(1 / 1000)
    assert r.ci_low[0] < r.estimate[0] < r.ci_high[0]
    assert r.ci_low[0] > 0.5 and r.ci_high[0] < 3.5


def test_an_untestable_design_gives_the_estimate_only():
    d = resolve_design(["a", "b"], "a", "b")
    (r,) = run_families(d, [_mean_difference(np.array([1.0, 3.0]))])
    assert r.estimate[0] == 2.0 and np.isnan(r.p[0]) and np.isnan(r.ci_low[0]) and r.n_permutations == 0


def test_bh_qvalues_match_scipy_and_skip_nan():
    p = np.array([0.001, 0.2, np.nan, 0.03, 0.04, 0.5])
    q = bh_qvalues(p)
    assert np.isnan(q[2])
    ok = ~np.isnan(p)
    np.testing.assert_allclose(q[ok], false_discovery_control(p[ok], method="bh"))
