"""Tests of the convergence rule (bayes_inerter.inference.sampling.convergence)."""

import numpy as np
import pytest

from bayes_inerter.inference.sampling.convergence import Convergence, Monitor, check_chain, is_converged, transient, TAU_RTOL


def test_transient_is_none_for_a_chain_in_equilibrium_and_the_climb_for_one_that_is_not():
    rng = np.random.default_rng(0)
    still = rng.normal(2700.0, 2.0, size=(4000, 24))
    assert transient(still) <= 2
    climbing = still.copy()
    climbing[:1500] -= np.linspace(440.0, 0.0, 1500)[:, None]  # a start 440 nats below, as A2 at 0.5 Hz
    assert 1300 <= transient(climbing) <= 1500
    assert transient(still[:3]) == 0  # too short to say


def test_the_warm_up_share_leaves_a_slow_start_out_of_tau():
    # 24 walkers in equilibrium from the start (no transient in the log posterior), whose
    # first 600 steps are a slow AR(1) (tau about 200) and the rest nearly independent
    # (tau about 1.2), as the fitted moves make a chain mix once they have seen it
    rng = np.random.default_rng(4)
    steps, slow = 1800, 600
    x = np.empty((steps, 24, 1))
    x[0] = rng.normal(size=(24, 1))
    for i in range(1, steps):
        a = 0.99 if i < slow else 0.1
        x[i] = a * x[i - 1] + np.sqrt(1 - a * a) * rng.normal(size=(24, 1))
    lp = rng.normal(size=(steps, 24))
    whole = check_chain(x, lp, Convergence(warmup=0.0), rhat_if=lambda *_: False)
    third = check_chain(x, lp, Convergence(warmup=1 / 3), rhat_if=lambda *_: False)
    assert whole.warmup == whole.transient <= 2 and third.warmup == steps // 3
    # the whole chain's tau carries the slow start: 50 of it are far more than the chain;
    # after the warm-up share (600 steps) tau is the fast part's, and 1,200 steps are plenty
    assert whole.tau[0] > 20 and steps - whole.warmup < 50 * whole.tau[0]
    assert third.tau[0] < 3 and steps - third.warmup > 50 * third.tau[0]
    # a transient longer than the share is left out instead (the climb of the test above)
    climbing = lp - np.r_[np.linspace(440.0, 0.0, 900), np.zeros(steps - 900)][:, None]
    late = check_chain(x, climbing, Convergence(warmup=1 / 3), rhat_if=lambda *_: False)
    assert late.warmup == late.transient and 800 <= late.warmup <= 900


def test_a_falling_tau_counts_as_settled_but_a_growing_one_does_not():
    conv = Convergence(tau_rtol=0.05)  # 50 tau, 5 % (the rule these chains were judged by)
    good = dict(rhat=np.array([1.01]), ess=np.array([2000.0]))
    # the adaptive A3 1 Hz chain of benchmarks/bench_adaptation.py at its checks of
    # 4,500 and 5,000 steps: tau fell 3.7 %, the chain is longer than 50 times either
    assert is_converged(5000, np.array([91.7]), np.array([95.2]), conv=conv, **good)
    # fallen by 10 %, more than the 5 % that the old two-sided rule allowed: settled
    assert is_converged(5000, np.array([90.0]), np.array([99.0]), conv=conv, **good)
    # grown by more than 5 %: underestimated, wait (5 % of the earlier estimate)
    assert not is_converged(5000, np.array([95.2]), np.array([89.0]), conv=conv, **good)
    assert not is_converged(5000, np.array([94.0]), np.array([89.4]), conv=conv, **good)  # 5.1 %
    assert is_converged(5000, np.array([93.8]), np.array([89.4]), conv=conv, **good)  # 4.9 %
    # fallen, but the chain is shorter than 50 times the last check's estimate
    assert not is_converged(5000, np.array([91.7]), np.array([101.0]), conv=conv, **good)
    # R-hat and ESS still decide
    assert not is_converged(5000, np.array([91.7]), np.array([95.2]), rhat=np.array([1.06]),
                             ess=np.array([2000.0]), conv=conv)


def test_growth_judged_against_the_largest_tau_ignores_a_small_taus_wander():
    good = dict(rhat=np.array([1.01, 1.01]), ess=np.array([2000.0, 2000.0]))
    each, largest = Convergence(tau_rtol=0.05), Convergence(growth="largest", tau_rtol=0.05)
    # the largest tau steady, a parameter with a fifth of it grown 10 % of itself (2 % of the largest)
    tau, previous = np.array([60.0, 13.2]), np.array([60.0, 12.0])
    assert not is_converged(5000, tau, previous, conv=each, **good)
    assert is_converged(5000, tau, previous, conv=largest, **good)
    # a small tau that grew by more than 5 % of the largest: not settled either way
    tau = np.array([60.0, 15.5])
    assert not is_converged(5000, tau, previous, conv=largest, **good)
    # the largest tau grown 10 %: both wait
    tau = np.array([66.0, 12.0])
    assert not is_converged(5000, tau, previous, conv=each, **good)
    assert not is_converged(5000, tau, previous, conv=largest, **good)


def test_the_default_tolerance_lets_tau_wander_by_a_fifth_between_checks():
    """``TAU_RTOL``: a tau estimated from a few hundred steps is noisy; growth up to a
    fifth of itself since the last check is taken for that noise, more is not."""
    good = dict(rhat=np.array([1.01, 1.01]), ess=np.array([2000.0, 2000.0]))
    assert Convergence().tau_rtol == TAU_RTOL == 0.2
    previous = np.array([10.0, 6.0])
    assert is_converged(1000, np.array([11.9, 6.0]), previous, conv=Convergence(), **good)
    assert not is_converged(1000, np.array([12.1, 6.0]), previous, conv=Convergence(), **good)
    assert not is_converged(1000, np.array([11.9, 6.0]), previous, conv=Convergence(tau_rtol=0.05), **good)
    # the length part is unchanged: 50 times the larger of the two checks' tau
    assert not is_converged(590, np.array([11.9, 6.0]), previous, conv=Convergence(), **good)


def test_an_unknown_growth_judgement_is_refused():
    with pytest.raises(ValueError, match="growth must be one of each, largest"):
        Convergence(growth="median")


@pytest.mark.parametrize("steps", [7, 300, 1000])
def test_integrated_time_is_emcees(steps):
    """The batched estimate gives emcee's tau on AR(1) chains of several colours, and NaN
    where a walker never moved, as emcee does."""
    import emcee

    from bayes_inerter.inference.sampling.convergence import integrated_time

    rng = np.random.default_rng(steps)
    noise = rng.standard_normal((steps, 8, 3))
    chain = np.empty_like(noise)
    rho = np.array([0.0, 0.7, 0.98])
    chain[0] = noise[0]
    for t in range(1, steps):
        chain[t] = rho * chain[t - 1] + noise[t]
    expected = emcee.autocorr.integrated_time(chain, tol=0)
    np.testing.assert_allclose(integrated_time(chain), expected, rtol=1e-12)
    assert integrated_time(chain)[2] > integrated_time(chain)[0]  # the slow AR(1) is slower
    chain[:, 3, 1] = 0.5  # a walker that never moved in one parameter
    with np.errstate(invalid="ignore", divide="ignore"):
        stuck = emcee.autocorr.integrated_time(chain, tol=0)
    got = integrated_time(chain)
    assert np.isnan(got[1]) and np.isnan(stuck[1])
    np.testing.assert_allclose(got[[0, 2]], stuck[[0, 2]], rtol=1e-12)


def test_integrated_time_refuses_a_chain_without_walkers():
    from bayes_inerter.inference.sampling.convergence import integrated_time

    with pytest.raises(ValueError, match="steps, walkers, ndim"):
        integrated_time(np.zeros((10, 3)))


def test_the_rule_never_stops_at_its_first_check_but_can_at_the_next():
    # independent draws: tau about 1 step, R-hat near 1, ESS in the thousands, so every
    # part of the rule but tau's comparison with an earlier check holds after 250
    # steps (tau's own scatter between checks, a few % at 1 step, given room)
    conv = Convergence(tau_rtol=0.5)
    rng = np.random.default_rng(3)
    chain = rng.normal(size=(500, 24, 2))
    log_prob = rng.normal(size=(500, 24))
    monitor = Monitor(conv)
    first, ok = monitor.check(chain[:250], log_prob[:250])
    assert not ok and np.max(first.tau) < 2.0
    assert monitor.check(chain, log_prob)[1]
    # a run continued after its first check takes that check's tau and may stop at the second
    resumed = Monitor(conv)
    resumed.resume(chain, log_prob, done=300)
    assert resumed.check(chain, log_prob)[1]


def test_the_replicas_tau_counts_where_the_rule_reads_them():
    # the posterior's slots nearly independent (as swaps make them), the replicas an AR(1)
    # with tau about 40: read on the replicas (the default), the rule takes their tau
    rng = np.random.default_rng(11)
    steps = 2000
    chain = rng.normal(size=(steps, 8, 2))
    paths = np.empty((steps, 24, 2))
    paths[0] = rng.normal(size=(24, 2))
    a = 0.95  # tau = (1 + a) / (1 - a) = 39
    for i in range(1, steps):
        paths[i] = a * paths[i - 1] + np.sqrt(1 - a * a) * rng.normal(size=(24, 2))
    lp = rng.normal(size=(steps, 8))
    off = check_chain(chain, lp, Convergence(replicas=False), rhat_if=lambda *_: False, replicas=paths)
    on = check_chain(chain, lp, Convergence(), rhat_if=lambda *_: False, replicas=paths)  # the default reads them
    assert off.replica_tau is None and np.all(off.tau < 2)
    assert np.all((on.replica_tau > 25) & (on.replica_tau < 60))
    assert np.array_equal(on.tau, np.maximum(off.tau, on.replica_tau))
    with pytest.raises(ValueError, match="replicas' trajectories hold 10 steps"):
        check_chain(chain, lp, Convergence(replicas=True), replicas=paths[:10])
