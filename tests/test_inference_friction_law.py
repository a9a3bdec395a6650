"""The friction law's marginalised shape (``inference.friction_law``)."""

import math

import numpy as np

from bayes_inerter.inference.friction_law import WIDTHS, law_basis


def test_the_laws_deviations_are_in_phase_with_a_sinusoidal_velocity_never_with_the_acceleration():
    """For v = V cos(w t) every function of v is even in t: its harmonics are real (in
    phase with the velocity), so none can stand in for the inertial force b a(t), a sine;
    an odd function of v also has only odd harmonics."""
    n, K = 4098, 20  # no sample at a reversal itself, where sgn(0) breaks the symmetry
    t = np.arange(n) / n
    v = 0.03 * np.cos(2 * math.pi * t)
    U = law_basis(v, np.sign(v), K)
    assert U.shape == (2 * K, len(WIDTHS))
    real, imag = U[:K], U[K:]
    scale = np.abs(real).max()
    assert scale > 0.1
    np.testing.assert_allclose(imag, 0.0, atol=1e-12 * scale)
    np.testing.assert_allclose(real[1::2], 0.0, atol=1e-12 * scale)  # harmonics 2, 4, ...


def test_the_widest_deviation_is_nearly_the_coulomb_square_wave_and_the_narrowest_lives_at_reversals():
    n, K = 8190, 30
    t = np.arange(n) / n
    v = np.cos(2 * math.pi * t)
    U = law_basis(v, np.sign(v), K)
    square = 4 / math.pi  # the fundamental of sgn(cos)
    # exp(-|v| / 0.03): a pulse at each reversal, far weaker at the fundamental than the square wave
    assert abs(U[0, 0]) < 0.2 * square
    assert abs(U[0, -1]) > 0.3 * square
    # and its harmonics fall slowly: a narrow pulse spreads over many harmonics
    assert abs(U[K - 2, 0]) > 0.5 * abs(U[0, 0])


def test_a_record_without_motion_has_no_deviations():
    assert law_basis(np.zeros(64), np.ones(64), 5).shape == (10, 0)
