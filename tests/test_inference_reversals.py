"""The plate's reversals (``inference.posterior.reversals``): windows, the ramped sign, the marginal."""

import math

import numpy as np
import pytest
from scipy import stats

from bayes_inerter.inference.posterior.reversals import (DEGREES, DWELL, MIN_HALF_WIDTH, WIDEN, deviations_mean,
                                               reversal_correction, reversal_windows, switched_sign, window_basis)

N, T = 4096, 2.0


def _sine():
    t = np.arange(N) / N
    w = 2 * math.pi / T
    return 0.0314 * np.cos(w * t * T), -0.0314 * w * np.sin(w * t * T)  # v, a: reversals at T/4, 3T/4


def test_a_clean_sine_has_two_narrow_windows_at_its_reversals():
    v, a = _sine()
    windows = reversal_windows(v, a, 0.0, T)
    assert len(windows) == 2
    centres = sorted(((lo + hi) / 2) % 1 for lo, hi in windows)
    np.testing.assert_allclose(centres, [0.25, 0.75], atol=2.0 / N)
    slow = math.asin(DWELL) / (2 * math.pi)  # where |v| stays below DWELL of its peak
    for lo, hi in windows:
        assert (hi - lo) / 2 == pytest.approx(slow + MIN_HALF_WIDTH, abs=2.0 / N)


def test_noise_widens_a_window_by_its_timing_uncertainty():
    v, a = _sine()
    sigma_v = 3e-4  # past the least half-width
    (lo, hi), _ = reversal_windows(v, a, sigma_v, T)
    expected = WIDEN * sigma_v / (0.0314 * 2 * math.pi / T) / T  # sigma_v / |a|, as a share of T
    slow = math.asin(DWELL) / (2 * math.pi)
    assert (hi - lo) / 2 == pytest.approx(slow + expected, abs=2.0 / N)


def test_crossings_that_chatter_near_a_reversal_are_one_window():
    v, a = _sine()
    v = v.copy()
    i = N // 4
    v[i - 40: i + 40] = 1e-6 * np.sign(np.sin(np.arange(80)))  # a stuck plate's ripple
    windows = reversal_windows(v, a, 0.0, T)
    assert len(windows) == 2
    first = min(windows, key=lambda w: abs(((w[0] + w[1]) / 2) % 1 - 0.25))
    assert first[0] <= (i - 40) / N and first[1] >= (i + 39) / N


def test_the_sign_switches_once_at_a_windows_middle_and_is_the_sign_outside():
    v, a = _sine()
    v = v.copy()
    v[N // 4 - 30: N // 4 + 30] = 1e-6 * np.sign(np.sin(np.arange(60)))  # chatter near the reversal
    windows = [(0.2, 0.3), (0.7, 0.8)]
    s = switched_sign(v, windows)
    x = np.arange(N) / N
    outside = ~(((x >= 0.2) & (x <= 0.3)) | ((x >= 0.7) & (x <= 0.8)))
    np.testing.assert_array_equal(s[outside], np.sign(v[outside]))
    first = s[(x >= 0.2) & (x <= 0.3)]
    switches = np.flatnonzero(np.diff(first) != 0)
    assert len(switches) == 1 and first[0] == 1.0 and first[-1] == -1.0  # one switch, no chatter
    # midway between the chatter's first and last crossing, about the true reversal at T/4
    assert x[(x >= 0.2)][switches[0]] == pytest.approx(0.25, abs=3.0 / N)


def test_the_correction_is_the_marginal_gaussian_density():
    """log N(r; 0, D + U S^2 U') - log N(r; 0, D), with D each harmonic's V_k / 2 for its
    real and imaginary part and S the columns' prior sds: the Woodbury form against the
    dense density."""
    rng = np.random.default_rng(3)
    K = 12
    U = window_basis([(0.2, 0.26), (0.7, 0.77)], K)
    assert U.shape == (2 * K, 2 * DEGREES)
    V = rng.uniform(0.5, 2.0, K)
    r = rng.standard_normal(K) + 1j * rng.standard_normal(K)
    s = np.linspace(0.5, 3.0, U.shape[1])  # unequal: each column its own prior sd
    D = np.concatenate([V, V]) / 2
    x = np.concatenate([r.real, r.imag])
    dense = (stats.multivariate_normal(np.zeros(2 * K), np.diag(D) + (U * s**2) @ U.T).logpdf(x)
             - stats.multivariate_normal(np.zeros(2 * K), np.diag(D)).logpdf(x))
    assert reversal_correction(U, V, r, s) == pytest.approx(dense, rel=1e-9, abs=1e-9)
    assert reversal_correction(U, V, r, np.zeros(U.shape[1])) == 0.0
    assert reversal_correction(U[:, :0], V, r, s[:0]) == 0.0


def test_the_deviations_mean_is_the_gaussian_conditional_mean():
    """E[U beta | r] under r = U beta + e, beta ~ N(0, S^2), e ~ N(0, D): the dense
    Gaussian's conditional mean U S^2 U' (D + U S^2 U')^-1 r, as K complex harmonics."""
    rng = np.random.default_rng(4)
    K = 10
    U = window_basis([(0.1, 0.18), (0.6, 0.66)], K)
    V = rng.uniform(0.5, 2.0, K)
    r = rng.standard_normal(K) + 1j * rng.standard_normal(K)
    s = np.linspace(0.3, 2.0, U.shape[1])
    D = np.diag(np.concatenate([V, V]) / 2)
    C = (U * s**2) @ U.T
    dense = C @ np.linalg.solve(D + C, np.concatenate([r.real, r.imag]))
    got = deviations_mean(U, V, r, s)
    assert got.shape == (K,)
    assert np.concatenate([got.real, got.imag]) == pytest.approx(dense, rel=1e-9, abs=1e-12)
    assert np.all(deviations_mean(U, V, r, np.zeros(U.shape[1])) == 0)
    assert np.all(deviations_mean(U[:, :0], V, r, s[:0]) == 0)


def test_the_basis_holds_the_windows_legendre_harmonics():
    """The constant on a window [lo, hi] has the harmonics 2 int exp(-i k w t) dt / T."""
    lo, hi = 0.1, 0.15
    U = window_basis([(lo, hi)], 5, points=4000)
    k = np.arange(1, 6)
    exact = 2 * (np.exp(-2j * np.pi * k * hi) - np.exp(-2j * np.pi * k * lo)) / (-2j * np.pi * k)
    np.testing.assert_allclose(U[:5, 0] + 1j * U[5:, 0], exact, rtol=1e-6)
