"""Tests of what a fit's draws are summarised into (bayes_inerter.inference.results)."""

import arviz as az
import numpy as np
import pytest

from bayes_inerter.inference.results import loo_data, loo_summary


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


def test_loo_reads_the_finite_posterior_variables_and_is_unchanged_by_the_others(capfd):
    with_nan, without = _idata(True), _idata(False)
    assert list(loo_data(with_nan).posterior.data_vars) == ["b"]
    capfd.readouterr()
    az.loo(with_nan)  # arviz on the whole posterior: its logger writes to stderr
    assert "NaN" in capfd.readouterr().err
    got = loo_summary(with_nan)
    assert "NaN" not in capfd.readouterr().err  # a fit's LOO says nothing of a derived quantity's gaps
    assert got == pytest.approx(loo_summary(without)) and got["n_points"] == 25
