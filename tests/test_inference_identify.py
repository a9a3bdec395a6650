"""Tests of the paper's least-squares identification (bayes_inerter.inference.identify)."""

import numpy as np
import pytest

from bayes_inerter.inference.identify import LEAST_SQUARES, identify
from bayes_inerter.inference.posterior.model import PosteriorModel
from bayes_inerter.records.generator import GeneratorSettings, paper_record


@pytest.fixture(scope="module")
def model():
    rec = paper_record("A3", 1.0, settings=GeneratorSettings(duration=4.0, ramp=1.0), seed=0)
    # the model the command line and the study identify with: the time-domain one
    return PosteriorModel(rec, likelihood=LEAST_SQUARES)


def test_least_squares_finds_b_and_phi_is_eq_5_on_the_unfiltered_record(model):
    got = identify(model, starts=2, seed=0, bootstrap=8)
    truth = model.record.metadata["true_parameters"]["b"]
    # two starts, the best kept: b within 0.6 % of the truth from each of ten single starts
    # tried (other seeds and start searches, some ending with f_share on a bound), and
    # within 0.5 % from twelve more with the BLAS's and numpy's code paths forced to older
    # processors'; the worst single start seen, a fit ten times worse than those (c_B held
    # at its lower bound), is 3 % off. The bound is set past that, so that no processor's
    # arithmetic decides the verdict: least squares on a record of the model's own
    # physics lands near b, not on it to a precision set by one start
    assert got.b == pytest.approx(truth, rel=0.05)
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


def test_the_default_interval_is_the_cycle_clustered_hessian(model):
    got = identify(model, starts=1, seed=0)
    assert got.interval == "hessian" and got.level == 0.94 and got.b_draws == ()
    # one start: where it ends (a parameter on a bound, a flat direction) depends on the
    # processor's floating-point path, so only what holds wherever it ends is asserted
    if got.b_interval is None:
        assert got.why
    else:
        lo, hi = got.b_interval
        assert lo < got.b < hi
    # 4 s at 1 Hz less the likelihood's edges: every whole cycle of the window, none more
    assert got.cycles == len(model.window) // int(round(model.fs))


class _Prior:
    def __init__(self, log_scale):
        self.log_scale = log_scale


class _Names:
    """What the sandwich needs of a model: the names and b's prior scale."""

    def __init__(self, names, log_scale=False):
        self.names = names
        self.all_priors = {"b": _Prior(log_scale)}


def test_the_sandwich_is_the_cluster_robust_variance_of_least_squares():
    from scipy import stats

    from bayes_inerter.inference.identify import _sandwich_interval

    rng = np.random.default_rng(3)
    n, period = 60, 12
    jac = np.column_stack([rng.normal(size=n), rng.normal(size=n) * 3.0])
    resid = rng.normal(size=n)
    blocks = [slice(i, i + period) for i in range(0, n, period)]
    (lo, hi), why = _sandwich_interval(_Names(["b", "c"]), np.array([10.0, 1.0]), jac, resid, blocks, 0.94)
    # written out for a linear model: beta_hat - beta = (J'J)^-1 J' r, summed over clusters
    bread = np.linalg.inv(jac.T @ jac)
    meat = sum(np.outer(jac[c].T @ resid[c], jac[c].T @ resid[c]) for c in blocks) * 5 / 4
    sd = np.sqrt((bread @ meat @ bread)[0, 0])
    half = stats.t.ppf(0.97, 4) * sd
    assert why == "" and (lo, hi) == pytest.approx((10.0 - half, 10.0 + half), rel=1e-10)
    # b sampled in log: the interval is exp of the one in log b
    (lo2, hi2), _ = _sandwich_interval(_Names(["b", "c"], log_scale=True), np.array([np.log(10.0), 1.0]), jac,
                                       resid, blocks, 0.94)
    assert (lo2, hi2) == pytest.approx((10.0 * np.exp(-half), 10.0 * np.exp(half)), rel=1e-10)


def test_no_sandwich_where_the_record_leaves_a_direction_flat():
    from bayes_inerter.inference.identify import _sandwich_interval

    rng = np.random.default_rng(4)
    col = rng.normal(size=40)
    blocks = [slice(i, i + 10) for i in range(0, 40, 10)]
    got, why = _sandwich_interval(_Names(["b", "c"]), np.zeros(2), np.column_stack([col, 2 * col]),
                                  rng.normal(size=40), blocks, 0.94)
    assert got is None and "flat" in why
    got, why = _sandwich_interval(_Names(["b", "c"]), np.zeros(2), np.column_stack([col, 2 * col]),
                                  rng.normal(size=40), blocks[:1], 0.94)
    assert got is None and "two whole drive cycles" in why


def test_a_bootstrap_interval_needs_replicates(model):
    with pytest.raises(ValueError, match="bootstrap replicates"):
        identify(model, interval="bootstrap")
    with pytest.raises(ValueError, match="interval must be one of"):
        identify(model, interval="jackknife")
