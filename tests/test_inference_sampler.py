"""The sampler's open-ended runs: a continued chain is checked where an uninterrupted
run would be, so it stops at the same step with the same chain; a converged chain run
again comes back as it is."""

import numpy as np
import pytest
from scipy import stats

from bayes_inerter import paper_parameters
from bayes_inerter.inference import Convergence, PosteriorModel
from bayes_inerter.inference.sampler import run_sampler, transient
from bayes_inerter.records import GeneratorSettings, generate_record

CONV = Convergence(check_every=40, n_tau=20, min_ess=200, max_steps=2000)


@pytest.fixture(scope="module")
def model():
    rec = generate_record(paper_parameters("A2"), 1.0, settings=GeneratorSettings(duration=1.5, ramp=0.5), rng=2,
                          setting_name="A2")
    pm = PosteriorModel(rec)
    # the record's posterior swapped for a cheap known density: independent normals in theta
    centre = pm.to_theta(paper_parameters("A2"), 3e-3, 0.2)
    lo, hi = pm.bounds().T
    sd = np.minimum(hi - centre, centre - lo) / 6
    pm.log_prob = lambda theta: (float(np.sum(stats.norm.logpdf(theta, centre, sd))), 0.0)
    pm.test_start = (centre, 0.0)
    return pm


def _run(model, path, max_steps):
    conv = Convergence(**{**CONV.__dict__, "max_steps": max_steps})
    return run_sampler(model, path, nwalkers=24, seed=3, convergence=conv, start=model.test_start)


def test_a_continued_chain_stops_where_an_uninterrupted_one_does(model, tmp_path):
    whole = _run(model, tmp_path / "whole.h5", 2000)
    assert whole.converged and whole.iteration % CONV.check_every == 0
    # stopped off a check boundary, then continued
    cut = int(whole.iteration) - CONV.check_every - 13
    first = _run(model, tmp_path / "cut.h5", cut)
    assert first.iteration == cut and not first.converged
    again = _run(model, tmp_path / "cut.h5", 2000)
    assert again.converged and again.iteration == whole.iteration
    assert np.array_equal(again.sampler.get_chain(), whole.sampler.get_chain())


def test_a_chain_stopped_on_a_check_continues_with_that_checks_tau(model, tmp_path):
    # stopped exactly on a check before convergence: continued, it must be checked there
    # again with the tau of the check before (as the uninterrupted run was) and go on
    whole = _run(model, tmp_path / "whole.h5", 2000)
    cut = int(whole.iteration) - CONV.check_every
    assert not _run(model, tmp_path / "cut.h5", cut).converged
    again = _run(model, tmp_path / "cut.h5", 2000)
    assert again.iteration == whole.iteration
    assert np.array_equal(again.sampler.get_chain(), whole.sampler.get_chain())


def test_a_converged_chain_run_again_comes_back_as_it_is(model, tmp_path):
    done = _run(model, tmp_path / "c.h5", 2000)
    again = _run(model, tmp_path / "c.h5", 2000)
    assert again.converged and again.iteration == done.iteration


def test_transient_is_none_for_a_chain_in_equilibrium_and_the_climb_for_one_that_is_not():
    rng = np.random.default_rng(0)
    still = rng.normal(2700.0, 2.0, size=(4000, 24))
    assert transient(still) <= 2
    climbing = still.copy()
    climbing[:1500] -= np.linspace(440.0, 0.0, 1500)[:, None]  # a start 440 nats below, as A2 at 0.5 Hz
    assert 1300 <= transient(climbing) <= 1500
    assert transient(still[:3]) == 0  # too short to say
