"""The harmonic likelihood (``inference.posterior.harmonic``): amplitudes, noise, transfer, density."""

import math

import numpy as np
import pytest
from scipy import stats

from bayes_inerter.inference.posterior.harmonic import (harmonic_data, harmonic_loglik, harmonic_variance, linear_transfer,
                                             whole_sample_periods)
from bayes_inerter.network.compile import chain_state_space
from bayes_inerter.records.record import Record

FS, FREQ = 1000.0, 1.0


def _periodic_record(amps_a, amps_f, *, noise_a=0.0, noise_f=0.0, seconds=10.0, ramp=2.0, seed=0, freq=FREQ):
    """A record whose channels are sums of the drive's harmonics (complex amplitudes
    X_k: x = Re sum X_k exp(i k w t)) with a ramp-in and white noise."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(seconds * FS) + 1) / FS
    env = np.clip(t / ramp, 0, 1)
    w = 2 * math.pi * freq

    def signal(amps):
        return env * sum(np.real(a * np.exp(1j * (k + 1) * w * t)) for k, a in enumerate(amps))

    accel = signal(amps_a) + noise_a * rng.standard_normal(len(t))
    force = signal(amps_f) + noise_f * rng.standard_normal(len(t))
    disp = -signal(amps_a[:1]) / w**2
    return Record(t, force, accel, disp=disp, metadata={"drive_frequency_hz": freq})


def test_amplitudes_of_a_periodic_record_are_recovered():
    amps_a = [0.4 - 0.1j, 0.0, 0.02 + 0.01j, 0.0, 0.005j]
    amps_f = [1500.0 + 200j, 0.0, 300.0, 0.0, -40j]
    data = harmonic_data(_periodic_record(amps_a, amps_f), FREQ, cutoff=30.0)
    assert data.harmonics == 30
    assert data.periods >= 5
    np.testing.assert_allclose(data.accel[:5], amps_a, atol=1e-9)
    np.testing.assert_allclose(data.force[:5], amps_f, atol=1e-6)
    assert np.all(data.var_accel < 1e-18)


def test_whole_sample_periods_are_the_fewest_periods_of_whole_samples():
    assert whole_sample_periods(1000.0, 1.0) == 1
    assert whole_sample_periods(1000.0, 1.5) == 3  # 666.67 samples a period, 2,000 in three
    assert whole_sample_periods(1024.0, 1.5) == 3
    assert whole_sample_periods(1000.0, 0.7) == 7
    assert whole_sample_periods(1000.0, 0.7, max_periods=6) is None
    assert whole_sample_periods(1000.0, math.pi) is None


def test_means_over_a_whole_sample_span_do_not_leak_what_lies_above_the_basis():
    """At 1.5 Hz and 1 kHz a period is 666.67 samples. Harmonics far above the cut-off's
    basis (a square wave's, up to 300 Hz) leak into a period's window that is not a whole
    period; over three periods, 2,000 samples, they are the span's DFT bins and do not."""
    freq = 1.5
    amps_a = [0.4 - 0.1j] + [0.0] * 199
    for k in range(1, 200, 2):  # odd harmonics 1/k, to 300 Hz
        amps_a[k - 1] += 0.05 / k
    rec = _periodic_record(amps_a, [1500.0], freq=freq)
    data = harmonic_data(rec, freq, cutoff=30.0)
    first, n, m = data.span
    assert n == 2000 * m // 3 and m % 3 == 0 and m == data.periods
    np.testing.assert_allclose(data.accel, amps_a[:20], atol=1e-12)
    # the same harmonics from each period's own window, averaged: the leak the span removes
    per_period = data.amplitudes(rec.accel).mean(axis=0)
    assert np.max(np.abs(per_period - amps_a[:20])) > 1e-5
    # a record whose periods are whole numbers of samples keeps its periods' means
    assert harmonic_data(_periodic_record(amps_a[:30], [1500.0]), FREQ, cutoff=30.0).span is None


def test_period_scatter_measures_white_noise():
    """A white noise of sd s gives each period's complex amplitude E|X|^2 = 4 s^2 / n
    (cosine and sine coefficients each of variance 2 s^2 / n over n samples)."""
    s = 0.01
    rec = _periodic_record([0.4], [1500.0], noise_a=s, noise_f=0.0, seconds=40.0)
    data = harmonic_data(rec, FREQ, cutoff=30.0)
    n = data.index.shape[1]
    assert np.median(data.var_accel) == pytest.approx(4 * s * s / n, rel=0.2)
    assert np.all(data.var_force < 1e-12)


def test_too_few_periods_are_refused():
    rec = _periodic_record([0.4], [1500.0], seconds=4.0, ramp=1.0)
    with pytest.raises(ValueError, match="steady drive periods"):
        harmonic_data(rec, FREQ, cutoff=30.0)


def test_transfer_of_one_mass_and_of_two_masses_on_a_spring():
    m1, m2, k = 3.0, 5.0, 2e4
    A, B = chain_state_space(np.array([m1]), np.zeros(0), np.zeros(0))
    np.testing.assert_allclose(linear_transfer(A, B, np.array([1.0, 10.0])), 1 / m1)
    A, B = chain_state_space(np.array([m1, m2]), np.zeros(1), np.array([k]))
    w = np.array([2.0, 30.0, 200.0])
    # driven mass m1 joined to m2 by k: a1/F = (k - m2 w^2) / (m1 (k - m2 w^2) + m2 k)
    expected = (k - m2 * w**2) / (m1 * (k - m2 * w**2) + m2 * k)
    np.testing.assert_allclose(linear_transfer(A, B, w), expected, rtol=1e-10)


def test_loglik_is_the_complex_normal_density_with_both_noises():
    rec = _periodic_record([0.4, 0.0, 0.02], [1500.0, 0.0, 300.0], noise_a=0.01, noise_f=2.0, seed=3)
    data = harmonic_data(rec, FREQ, cutoff=30.0)
    rng = np.random.default_rng(1)
    transfer = (1 / 3000.0) * np.exp(1j * rng.uniform(-0.1, 0.1, data.harmonics))
    sim = rec.accel * 1.01
    tau, alpha, gain = 2e-4, 0.7, 1.003
    V = harmonic_variance(data, transfer, tau, alpha, gain)
    G = gain * transfer
    k = np.arange(1, data.harmonics + 1)
    by_hand_V = (data.var_accel + np.abs(G) ** 2 * data.var_force - 2 * np.real(np.conj(G) * data.cov)) / data.periods
    np.testing.assert_allclose(V, by_hand_V + tau**2 * k ** (-2 * alpha))
    r = data.accel - gain * data.mean_amplitudes(sim)
    # a complex normal of variance V: real and imaginary parts independent, each V / 2
    expected = sum(stats.norm(0, math.sqrt(v / 2)).logpdf(z.real) + stats.norm(0, math.sqrt(v / 2)).logpdf(z.imag)
                   for z, v in zip(r, V))
    assert harmonic_loglik(data, sim, transfer, tau, alpha, gain) == pytest.approx(expected, rel=1e-10)
    terms = harmonic_loglik(data, sim, transfer, tau, alpha, gain, pointwise=True)
    assert terms.shape == (data.harmonics,)
    assert terms.sum() == pytest.approx(expected, rel=1e-10)


@pytest.fixture(scope="module")
def harmonic_model():
    from bayes_inerter import paper_parameters
    from bayes_inerter.inference import PosteriorModel
    from bayes_inerter.inference.posterior.likelihood import LikelihoodSettings
    from bayes_inerter.records import generate_record

    rec = generate_record(paper_parameters("A3"), 1.0, rng=0, setting_name="A3")
    return PosteriorModel(rec, likelihood=LikelihoodSettings(residual="harmonic"))


def test_model_samples_the_discrepancy_and_the_gain(harmonic_model):
    pm = harmonic_model
    assert pm.names[pm.n_phys:] == ["tau", "alpha", "gain"]
    assert "zeta_B" in pm.names and "c_B" in pm.derived_names


def test_model_log_prob_is_prior_plus_harmonic_terms_and_peaks_near_the_truth(harmonic_model):
    import dataclasses

    from bayes_inerter import paper_parameters

    pm = harmonic_model
    p = paper_parameters("A3")
    p = dataclasses.replace(p, c_B=2 * 0.02 * math.sqrt(p.k_B * pm.m_B))  # inside the modal prior
    theta = pm.to_theta(p, hyper={"tau": 1e-5})
    lp, phi = pm.log_prob(theta)
    prior, terms, sim_lp = pm.evaluate(theta)
    assert lp == pytest.approx(prior + terms.sum(), rel=1e-12)
    assert 0.9 < phi <= 1.0
    assert sim_lp.shape == pm.record.time.shape
    for step in (-0.01, 0.01):  # b 1 % off either way
        off = theta.copy()
        off[pm.names.index("b")] += step
        assert pm.log_prob(off)[0] < lp - 10


def test_settings_refuse_unknown_values():
    from bayes_inerter.inference.posterior.likelihood import LikelihoodSettings

    with pytest.raises(ValueError, match="residual"):
        LikelihoodSettings(residual="spectral")
    with pytest.raises(ValueError, match="gain_sd"):
        LikelihoodSettings(gain_sd=-0.1)
    assert LikelihoodSettings(residual="harmonic", gain_sd=0).hyper_names == ("tau", "alpha")
    # the motion-in discrepancy is white unless its decay is asked for
    # and samples the channels' delay unless told the channels are simultaneous
    assert LikelihoodSettings(residual="motion").hyper_names == ("tau", "gain", "delay")
    assert LikelihoodSettings(residual="motion", decay=True, delay_sd=0).hyper_names == ("tau", "alpha", "gain")


def test_the_command_lines_likelihoods_are_the_librarys():
    from bayes_inerter.cli import DEFAULT_RESIDUAL, FIT_RESIDUALS
    from bayes_inerter.inference.posterior.likelihood import RESIDUALS, LikelihoodSettings

    assert FIT_RESIDUALS == RESIDUALS
    assert DEFAULT_RESIDUAL == LikelihoodSettings().residual


def test_at_times_sums_the_harmonics_back_to_a_signal():
    from bayes_inerter.inference.posterior.harmonic import at_times

    omega = 2 * np.pi * np.array([1.0, 3.0])
    t = np.array([0.0, 0.25, 1 / 12])
    X = np.array([2.0, -0.5j])  # 2 cos(w t) + 0.5 sin(3 w t)
    expected = 2 * np.cos(omega[0] * t) + 0.5 * np.sin(omega[1] * t)
    np.testing.assert_allclose(at_times(X, omega, t), expected, atol=1e-12)
