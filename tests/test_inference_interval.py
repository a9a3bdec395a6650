"""Tests of b's reported interval (bayes_inerter.inference.summaries.interval)."""

import math

import numpy as np
import pytest

from bayes_inerter.device import paper_parameters
from bayes_inerter.inference.posterior.discrepancy import harmonic_discrepancy
from bayes_inerter.inference.summaries.interval import (INTERVALS, InertanceInterval, IntervalSettings, combined_interval,
                                              inertance_interval, widened_interval)
from bayes_inerter.inference.posterior.likelihood import LikelihoodSettings
from bayes_inerter.inference.posterior.model import PosteriorModel
from bayes_inerter.records.generator import GeneratorSettings, paper_record
from bayes_inerter.records.sensitivity import SensorCalibration

Z94 = 1.8807936081512509  # the normal quantile of 0.97


def test_no_added_sd_gives_the_draws_own_quantiles():
    rng = np.random.default_rng(0)
    log_b = np.log(3000.0) + 0.01 * rng.standard_normal(20_000)
    got = widened_interval(log_b, 0.0, 0.94, np.random.default_rng(1))
    lo, hi = np.exp(np.quantile(log_b, [0.03, 0.97]))
    assert (got.lo, got.hi) == (pytest.approx(lo, rel=1e-12), pytest.approx(hi, rel=1e-12))
    assert got.median == pytest.approx(np.exp(np.median(log_b)), rel=1e-12)


def test_an_added_sd_combines_with_the_posteriors_in_quadrature():
    """Normal draws of sd s widened by an independent normal term of sd e: the interval is
    exp(mu +- z sqrt(s^2 + e^2)) (to the draws' sampling error)."""
    s, e = 0.01, 0.03
    log_b = math.log(3000.0) + s * np.random.default_rng(2).standard_normal(200_000)
    got = widened_interval(log_b, e, 0.94, np.random.default_rng(3))
    half = Z94 * math.hypot(s, e)
    assert math.log(got.hi / got.median) == pytest.approx(half, rel=0.02)
    assert math.log(got.median / got.lo) == pytest.approx(half, rel=0.02)
    assert got.covers(3000.0 * math.exp(0.9 * half)) and not got.covers(3000.0 * math.exp(1.1 * half))


@pytest.fixture(scope="module")
def model():
    rec = paper_record("A3", 1.0, settings=GeneratorSettings(duration=4.0, ramp=1.0), seed=0)
    # the time-domain likelihood, whose fits report the honest interval by default (and
    # whose prior holds Table I's c_B, where theta is taken)
    pm = PosteriorModel(rec, likelihood=LikelihoodSettings(residual="ar1"))
    return pm, pm.to_theta(paper_parameters("A3"), sigma=0.01)


def test_the_honest_interval_adds_the_sensors_and_the_discrepancy(model):
    pm, theta = model
    b = 3500.0 * np.exp(0.002 * np.random.default_rng(4).standard_normal(4000))
    got = inertance_interval(pm, b, theta, phi=0.95, rng=np.random.default_rng(5))
    assert got.method == "honest"
    cal = SensorCalibration()
    m = pm.m_s + pm.m_B
    assert got.sd_log_sensors == pytest.approx(cal.ratio_sd * (np.median(b) + m) / np.median(b), rel=1e-12)
    assert got.sd_log_discrepancy == harmonic_discrepancy(pm, theta).sd_log_b
    plain = inertance_interval(pm, b, theta, settings=INTERVALS["posterior"], rng=np.random.default_rng(5))
    assert got.identified and got.phi == 0.95
    assert plain.method == "posterior" and plain.sd_log_sensors == plain.sd_log_discrepancy == 0.0
    assert got.lo < plain.lo < plain.hi < got.hi
    assert "sensors" in got.describe() and "alone" in plain.describe()


def test_the_cli_offers_every_interval():
    from bayes_inerter.cli.parser import FIT_INTERVALS

    assert set(FIT_INTERVALS) == set(INTERVALS)


@pytest.mark.parametrize("level", [0.0, 1.0, 94.0])
def test_a_level_outside_zero_to_one_is_refused(level):
    with pytest.raises(ValueError, match="level"):
        IntervalSettings(level=level)


def test_bad_draws_are_refused(model):
    with pytest.raises(ValueError, match="positive"):
        inertance_interval(*model[:1], np.array([1.0, -1.0]), model[1], rng=np.random.default_rng(0))
    with pytest.raises(ValueError, match="two finite"):
        widened_interval(np.array([np.nan, 1.0]), 0.0, 0.94, np.random.default_rng(0))


def test_a_record_the_model_reproduces_poorly_leaves_b_to_the_prior(model):
    pm, theta = model
    b = 3500.0 * np.exp(0.002 * np.random.default_rng(4).standard_normal(400))
    got = inertance_interval(pm, b, theta, phi=0.3, rng=np.random.default_rng(5))
    assert not got.identified and (got.lo, got.hi) == pytest.approx((100.0, 1e5))  # the prior's range of b
    assert "not identified" in got.describe() and "30%" in got.describe()
    with pytest.raises(ValueError, match="phi"):
        inertance_interval(pm, b, theta, rng=np.random.default_rng(5))  # phi unknown: cannot tell


def _part(b, sd_post, sd_disc, identified=True, phi=0.9):
    return InertanceInterval("honest", b, 0.0, 0.0, 0.94, sd_post, 0.0, sd_disc, identified, phi)


def test_records_that_agree_combine_as_a_product():
    got = combined_interval([_part(3000.0, 0.003, 0.004)] * 4, calibration=None, moving_mass=60.0)
    half = Z94 * 0.005 / 2  # four records of sd 0.005 each
    assert got.median == pytest.approx(3000.0) and math.log(got.hi / got.median) == pytest.approx(half)
    with_cal = combined_interval([_part(3000.0, 0.003, 0.004)] * 4, calibration=SensorCalibration(),
                                 moving_mass=60.0)
    u = SensorCalibration().ratio_sd * 3060.0 / 3000.0  # added once, after combining
    assert math.log(with_cal.hi / with_cal.median) == pytest.approx(Z94 * math.hypot(0.005 / 2, u))


def test_records_that_disagree_widen_the_combination_by_the_birge_ratio():
    parts = [_part(3000.0, 0.01, 0.0), _part(3000.0 * math.exp(0.1), 0.01, 0.0)]
    got = combined_interval(parts, calibration=None, moving_mass=0.0)
    # log means 0.1 apart, sd 0.01 each: chi2 = 2 (0.05 / 0.01)^2 = 50, one degree of freedom
    sd = math.sqrt(50.0) * 0.01 / math.sqrt(2)
    assert math.log(got.median / 3000.0) == pytest.approx(0.05)
    assert math.log(got.hi / got.median) == pytest.approx(Z94 * sd)


def test_records_not_identified_are_left_out_of_the_combination():
    good = _part(3000.0, 0.01, 0.0)
    bad = InertanceInterval("honest", 9000.0, 100.0, 1e5, 0.94, 0.01, 0.0, 0.0, False, 0.3)
    got = combined_interval([good, bad], calibration=None, moving_mass=0.0)
    assert got.identified and got.median == pytest.approx(3000.0)
    none = combined_interval([bad, bad], calibration=None, moving_mass=0.0)
    assert not none.identified and (none.lo, none.hi) == (100.0, 1e5)
