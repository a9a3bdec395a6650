"""The friction law's marginalised shape (``inference.posterior.friction_law``)."""

import math

import numpy as np

from bayes_inerter.inference.posterior.friction_law import WIDTHS, beyond, law_basis


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


def test_the_deviations_beyond_the_model_s_law_are_orthogonal_to_its_coulomb_and_viscous_harmonics():
    """``beyond`` leaves only what f1_0 sgn(v) + c_f1 v cannot make: every column is
    orthogonal to the sign's and the velocity's harmonics, and what was already
    orthogonal to them is left as it was."""
    n, K = 8190, 30
    t = np.arange(n) / n
    v = 0.02 * np.cos(2 * math.pi * t) + 0.004 * np.sin(6 * math.pi * t)
    s = np.sign(v)
    S = (np.fft.rfft(s) / n * 2)[1: K + 1]
    V = (np.fft.rfft(v) / n * 2)[1: K + 1]
    U = law_basis(v, s, K)
    W = beyond(U, S, V)
    A = np.column_stack([np.concatenate([h.real, h.imag]) for h in (S, V)])
    assert W.shape == U.shape
    np.testing.assert_allclose(A.T @ W, 0.0, atol=1e-12 * np.abs(U).max())
    assert np.linalg.norm(W[:, -1]) < 0.5 * np.linalg.norm(U[:, -1])  # the widest was mostly Coulomb's
    Q, _ = np.linalg.qr(A)
    free = U - Q @ (Q.T @ U)
    np.testing.assert_allclose(beyond(free, S, V), free, atol=1e-12)
    assert beyond(np.zeros((2 * K, 0)), S, V).shape == (2 * K, 0)
