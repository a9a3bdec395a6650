"""The sampler's open-ended runs: a continued chain is checked where an uninterrupted
run would be, so it stops at the same step with the same chain; a converged chain run
again comes back as it is. Its adaptation: fitted only after the transient, used in its
share of the steps, and refitted so that a continued chain is the uninterrupted one."""

import numpy as np
import pytest
from conftest import normal_posterior

from bayes_inerter.inference import Convergence
from bayes_inerter.inference.sampling.sampler import START_PHASES, Adaptation, run_sampler

CONV = Convergence(check_every=40, n_tau=20, min_ess=200, max_steps=2000)


@pytest.fixture(scope="module")
def model():
    # the record's posterior swapped for a cheap known density: independent normals in theta
    return normal_posterior(duration=1.5, ramp=0.5)


def _run(model, path, max_steps):
    conv = Convergence(**{**CONV.__dict__, "max_steps": max_steps})
    return run_sampler(model, path, nwalkers=24, seed=3, convergence=conv, start=model.test_start)


@pytest.mark.slow
def test_a_continued_chain_stops_where_an_uninterrupted_one_does(model, tmp_path):
    whole = _run(model, tmp_path / "whole.h5", 2000)
    assert whole.converged and whole.iteration % CONV.check_every == 0
    # stopped off a check boundary (and between two refits of the adaptive proposal),
    # then continued; the stopped run may or may not call its shorter chain converged
    cut = int(whole.iteration) - CONV.check_every - 13
    assert cut > Adaptation().every and cut % Adaptation().every
    first = _run(model, tmp_path / "cut.h5", cut)
    assert first.iteration == cut
    again = _run(model, tmp_path / "cut.h5", 2000)
    assert again.converged and again.iteration == whole.iteration
    assert np.array_equal(again.sampler.get_chain(), whole.sampler.get_chain())


@pytest.mark.slow
def test_a_chain_stopped_on_a_check_continues_with_that_checks_tau(model, tmp_path):
    # stopped exactly on a check before convergence: continued, it must be checked there
    # again with the tau of the check before (as the uninterrupted run was) and go on
    whole = _run(model, tmp_path / "whole.h5", 2000)
    cut = int(whole.iteration) - CONV.check_every
    assert not _run(model, tmp_path / "cut.h5", cut).converged
    again = _run(model, tmp_path / "cut.h5", 2000)
    assert again.iteration == whole.iteration
    assert np.array_equal(again.sampler.get_chain(), whole.sampler.get_chain())


@pytest.mark.slow
def test_a_converged_chain_run_again_comes_back_as_it_is(model, tmp_path):
    done = _run(model, tmp_path / "c.h5", 2000)
    again = _run(model, tmp_path / "c.h5", 2000)
    assert again.converged and again.iteration == done.iteration


def test_a_run_keeps_its_draws_after_the_warm_up(model, tmp_path):
    from bayes_inerter.inference.summaries.results import posterior_sample

    run = run_sampler(model, tmp_path / "c.h5", nwalkers=24, seed=3, steps=300, start=model.test_start,
                      convergence=Convergence(warmup=0.4))
    assert run.warmup == max(run.transient, 120)
    sample = posterior_sample(model, run)
    assert sample.burn >= run.warmup + 2 * int(np.max(run.tau)) > run.warmup


def test_a_run_stopped_between_refits_continues_to_the_uninterrupted_chain(model, tmp_path):
    adapt = Adaptation(every=30)

    def run(path, steps):
        return run_sampler(model, path, nwalkers=24, seed=5, steps=steps, start=model.test_start, adaptation=adapt)

    whole = run(tmp_path / "whole.h5", 100)
    assert any("IndependenceMove" in m for m in whole.moves)
    run(tmp_path / "cut.h5", 47)  # after the refit at 30, before the one at 60
    again = run(tmp_path / "cut.h5", 100)
    assert np.array_equal(again.sampler.get_chain(), whole.sampler.get_chain())
    # the proposal did take part: the run differs from one without it after step 30
    plain = run_sampler(model, tmp_path / "plain.h5", nwalkers=24, seed=5, steps=100, start=model.test_start,
                        adaptation=None)
    assert np.array_equal(plain.sampler.get_chain()[:30], whole.sampler.get_chain()[:30])
    assert not np.array_equal(plain.sampler.get_chain()[30:], whole.sampler.get_chain()[30:])


def test_a_checkpoint_continues_only_with_the_kernel_it_was_sampled_with(model, tmp_path):
    import h5py

    from bayes_inerter.inference.sampling.checkpoint import IDENTITY_ATTR, CheckpointError, twin_path

    path = tmp_path / "c.h5"
    short = run_sampler(model, path, nwalkers=24, seed=5, steps=20, start=model.test_start, adaptation=Adaptation())
    # 20 steps: no refit had steps to fit, so the chain used the ensemble moves alone and says so
    assert not any("IndependenceMove" in m for m in short.moves)
    with pytest.raises(CheckpointError, match="no adaptation.*--fresh"):
        run_sampler(model, path, nwalkers=24, seed=5, steps=40, start=model.test_start, adaptation=None)
    with pytest.raises(CheckpointError, match="kernel"):
        run_sampler(model, path, nwalkers=24, seed=5, steps=40, start=model.test_start, adaptation=Adaptation(every=30))
    assert run_sampler(model, path, nwalkers=24, seed=5, steps=40, start=model.test_start).iteration == 40
    # a checkpoint of an earlier format (no identity: written before it was data) is
    # refused, with either kernel; --fresh starts it over
    with h5py.File(path, "a") as f:
        del f["mcmc"].attrs[IDENTITY_ATTR]
    twin_path(path).unlink()
    for adaptation in (None, Adaptation()):
        with pytest.raises(CheckpointError, match="older version of bayes-inerter.*--fresh"):
            run_sampler(model, path, nwalkers=24, seed=5, steps=50, start=model.test_start, adaptation=adaptation)
    assert run_sampler(model, path, nwalkers=24, seed=5, steps=50, start=model.test_start,
                       adaptation=None, fresh=True).iteration == 50


def test_a_chain_keeps_its_likelihoods_reference_point_when_continued(tmp_path):
    """The motion-in likelihood's normaliser takes the noise at the chain's start; the
    checkpoint remembers that point, so a continued chain samples the same posterior
    without searching for a start again."""
    import dataclasses

    from bayes_inerter import paper_parameters
    from bayes_inerter.inference import PosteriorModel
    from bayes_inerter.inference.sampling.checkpoint import stored_identity
    from bayes_inerter.records import generate_record

    pm = PosteriorModel(generate_record(paper_parameters("A3"), 1.5, rng=0, setting_name="A3"))
    assert pm.needs_reference and pm.reference_noise is None
    theta = pm.to_theta(dataclasses.replace(paper_parameters("A3"), c_B=2420.0), hyper={"tau": 1.0})
    path = tmp_path / "c.h5"
    first = run_sampler(pm, path, nwalkers=2 * pm.ndim + 2, seed=1, steps=4, start=(theta, pm.log_prob(theta)[0]),
                        adaptation=None)
    assert first.model.reference == tuple(theta) and first.model.reference_noise is not None
    assert stored_identity(path)["reference"] == list(theta)
    # the normaliser differs from the parameters' own: the chain's density is the referenced model's
    lp = first.log_prob()[-1]  # in theta, without the coordinates' Jacobian
    walkers = first.chain()[-1]
    np.testing.assert_allclose(lp, [first.model.log_prob(w)[0] for w in walkers], rtol=1e-9)
    assert np.all(np.abs(lp - [pm.log_prob(w)[0] for w in walkers]) > 1e-6)

    def no_search():
        raise AssertionError("a continued chain searched for a start")

    again = run_sampler(pm, path, nwalkers=2 * pm.ndim + 2, seed=1, steps=8, start=no_search, adaptation=None)
    assert again.iteration == 8 and again.model.reference == first.model.reference
    # a new chain's start is timed by phase; a continued chain has no start to time
    assert set(first.start_seconds) == set(START_PHASES) and first.start_seconds["ensemble"] > 0
    assert min(first.start_seconds.values()) >= 0
    assert again.start_seconds == {}


def test_a_searched_start_shares_the_walkers_with_a_held_viscous_sums_mode(tmp_path, monkeypatch):
    """Where c_f's posterior has two separated optima and the start search ends at one,
    the polish with c_f held at a tenth of the start's (``optimize.held_modes``) finds the
    other and half the walkers begin there; with no parameter held, none do."""
    from scipy import stats

    import bayes_inerter.inference.sampling.optimize as optimize
    import bayes_inerter.inference.sampling.sampler as sampler

    pm = normal_posterior(duration=1.5, ramp=0.5)
    centre = pm.test_start[0].copy()
    i = pm.names.index("c_f")
    lo, hi = pm.bounds().T
    high, low = min(centre[i], hi[i] - 0.5), min(centre[i], hi[i] - 0.5) - 2.0  # log c_f: a factor e^2 apart
    assert low > lo[i] + 0.5
    sd = np.minimum(hi - centre, centre - lo) / 6
    rest = np.arange(len(centre)) != i

    def two_optima(theta):
        theta = np.asarray(theta, dtype=float)
        if np.any(theta < lo) or np.any(theta > hi):
            return -np.inf, np.nan
        ends = np.logaddexp(stats.norm.logpdf(theta[i], high, 0.05), stats.norm.logpdf(theta[i], low, 0.05) - 1.0)
        return float(np.sum(stats.norm.logpdf(theta[rest], centre[rest], sd[rest])) + ends), 0.0

    pm.log_prob = two_optima
    start = centre.copy()
    start[i] = high
    monkeypatch.setattr(sampler, "find_start", lambda model, rng, many=None, map=None: (start, two_optima(start)[0]))
    monkeypatch.setattr(optimize, "MIRROR_SHARES", ())

    def first_viscous(path):
        return run_sampler(pm, path, nwalkers=24, seed=3, steps=1, adaptation=None).chain()[0][:, i]

    monkeypatch.setattr(optimize, "HELD_MODES", {"c_f": (0.1,)})
    held = first_viscous(tmp_path / "held.h5")
    assert 8 <= np.sum(np.abs(held - low) < 0.3) <= 16 and np.sum(np.abs(held - high) < 0.3) >= 8
    monkeypatch.setattr(optimize, "HELD_MODES", {})
    assert np.all(np.abs(first_viscous(tmp_path / "none.h5") - high) < 0.3)


def test_a_searched_start_puts_half_the_walkers_in_the_splits_mirrored_mode(tmp_path, monkeypatch):
    """Where the friction split's posterior has a mode at either end and the start
    search ends at one, half the walkers begin at the other (``optimize.mirrored_modes``);
    a start the caller gives is left as it is."""
    from scipy import stats

    import bayes_inerter.inference.sampling.sampler as sampler

    pm = normal_posterior(duration=1.5, ramp=0.5)
    centre = pm.test_start[0].copy()
    i = pm.names.index("f_share")
    lo, hi = pm.bounds().T
    sd = np.minimum(hi - centre, centre - lo) / 6
    rest = np.arange(len(centre)) != i

    def two_ends(theta):
        theta = np.asarray(theta, dtype=float)
        if not 0.0 <= theta[i] <= 1.0:
            return -np.inf, np.nan
        ends = np.logaddexp(stats.norm.logpdf(theta[i], 0.1, 0.02), stats.norm.logpdf(theta[i], 0.9, 0.02))
        return float(np.sum(stats.norm.logpdf(theta[rest], centre[rest], sd[rest])) + ends), 0.0

    pm.log_prob = two_ends
    start = centre.copy()
    start[i] = 0.1
    monkeypatch.setattr(sampler, "find_start", lambda model, rng, many=None, map=None: (start, two_ends(start)[0]))

    def first_shares(path, given=None):
        run = run_sampler(pm, path, nwalkers=24, seed=3, steps=1, start=given, adaptation=None)
        return run.chain()[0][:, i]

    searched = first_shares(tmp_path / "searched.h5")
    assert 8 <= np.sum(searched > 0.5) <= 16 and np.sum(np.abs(searched - 0.9) < 0.1) >= 8
    given = first_shares(tmp_path / "given.h5", given=(start, two_ends(start)[0]))
    assert np.all(given < 0.5)


def test_on_a_flat_likelihood_the_chain_is_the_prior_inside_the_impedance_domain(tmp_path):
    """The default moves, their fitted proposals and the impedance coordinates (logits at
    the uniform priors' walls, the modal damping ratio's and the hyper-parameters'
    priors) sample the motion-in model's prior restricted to the coordinates' domain,
    the prior a fit in them assumes: the chain's marginals are those of exact draws,
    by a two-sample KS test on the chain thinned to about one draw per autocorrelation
    time, and so is its share of draws in every pair of parameters' joint corners."""
    from scipy import stats

    from bayes_inerter import paper_parameters
    from bayes_inerter.inference import PosteriorModel
    from bayes_inerter.inference.sampling.convergence import integrated_time
    from bayes_inerter.inference.sampling.coordinates import default_coordinates
    from bayes_inerter.records import GeneratorSettings, generate_record
    from bayes_inerter.study.study_calibration import STUDY_SBC_PRIORS

    record = generate_record(paper_parameters("A3"), 1.5, settings=GeneratorSettings(duration=4.0, ramp=0.8),
                             rng=2, setting_name="A3")

    class Flat(PosteriorModel):  # the record says nothing (a subclass: the sampler may replace() the model)
        def log_likelihood(self, theta, *, marginal_scale=False):
            return 0.0, 1.0

    model = Flat(record, priors=STUDY_SBC_PRIORS)
    coords = default_coordinates(model, "impedance")
    assert coords.kind == "impedance"
    rng = np.random.default_rng(7)
    exact = np.array([[model.all_priors[n].sample(rng) for n in model.names] for _ in range(30000)])
    exact = exact[np.all(np.isfinite(coords.to_u(exact)), axis=1)]
    assert 0.5 < len(exact) / 30000 < 1.0  # the domain cuts the box, but not most of it
    start = exact[0]
    run = run_sampler(model, tmp_path / "chain.h5", steps=2000, seed=4, start=(start, model.log_prob(start)[0]),
                      coordinates=coords)
    chain = run.chain(discard=1000)  # walkers started around one point spread out over the prior
    tau = float(np.max(integrated_time(chain)))
    draws = chain[:: max(1, round(tau))].reshape(-1, model.ndim)
    assert len(draws) > 300
    p = [stats.ks_2samp(draws[:, i], exact[:, i]).pvalue for i in range(model.ndim)]
    assert min(p) > 1e-3, dict(zip(model.names, np.round(p, 4)))
    # the corners jointly: for every pair, the share of draws beyond both parameters'
    # exact 10 or 90 % quantiles at once (a corner of the pair's square), within 4 se
    lo, hi = np.quantile(exact, [0.1, 0.9], axis=0)
    out_chain, out_exact = (draws < lo) | (draws > hi), (exact < lo) | (exact > hi)
    for i in range(model.ndim):
        for j in range(i):
            want = np.mean(out_exact[:, i] & out_exact[:, j])
            got = np.mean(out_chain[:, i] & out_chain[:, j])
            assert abs(got - want) < 4 * np.sqrt(want * (1 - want) / len(draws)), (model.names[i], model.names[j])
