import numpy as np
import pytest

from bayes_inerter.records import fit_accuracy, lowpass


def test_phi_definition():
    a_m = np.array([1.0, -1.0, 1.0, -1.0])
    assert fit_accuracy(a_m, a_m) == 1.0
    assert fit_accuracy(np.zeros(4), a_m) == pytest.approx(0.0)  # predicting the mean
    assert fit_accuracy(-a_m, a_m) == pytest.approx(-1.0)
    both = fit_accuracy(np.stack([a_m, np.zeros(4)]), a_m)
    np.testing.assert_allclose(both, [1.0, 0.0])
    with pytest.raises(ValueError, match="constant"):
        fit_accuracy(a_m, np.ones(4))


def test_lowpass_is_zero_phase_and_removes_high_frequencies():
    fs = 1000.0
    t = np.arange(20000) / fs
    slow = np.sin(2 * np.pi * 1.0 * t)
    fast = 0.5 * np.sin(2 * np.pi * 170.0 * t)
    y = lowpass(slow + fast, fs)
    mid = slice(2000, -2000)
    np.testing.assert_allclose(y[mid], slow[mid], atol=1e-3)  # no lag, no 170 Hz


def test_lowpass_cutoff_checked():
    with pytest.raises(ValueError, match="cut-off"):
        lowpass(np.zeros(100), 1000.0, cutoff=600.0)


@pytest.mark.parametrize("n, cutoff, order", [(10001, 30.0, 4), (200, 5.0, 2), (15, 30.0, 4)])
def test_lowpass_equals_scipy_sosfiltfilt(n, cutoff, order):
    """The compiled 1-D path gives scipy's numbers (15 samples: too short for the
    padding, scipy's own path and its error)."""
    from scipy import signal

    x = np.cumsum(np.random.default_rng(n).standard_normal(n))
    sos = signal.butter(order, cutoff, fs=1000.0, output="sos")
    if n <= 3 * (2 * len(sos) + 1):
        with pytest.raises(ValueError):
            lowpass(x, 1000.0, cutoff, order)
        return
    ref = signal.sosfiltfilt(sos, x)
    np.testing.assert_allclose(lowpass(x, 1000.0, cutoff, order), ref, rtol=0, atol=1e-12 * np.max(np.abs(ref)))
    two = lowpass(np.stack([x, -x]), 1000.0, cutoff, order)
    np.testing.assert_allclose(two[1], -ref, rtol=0, atol=1e-12 * np.max(np.abs(ref)))
