"""Parallel tempering in the sampler: the cold chain puts each mode's weight where it
belongs though every walker starts in one; a continued tempered run is the
uninterrupted one; a checkpoint continues only with its own ladder."""

import json

import numpy as np
import pytest
from conftest import normal_posterior

from bayes_inerter.inference.sampling.checkpoint import CheckpointError
from bayes_inerter.inference.sampling.sampler import Adaptation, run_sampler
from bayes_inerter.inference.sampling.tempering import Tempering

#: The lighter mode's weight in the two-mode target.
WEIGHT = 0.3


@pytest.fixture(scope="module")
def bimodal():
    """A record's model with its posterior swapped for a flat prior within the model's
    bounds and a likelihood of the first parameter alone: two normals weighted WEIGHT
    and 1 - WEIGHT, 24 sds apart (the valley between them 72 nats down);
    ``test_start`` the lighter mode's centre."""
    pm = normal_posterior(duration=1.5, ramp=0.5)
    lo, hi = pm.bounds().T
    centre = pm.test_start[0]
    sd = min(hi[0] - centre[0], centre[0] - lo[0]) / 30
    light, heavy = centre.copy(), centre.copy()
    light[0] -= 12 * sd
    heavy[0] += 12 * sd

    def log_prior(theta):
        return 0.0 if np.all((theta > lo) & (theta < hi)) else -np.inf

    def log_prob(theta):
        theta = np.asarray(theta, dtype=float)
        if not np.isfinite(log_prior(theta)):
            return -np.inf, np.nan
        z = (theta[0] - np.array([light[0], heavy[0]])) / sd
        return float(np.logaddexp(*(np.log([WEIGHT, 1 - WEIGHT]) - 0.5 * z * z))), 0.0

    pm.log_prior, pm.log_prob = log_prior, log_prob
    pm.test_start = (light, log_prob(light)[0])
    pm.test_split = centre[0]
    return pm


def _light_share(run, model) -> float:
    chain = run.chain(discard=run.iteration // 4)
    return float(np.mean(chain[..., 0] < model.test_split))


def test_the_cold_chain_finds_the_weight_of_a_mode_no_walker_started_in(bimodal, tmp_path):
    common = dict(nwalkers=24, seed=5, start=bimodal.test_start, adaptation=None, coordinates="unconstrained")
    alone = run_sampler(bimodal, tmp_path / "alone.h5", steps=400, **common)
    tempered = run_sampler(bimodal, tmp_path / "pt.h5", steps=600, tempering=Tempering(temps=3, beta_min=0.01),
                           **common)
    # the ensemble moves alone stay in the mode the walkers started in
    assert _light_share(alone, bimodal) > 0.95
    # tempered, the cold chain's share of the light mode is its weight; the tolerance is
    # four times the binomial sd of a few dozen independent draws
    assert abs(_light_share(tempered, bimodal) - WEIGHT) < 0.15
    assert len(tempered.swap_rates) == 2 and all(0.0 < r <= 1.0 for r in tempered.swap_rates)


@pytest.mark.parametrize("damage, adapt_hot", [(False, False), (True, False), (False, True)])
def test_a_continued_tempered_run_is_the_uninterrupted_one(bimodal, tmp_path, damage, adapt_hot):
    # refits every 10 steps (the cut falls between two, the continuation crosses three),
    # every step written; with ``damage`` the stopped run's chain.h5 is spoilt, so the
    # run goes on from its twin; with ``adapt_hot`` the hot ensembles' moves are refitted
    # too, from their stored walkers
    common = dict(nwalkers=24, seed=7, start=bimodal.test_start,
                  tempering=Tempering(temps=3, beta_min=0.2, adapt_hot=adapt_hot),
                  coordinates="unconstrained", adaptation=Adaptation(every=10), checkpoint_seconds=0)
    whole = run_sampler(bimodal, tmp_path / "whole.h5", steps=45, **common)
    run_sampler(bimodal, tmp_path / "cut.h5", steps=17, **common)
    if damage:
        (tmp_path / "cut.h5").write_bytes(b"not HDF5")
    again = run_sampler(bimodal, tmp_path / "cut.h5", steps=45, **common)
    assert again.resumed_at == 17 and again.iteration == 45
    assert bool(again.recovered) == damage
    assert np.array_equal(again.sampler.get_chain(), whole.sampler.get_chain())
    assert np.array_equal(again.sampler.get_log_prob(), whole.sampler.get_log_prob())
    assert again.swap_rates == whole.swap_rates
    for name in ("hot_chain", "replicas"):  # the replicas' history too, step by step
        assert np.array_equal(again.sampler.backend.get_rows(name), whole.sampler.backend.get_rows(name))
    if adapt_hot:  # the hot ensembles' own fitted moves changed the chain
        plain = run_sampler(bimodal, tmp_path / "plain.h5", steps=45,
                            **{**common, "tempering": Tempering(temps=3, beta_min=0.2)})
        assert not np.array_equal(plain.sampler.get_chain(), whole.sampler.get_chain())


def test_a_write_of_the_hot_ensembles_cut_short_leaves_the_sealed_state_whole(bimodal, tmp_path):
    import h5py

    from bayes_inerter.inference.sampling.checkpoint import read_chain
    from bayes_inerter.inference.sampling.twin_backend import EXTRA, GROUP, SEAL

    common = dict(nwalkers=24, seed=7, start=bimodal.test_start, tempering=Tempering(temps=3, beta_min=0.2),
                  coordinates="unconstrained", steps=6, checkpoint_seconds=0)  # a write a step: both slots used
    run_sampler(bimodal, tmp_path / "c.h5", **common)
    with h5py.File(tmp_path / "c.h5", "a") as f:
        g = f[GROUP]
        sealed = json.loads(g.attrs[SEAL])["extra_slot"]
        other = g[EXTRA][str(1 - int(sealed))]["hot_coords"]  # a kill inside the next write's slot
        other[...] = np.nan
    assert read_chain(tmp_path / "c.h5").shape[0] == 6  # still intact: the sealed slot is whole
    with h5py.File(tmp_path / "c.h5", "a") as f:
        f[GROUP][EXTRA][sealed]["hot_coords"][...] = 0.0  # the sealed slot spoilt: the file is damaged
    again = run_sampler(bimodal, tmp_path / "c.h5", **{**common, "steps": 8})
    assert "c.h5" in again.recovered and again.resumed_at == 6


def test_a_tempered_checkpoint_continues_only_with_its_own_ladder(bimodal, tmp_path):
    common = dict(nwalkers=24, seed=7, start=bimodal.test_start, coordinates="unconstrained", steps=5)
    run_sampler(bimodal, tmp_path / "c.h5", tempering=Tempering(temps=3, beta_min=0.2), **common)
    with pytest.raises(CheckpointError, match="no tempering now"):
        run_sampler(bimodal, tmp_path / "c.h5", **{**common, "steps": 8})
    with pytest.raises(CheckpointError, match="tempering ladder"):
        run_sampler(bimodal, tmp_path / "c.h5", tempering=Tempering(temps=4, beta_min=0.2), **{**common, "steps": 8})


@pytest.mark.parametrize("kwargs, message", [({"temps": 1}, "at least 2"), ({"beta_min": 0.0}, "in \\(0, 1\\)"),
                                             ({"beta_min": 1.0}, "in \\(0, 1\\)")])
def test_a_ladder_that_cannot_temper_is_refused(kwargs, message):
    with pytest.raises(ValueError, match=message):
        Tempering(**kwargs)


def test_the_ladder_is_geometric_from_the_posterior_down():
    betas = Tempering(temps=4, beta_min=0.1).betas
    assert betas[0] == 1.0 and np.isclose(betas[-1], 0.1)
    assert np.allclose(betas[1:] / betas[:-1], betas[1] / betas[0])


def test_a_tempered_fit_given_no_rule_is_capped_at_its_own_steps():
    from bayes_inerter.inference.sampling.convergence import Convergence
    from bayes_inerter.inference.sampling.tempering import MAX_STEPS, Tempering, default_convergence

    assert default_convergence(None) == Convergence()
    tempered = default_convergence(Tempering())
    assert tempered.max_steps == MAX_STEPS == 10_000
    assert tempered == Convergence(max_steps=MAX_STEPS)  # the rule is otherwise the package's
    # in evaluations, twice the untempered cap with the default ladder
    assert MAX_STEPS * Tempering().temps == 2 * Convergence().max_steps


def test_each_hot_ensemble_starts_at_its_own_temperatures_spread(tmp_path):
    # drawn at the posterior's own spread, a hot ensemble starts far narrower than its
    # equilibrium, and its swaps then pull the cold chain in towards the mode
    pm = normal_posterior(duration=1.5, ramp=0.5)
    normal = pm.log_prob
    pm.log_prob = lambda theta: normal(theta) if np.isfinite(pm.log_prior(theta)) else (-np.inf, np.nan)
    ladder = Tempering(temps=2, beta_min=0.25)
    run = run_sampler(pm, tmp_path / "c.h5", steps=1, nwalkers=300, seed=3, start=pm.test_start, adaptation=None,
                      coordinates="physical", tempering=ladder)
    cold = run.chain()[0]
    hot = np.asarray(run.sampler.backend.extra["hot_coords"][0])  # after one step: still about as drawn
    ratio = np.median(np.std(hot, axis=0) / np.std(cold, axis=0))
    assert 1.6 < ratio < 2.4  # 1 / sqrt(0.25) = 2


def test_the_replicas_labels_follow_the_walkers_through_the_swaps(bimodal, tmp_path):
    from bayes_inerter.inference.sampling.tempering import replica_trajectories

    ladder = Tempering(temps=3, beta_min=0.01)
    common = dict(nwalkers=24, seed=4, start=bimodal.test_start, adaptation=None, coordinates="unconstrained",
                  tempering=ladder)
    run = run_sampler(bimodal, tmp_path / "a.h5", steps=30, **common)
    extra = run.sampler.backend.extra
    labels = np.asarray(extra["replicas"])
    assert sorted(labels.ravel()) == list(range(72))  # a permutation of the replicas
    assert not np.array_equal(labels, np.arange(72).reshape(3, 24))  # swaps were accepted and relabelled
    # a replica's position is its slot's: the last step's trajectories put each walker
    # of each ensemble at its label's row
    cold = run.sampler.backend.get_chain()[-1:]
    hot = np.asarray(extra["hot_coords"])[None]
    paths = replica_trajectories(cold, hot, labels[None])
    slots = np.concatenate([cold[0][None], hot[0]])
    for t in range(3):
        for w in range(24):
            assert np.array_equal(paths[0, labels[t, w]], slots[t, w])


def test_every_step_keeps_the_hot_walkers_and_labels_the_replica_rule_reads(bimodal, tmp_path):
    from bayes_inerter.inference.sampling.sampler import Convergence

    # the ladder from the light mode's centre, as the first test: swaps decorrelate the
    # posterior's slots at once, while a replica crosses between the modes only through
    # the hottest copies, so the replicas' tau is the larger
    common = dict(nwalkers=24, seed=5, start=bimodal.test_start, adaptation=None, coordinates="unconstrained",
                  tempering=Tempering(temps=3, beta_min=0.01), steps=300)
    slots = run_sampler(bimodal, tmp_path / "a.h5", convergence=Convergence(replicas=False), **common)
    read = run_sampler(bimodal, tmp_path / "b.h5", **common)  # the default rule reads the replicas
    backend = read.sampler.backend
    hot, labels = backend.get_rows("hot_chain"), backend.get_rows("replicas")
    assert hot.shape == (300, 2, 24, bimodal.ndim) and labels.shape == (300, 3, 24)
    assert np.array_equal(hot[-1], backend.extra["hot_coords"].astype(np.float32))
    assert np.array_equal(labels[-1], backend.extra["replicas"])
    assert np.array_equal(read.chain(), slots.chain())  # the rule reads the chain; it changes no step
    assert np.all(read.tau >= slots.tau)
    assert read.tau[0] > 1.5 * slots.tau[0]


def test_a_hot_ensemble_proposes_from_moves_fitted_to_its_own_walkers():
    from bayes_inerter.inference.sampling.adaptation import Adaptation, Schedule
    from bayes_inerter.inference.sampling.moves import IndependenceMove

    rng = np.random.default_rng(3)
    hot = rng.normal(0.0, 1.0, size=(40, 2, 16, 3))  # steps, hot ensembles, walkers, ndim
    hot[:, 1] *= 10.0  # the hotter ensemble ten times wider

    class Stored:
        def get_rows(self, name):
            assert name == "hot_chain"
            return hot

    base = [(object(), 1.0)]
    schedule = Schedule(base, Adaptation(every=20, knots=None, blocks=0.0))
    assert schedule.hot_moves_at(5, Stored(), 0) == base  # nothing fitted before the first period
    for k, spread in ((0, 1.0), (1, 10.0)):  # each ensemble's proposal at its own walkers' spread
        fitted = [m for m, _ in schedule.hot_moves_at(25, Stored(), k) if isinstance(m, IndependenceMove)]
        assert len(fitted) == 1
        sd = np.sqrt(np.diag(fitted[0].chol @ fitted[0].chol.T)) / fitted[0].scale
        assert np.all((0.8 * spread < sd) & (sd < 1.25 * spread))
    assert Schedule(base, None).hot_moves_at(25, Stored(), 0) == base  # no adaptation: the ensemble moves


def test_a_continued_tempered_run_stops_where_the_uninterrupted_one_does(bimodal, tmp_path):
    from bayes_inerter.inference.sampling.sampler import Convergence

    # the rule read on the replicas, checked every 10 steps: the continued run takes the
    # previous check's tau from the stored chain and replicas, as the uninterrupted run
    # carried it, and stops at the same step with the same tau
    conv = Convergence(n_tau=3.0, check_every=10, max_steps=300, min_ess=10.0)
    common = dict(nwalkers=24, seed=9, start=bimodal.test_start, coordinates="unconstrained",
                  tempering=Tempering(temps=3, beta_min=0.2, adapt_hot=True), adaptation=Adaptation(every=10),
                  convergence=conv)
    whole = run_sampler(bimodal, tmp_path / "whole.h5", **common)
    assert whole.converged and 20 <= whole.iteration < 300 and whole.replica_tau is not None
    run_sampler(bimodal, tmp_path / "cut.h5", steps=whole.iteration - 13, **common)
    again = run_sampler(bimodal, tmp_path / "cut.h5", **common)
    assert again.resumed_at == whole.iteration - 13
    assert again.iteration == whole.iteration and again.converged
    assert np.array_equal(again.tau, whole.tau) and np.array_equal(again.replica_tau, whole.replica_tau)
