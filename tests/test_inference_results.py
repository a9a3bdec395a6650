"""Tests of what a fit's draws are summarised into (bayes_inerter.inference.summaries.results)."""

import arviz as az
import numpy as np
import pytest

from bayes_inerter.inference.summaries.results import every_nth, loo_data, loo_summary


def _idata(with_nan: bool, seed: int = 0):
    rng = np.random.default_rng(seed)
    b = rng.normal(1000.0, 10.0, (4, 200))
    y = rng.normal(0.0, 1.0, 25)
    mu = rng.normal(0.0, 0.1, (4, 200, 1))
    post = {"b": b}
    if with_nan:  # a derived quantity defined on some draws only, as b_app is
        post["b_app"] = np.where(rng.random(b.shape) < 0.3, np.nan, 1.1 * b)
    ll = -0.5 * (y - mu) ** 2 - 0.5 * np.log(2 * np.pi)
    return az.from_dict(posterior=post, log_likelihood={"y": ll})


def test_loo_reads_the_finite_posterior_variables_and_is_unchanged_by_the_others():
    # arviz warns "Array contains NaN-value" once per process (its logger caches messages, and
    # the CLI raises its level), so the log is no stable witness: the variables given are.
    with_nan, without = _idata(True), _idata(False)
    assert np.isnan(with_nan.posterior["b_app"].values).any()
    given = loo_data(with_nan).posterior
    assert list(given.data_vars) == ["b"]
    assert all(np.isfinite(given[name].values).all() for name in given.data_vars)
    got = loo_summary(with_nan)
    assert got == pytest.approx(loo_summary(without)) and got["n_points"] == 25


def test_every_nth_says_which_draws_are_kept_in_words():
    assert [every_nth(n) for n in (1, 2, 3, 4, 11, 12, 13, 21, 22, 23, 101, 111)] == [
        "every step", "every 2nd step", "every 3rd step", "every 4th step", "every 11th step", "every 12th step",
        "every 13th step", "every 21st step", "every 22nd step", "every 23rd step", "every 101st step",
        "every 111th step"]
