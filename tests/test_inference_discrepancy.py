"""Tests of the harmonic model discrepancy (bayes_inerter.inference.posterior.discrepancy)."""

import dataclasses
import math

import numpy as np
import pytest

from bayes_inerter.device import paper_parameters
from bayes_inerter.inference.posterior.discrepancy import harmonic_discrepancy
from bayes_inerter.inference.posterior.model import PosteriorModel
from bayes_inerter.records.generator import GeneratorSettings, paper_record


def _model(extra_amplitude: float = 0.0, k: int = 3):
    """A generated A3 record at 1 Hz, with ``extra_amplitude`` m/s^2 of a cosine at
    harmonic ``k`` added to its acceleration (a discrepancy no model parameter makes)."""
    rec = paper_record("A3", 1.0, settings=GeneratorSettings(duration=6.0, ramp=1.0), seed=0)
    if extra_amplitude:
        extra = extra_amplitude * np.cos(2 * np.pi * k * rec.drive_frequency * rec.time)
        rec = dataclasses.replace(rec, accel=rec.accel + extra)
    pm = PosteriorModel(rec)
    theta = pm.to_theta(paper_parameters("A3"), sigma=0.01)
    return pm, theta


@pytest.fixture(scope="module")
def clean():
    return _model()


def test_a_known_harmonic_sets_tau_by_its_order(clean):
    """A cosine of amplitude A at harmonic 3 puts A^2 / 2 per coefficient pair there;
    with decay 1 its share of the fundamental's variance is 9 A^2 / 2 over the five
    harmonics' mean, with decay 0 plain A^2 / 2 over five."""
    A = 0.05
    pm, theta = _model(A, k=3)
    base_flat = harmonic_discrepancy(*clean, decay=0.0)
    flat = harmonic_discrepancy(pm, theta, decay=0.0)
    steep = harmonic_discrepancy(pm, theta, decay=1.0)
    assert flat.harmonics == steep.harmonics == (2, 3, 4, 5, 6)
    assert flat.power[1] == pytest.approx(A ** 2 / 2, rel=0.05)
    assert flat.tau ** 2 == pytest.approx(A ** 2 / 2 / 5 + base_flat.tau ** 2, rel=0.05)
    assert steep.tau ** 2 == pytest.approx(9 * A ** 2 / 2 / 5, rel=0.1)
    # the sd in log b is tau over the norm of b's signature (at the fundamental): decay
    # scales both alike, so their ratio is tau's
    assert steep.sd_log_b / flat.sd_log_b == pytest.approx(steep.tau / flat.tau, rel=0.05)
    assert flat.sd_log_b > 5 * base_flat.sd_log_b


def test_a_record_of_the_model_itself_has_a_small_discrepancy(clean):
    """At the true parameters the residual is noise: the excess power at each harmonic is
    within a few times what the noise puts into a coefficient."""
    pm, theta = clean
    got = harmonic_discrepancy(pm, theta)
    big = harmonic_discrepancy(*_model(0.05, k=3))
    assert got.sd_log_b < 0.1 * big.sd_log_b
    assert math.isfinite(got.sd_log_b) and got.sd_log_b >= 0


@pytest.mark.parametrize("bad, message", [(dict(harmonics=0), "harmonics"), (dict(decay=-1.0), "decay"),
                                          (dict(decay=float("nan")), "decay")])
def test_bad_options_are_refused(clean, bad, message):
    with pytest.raises(ValueError, match=message):
        harmonic_discrepancy(*clean, **bad)


def test_with_b_alone_free_the_response_is_the_held_projection():
    """A covariance that lets only b move (its variance the likelihood's own, sigma^2 over
    its signature's squared norm on the grid; white noise) gives the posterior's response
    g = H' J_b / ||J_b||^2: the held projection d / ||d||^2, to the grid's sampling of
    the harmonics."""
    pm, theta = _model(0.05, k=3)
    theta = theta.copy()
    theta[-1] = 0.0  # rho: white noise
    i = pm.names.index("b")
    step = 1e-3
    up, down = theta.copy(), theta.copy()
    up[i] += step
    down[i] -= step
    jb = (pm.simulate_lp(up)[pm.grid] - pm.simulate_lp(down)[pm.grid]) / (2 * step)
    sigma, _ = pm.noise(theta)
    cov = np.zeros((pm.ndim, pm.ndim))
    cov[i, i] = sigma ** 2 / float(jb @ jb)
    free = harmonic_discrepancy(pm, theta, cov=cov)
    held = harmonic_discrepancy(pm, theta)
    assert free.tau == held.tau
    assert free.sd_log_b == pytest.approx(held.sd_log_b, rel=0.05)
