"""EM for a normal mixture: it finds the components draws were made from, gives the same
answer for the same seed, and refuses what cannot define one."""

import numpy as np
import pytest

from bayes_inerter.inference.mixture import fit_normal_mixture

W = np.array([0.3, 0.7])
MEANS = np.array([[-3.0, 0.0, 1.0], [2.0, 1.0, -1.0]])
COVS = np.array([np.diag([0.5, 1.0, 0.2]), [[1.0, 0.6, 0.0], [0.6, 1.0, 0.0], [0.0, 0.0, 2.0]]])


def _draws(n, seed):
    rng = np.random.default_rng(seed)
    which = rng.random(n) < W[0]
    out = np.where(which[:, None], rng.multivariate_normal(MEANS[0], COVS[0], n),
                   rng.multivariate_normal(MEANS[1], COVS[1], n))
    return out


def test_em_recovers_the_components_draws_were_made_from():
    w, m, c = fit_normal_mixture(_draws(20000, 0), 2, seed=1)
    order = np.argsort(m[:, 0])  # component labels are arbitrary
    w, m, c = w[order], m[order], c[order]
    # standard errors at n = 20,000: a weight's sqrt(0.21 / n) = 0.003, a mean's about 0.01
    np.testing.assert_allclose(w, W, atol=0.015)
    np.testing.assert_allclose(m, MEANS, atol=0.05)
    np.testing.assert_allclose(c, COVS, atol=0.08)


def test_em_is_deterministic_for_a_seed():
    x = _draws(3000, 2)
    a, b = fit_normal_mixture(x, 3, seed=4), fit_normal_mixture(x, 3, seed=4)
    for u, v in zip(a, b):
        np.testing.assert_array_equal(u, v)


def test_one_component_is_the_draws_mean_and_covariance():
    x = _draws(5000, 3)
    w, m, c = fit_normal_mixture(x, 1)
    np.testing.assert_allclose(w, [1.0])
    np.testing.assert_allclose(m[0], x.mean(axis=0), atol=1e-10)
    np.testing.assert_allclose(c[0], np.cov(x, rowvar=False, bias=True), rtol=1e-4, atol=1e-5)  # + reg


def test_em_refuses_what_defines_no_mixture():
    x = _draws(100, 0)
    fit_normal_mixture(x[:12], 2)  # 2 d k = 12 draws: enough
    with pytest.raises(ValueError, match="too few"):
        fit_normal_mixture(x[:11], 2)
    with pytest.raises(ValueError, match="whole number"):
        fit_normal_mixture(x, 0)
    with pytest.raises(ValueError, match="finite"):
        fit_normal_mixture(np.full((100, 3), np.nan), 2)


def test_a_component_left_with_too_few_draws_is_dropped():
    # 5 components asked of one tight cluster and 20 far draws: the far ones cannot hold
    # 2 d = 6 draws' worth each for long, and every draw still ends in some component
    rng = np.random.default_rng(5)
    x = np.vstack([rng.normal(0.0, 1.0, size=(400, 3)), rng.normal(40.0, 1.0, size=(20, 3))])
    w, m, c = fit_normal_mixture(x, 5, seed=0)
    assert 1 <= len(w) <= 5 and np.all(np.isfinite(m)) and np.all(np.isfinite(c))
    assert w.sum() == pytest.approx(1.0)
    assert np.all(np.linalg.eigvalsh(c) > 0)
