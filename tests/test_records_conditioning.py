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
