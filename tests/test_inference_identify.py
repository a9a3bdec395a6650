"""Tests of the paper's least-squares identification (bayes_inerter.inference.identify)."""

import numpy as np
import pytest

from bayes_inerter.inference.identify import identify
from bayes_inerter.inference.model import PosteriorModel
from bayes_inerter.records.generator import GeneratorSettings, paper_record


@pytest.fixture(scope="module")
def model():
    rec = paper_record("A3", 1.0, settings=GeneratorSettings(duration=4.0, ramp=1.0), seed=0)
    return PosteriorModel(rec)


def test_least_squares_finds_b_and_phi_is_eq_5_on_the_unfiltered_record(model):
    got = identify(model, starts=2, seed=0, bootstrap=8)
    truth = model.record.metadata["true_parameters"]["b"]
    assert got.b == pytest.approx(truth, rel=0.02)
    # eq. 5 computed here from the fitted parameters, on the raw record in the window
    w = model.window
    phys = [got.values[n] for n in model.names[: model.n_phys]]
    x = np.array([np.log(v) if model.all_priors[n].log_scale else v for n, v in zip(model.names, phys)])
    full = np.concatenate([x, model.bounds()[model.n_phys:].mean(axis=1)])
    sim = model.simulate_unfiltered(full)
    m = model.record.accel[w]
    phi = 1 - np.linalg.norm(sim[w] - m) / np.linalg.norm(m - m.mean())
    assert got.phi == pytest.approx(phi, rel=1e-9)
    # the low-pass takes the noise out: the filtered phi is higher
    assert 0.5 < got.phi < got.phi_filtered <= 1.0
    lo, hi = got.b_interval
    assert lo < hi and len(got.b_draws) == 8 and got.level == 0.94


@pytest.mark.parametrize("bad, message", [(dict(starts=0), "starts"), (dict(bootstrap=-1), "bootstrap"),
                                          (dict(level=1.0), "level")])
def test_bad_options_are_refused(model, bad, message):
    with pytest.raises(ValueError, match=message):
        identify(model, **bad)
