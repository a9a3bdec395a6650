"""Tests of leave-one-frequency-out prediction (bayes_inerter.study.prediction)."""

import numpy as np
import pytest

from bayes_inerter import paper_parameters
from bayes_inerter.inference import PosteriorModel
from bayes_inerter.inference.posterior.likelihood import LikelihoodSettings
from bayes_inerter.records.generator import GeneratorSettings, paper_record
from bayes_inerter.study.prediction import predict_record

SHORT = GeneratorSettings(duration=3.0, ramp=0.8)
#: The time-domain likelihood's models: c_B sampled, so Table I's values are the draws'
#: (the 3 s records also hold too few drive periods for the harmonic likelihoods).
AR1 = LikelihoodSettings(residual="ar1")


@pytest.fixture(scope="module")
def models():
    return {f: PosteriorModel(paper_record("A3", f, settings=SHORT, seed=0), likelihood=AR1) for f in (0.5, 1.0, 1.5)}


def _draws(model, n=60, spread=0.0, seed=1):
    """Joint-fit-like draws (b_A3 and the shared parameters by name) about the truth."""
    values = model.values(model.to_theta(paper_parameters("A3"), 1.0, 0.0))
    rng = np.random.default_rng(seed)
    out = {k: v * np.exp(spread * rng.standard_normal(n)) for k, v in values.items()
           if k not in ("sigma", "rho", "phi") and np.isscalar(v)}
    out["b_A3"] = out.pop("b")
    return out


def test_the_truth_predicts_the_held_out_record_and_its_band_covers_it(models):
    got = predict_record(models[0.5], [models[1.0], models[1.5]], _draws(models[0.5]), "A3", n_draws=40,
                         rng=np.random.default_rng(0))
    assert got.draws == 40 and got.phi > 0.9
    # draws without spread: the band is the noise's alone, about +-1.88 residual sds
    assert np.allclose(got.lo_model, got.hi_model)
    assert got.coverage > 0.8 and got.coverage_model < got.coverage
    assert np.all(got.lo <= got.median) and np.all(got.median <= got.hi)


def test_a_wrong_b_predicts_worse(models):
    right = predict_record(models[0.5], [models[1.0]], _draws(models[0.5]), "A3", n_draws=20,
                           rng=np.random.default_rng(0))
    wrong_draws = _draws(models[0.5])
    wrong_draws["b_A3"] = wrong_draws["b_A3"] * 1.5
    wrong = predict_record(models[0.5], [models[1.0]], wrong_draws, "A3", n_draws=20, rng=np.random.default_rng(0))
    assert wrong.phi < right.phi - 0.05


def test_too_few_draws_are_refused(models):
    with pytest.raises(ValueError, match="n_draws"):
        predict_record(models[0.5], [models[1.0]], _draws(models[0.5]), "A3", n_draws=5, rng=np.random.default_rng(0))


def test_models_of_the_harmonic_likelihoods_predict_from_the_physical_draws_alone():
    """The default likelihood's models sample their own tau and gain, which a joint
    fit's draws name per frequency (``tau_1Hz``) or not at all: the prediction simulates
    from the physical draws alone, as the time-domain models' do."""
    recs = {f: paper_record("A3", f, settings=GeneratorSettings(duration=d, ramp=0.8), seed=0)
            for f, d in ((1.0, 5.5), (1.5, 4.0))}  # three steady drive periods after the first
    default = {f: PosteriorModel(r) for f, r in recs.items()}
    assert {"tau", "gain", "zeta_B"} <= set(default[1.5].names)
    draws = {k: v for k, v in _draws(default[1.5]).items() if k not in ("tau", "alpha")}
    got = predict_record(default[1.5], [default[1.0]], draws, "A3", n_draws=20, rng=np.random.default_rng(0))
    time_domain = {f: PosteriorModel(r, likelihood=AR1) for f, r in recs.items()}
    want = predict_record(time_domain[1.5], [time_domain[1.0]], draws, "A3", n_draws=20,
                          rng=np.random.default_rng(0))
    assert got.phi > 0.9 and got.noise_sd == pytest.approx(want.noise_sd, rel=1e-9)
    np.testing.assert_allclose(got.median, want.median, rtol=1e-9, atol=1e-12)
