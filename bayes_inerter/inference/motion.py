"""Motion in, force out: the harmonic likelihood of the force given the measured motion.

A displacement-controlled test prescribes the motion of terminal 1; the device answers
with a force. Over the record's whole steady drive periods (``harmonic.harmonic_data``)
the measured acceleration's harmonics A_k give the plate's periodic motion,
V_k = A_k / (i k omega), and the two-port model (MODEL.md section 2) then gives the force
at terminal 1 **without a simulation**, harmonic by harmonic:

    z_B = c_B + k_B / (i w),  z_n = c_n + k_n / (i w),  y = i w b + c_f2
    Z_f = z_n y / (z_n + y),  g = z_n / (z_n + y)           (nut in series with the rotation)
    V_s = (z_B V - g F_2) / (z_B + i w m_s + Z_f)            (the screw's translation)
    F   = (i w m_B + c_f1) V + f1_0 S + z_B (V - V_s)

S_k are the harmonics of sgn(v_B(t)), the Coulomb forces' square wave, and
F_2 = f2_0 S the rotation's Coulomb force. Two **assumptions** make this algebra exact for
the model's steady state:

- the Coulomb forces switch when the plate's velocity changes sign, read from the
  measured motion reconstructed up to ``sign_band`` (default 100 Hz: the switches' timing
  sets the friction's phase, and a band of 30 Hz moved the apparent mass at 1 Hz by
  0.5 % on the generator's noise-free records, 100 Hz by 0.03 %);
- the rotation reverses with the plate (the nut's damper, c_n, couples them within
  b / c_n, about 2 ms; a stuck rotation is not modelled).

The plate's mode and its chatter, and every simulation, leave the likelihood; what the
data cannot pin (the bearing) stays with its prior. The residual F_k - F^_k(theta) is
complex normal with

    V_k = (s2_F,k + |Y_k / g|^2 s2_A,k - 2 Re(Y_k c_k / g)) / P  +  tau^2 k^(-2 alpha)

Y_k = dF^_k / dA_k the model's linear transfer from the measured acceleration to the
predicted force (its noise enters the prediction: errors in both signals), g the
acceleration channel's gain relative to the force's, c_k = E[(A - A_k) conj(F - F_k)],
and tau (N) and alpha the model's discrepancy, sampled. The fit accuracy reported with
each evaluation is the force's at the harmonics, 1 - |F - F^| / |F| over k = 1..K
(Parseval's: the periodic part's phi, not the paper's phi of the acceleration).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from ..models import FIELDS
from ..records.record import Record
from .harmonic import HarmonicData, harmonic_data

__all__ = ["MotionData", "motion_data", "predicted_force", "motion_variance", "motion_loglik", "fundamental_misfit", "SIGN_BAND",
           "SIGN_GRID", "ORDER", "FUNDAMENTAL_MAX"]

#: **Assumption** of the reporting: b is called identified only where the fit reproduces
#: the fundamental's force in phase with the acceleration (the inertial force, which b
#: makes) to within this share. Where it does not, the posterior's b is set by the
#: harmonics above, whose inertial content a richer device need not share with the
#: model (its nut's backlash keeps the plate's reversal jerks from the flywheel).
FUNDAMENTAL_MAX = 0.1

#: **Assumption**: the band of the measured motion whose sign times the Coulomb forces, Hz.
SIGN_BAND = 100.0
#: Points per period on which the sign's square wave is formed before its harmonics are taken.
SIGN_GRID = 8192


@dataclass(frozen=True)
class MotionData:
    """What the motion-in likelihood needs of a record: the harmonic data (force and
    acceleration, their scatter), the plate's velocity harmonics and the sign's."""

    harmonic: HarmonicData
    velocity: np.ndarray  # (K,) complex, m/s: A_k / (i k omega)
    sign: np.ndarray  # (K,) complex: harmonics of sgn(v_B(t))
    omega: np.ndarray  # (K,) rad/s

    @property
    def harmonics(self) -> int:
        return self.harmonic.harmonics


def _sign_harmonics(record: Record, freq: float, K: int, band: float, pool: int, settle: int) -> np.ndarray:
    fine = harmonic_data(record, freq, cutoff=min(band, 0.45 * record.fs), pool=pool, settle=settle)
    V = fine.accel / (1j * fine.omega)
    t = np.arange(SIGN_GRID) / (SIGN_GRID * freq)
    v = np.real(np.exp(1j * np.outer(t, fine.omega)) @ V)
    S = np.fft.rfft(np.sign(v)) / SIGN_GRID * 2.0
    return S[1: K + 1]


def motion_data(record: Record, freq: float, *, cutoff: float, pool: int = 2, settle: int = 1,
                sign_band: float = SIGN_BAND) -> MotionData:
    """:class:`MotionData` of ``record`` driven at ``freq`` Hz (see module docstring)."""
    data = harmonic_data(record, freq, cutoff=cutoff, pool=pool, settle=settle)
    sign = _sign_harmonics(record, freq, data.harmonics, max(sign_band, cutoff), pool, settle)
    return MotionData(data, data.accel / (1j * data.omega), sign, data.omega)


#: The physical parameters in the order the compiled kernels unpack them: ``models.FIELDS``'s.
ORDER = ("b", "m_s", "m_B", "c_n", "k_n", "c_B", "k_B", "f1_0", "c_f1", "f2_0", "c_f2")
if ORDER != FIELDS:  # the model hands the kernels its field vector as it is
    raise ImportError("motion.ORDER must be models.FIELDS")


@njit(cache=True)
def _predicted(x, gain, omega, velocity, sign):
    """(F^_k, Y_k) of the module docstring for the parameters ``x`` in :data:`ORDER`."""
    b, m_s, m_B, c_n, k_n, c_B, k_B, f1_0, c_f1, f2_0, c_f2 = x[0], x[1], x[2], x[3], x[4], x[5], x[6], x[7], \
        x[8], x[9], x[10]
    K = omega.shape[0]
    F = np.empty(K, dtype=np.complex128)
    Y = np.empty(K, dtype=np.complex128)
    for k in range(K):
        iw = 1j * omega[k]
        V = velocity[k] / gain
        z_B = c_B + k_B / iw
        z_n = c_n + k_n / iw
        y = iw * b + c_f2
        Z_f = z_n * y / (z_n + y)
        g = z_n / (z_n + y)
        den = z_B + iw * m_s + Z_f
        V_s = (z_B * V - g * f2_0 * sign[k]) / den
        F[k] = (iw * m_B + c_f1) * V + f1_0 * sign[k] + z_B * (V - V_s)
        Y[k] = (iw * m_B + c_f1 + z_B * (1.0 - z_B / den)) / iw / gain
    return F, Y


@njit(cache=True)
def _variance(Y, tau, alpha, var_force, var_accel, cov, periods):
    """V_k of the module docstring, from the transfer Y_k."""
    K = Y.shape[0]
    V = np.empty(K)
    for k in range(K):
        noise = (var_force[k] + (Y[k].real ** 2 + Y[k].imag ** 2) * var_accel[k]
                 - 2.0 * (Y[k] * cov[k]).real) / periods
        V[k] = max(noise, 0.0) + tau * tau * (k + 1.0) ** (-2.0 * alpha)
    return V


@njit(cache=True)
def _terms(x, tau, alpha, gain, omega, velocity, sign, force, var_force, var_accel, cov, periods):
    """Each harmonic's log-likelihood term and the squared residuals' and the force's sums."""
    F, Y = _predicted(x, gain, omega, velocity, sign)
    V_all = _variance(Y, tau, alpha, var_force, var_accel, cov, periods)
    K = omega.shape[0]
    terms = np.empty(K)
    sq_sum = 0.0
    f_sum = 0.0
    for k in range(K):
        V = V_all[k]
        r = force[k] - F[k]
        sq = r.real ** 2 + r.imag ** 2
        terms[k] = -np.log(np.pi * V) - sq / V if V > 0 else -np.inf
        sq_sum += sq
        f_sum += force[k].real ** 2 + force[k].imag ** 2
    return terms, sq_sum, f_sum


def _vector(p) -> np.ndarray:
    return p if isinstance(p, np.ndarray) else np.array([float(p[n]) for n in ORDER])


def predicted_force(data: MotionData, p, gain: float = 1.0):
    """(F^_k, Y_k): the model's force at the harmonics for the physical parameters ``p``
    (by name, or a vector in :data:`ORDER`), and its transfer from the measured
    acceleration, dF^_k / dA_k."""
    return _predicted(_vector(p), float(gain), data.omega, data.velocity, data.sign)


def motion_variance(data: MotionData, p, tau: float, alpha: float, gain: float = 1.0):
    """(V_k, Y_k): each harmonic's residual variance (noise of both channels and the
    discrepancy, N^2) and the model's transfer from the measured acceleration to the force
    (``p`` as for :func:`predicted_force`)."""
    h = data.harmonic
    _, Y = predicted_force(data, p, gain)
    return _variance(Y, float(tau), float(alpha), h.var_force, h.var_accel, h.cov, float(h.periods)), Y


def motion_loglik(data: MotionData, p, tau: float, alpha: float, gain: float = 1.0, *,
                  pointwise: bool = False):
    """(log L, phi of the force at the harmonics) of the module docstring; with
    ``pointwise``, each harmonic's term (an array) instead of log L. ``p`` as for
    :func:`predicted_force`."""
    h = data.harmonic
    terms, sq, norm = _terms(_vector(p), float(tau), float(alpha), float(gain), data.omega, data.velocity, data.sign,
                             h.force, h.var_force, h.var_accel, h.cov, float(h.periods))
    phi = 1.0 - math.sqrt(sq / norm)
    return (terms if pointwise else float(terms.sum())), phi


def fundamental_misfit(data: MotionData, p, gain: float = 1.0) -> float:
    """The fit's residual at the drive's fundamental in phase with the model's inertial
    force there, as a share of that force: |Re(r_1 / (Y_1 A_1 / g))| (see
    :data:`FUNDAMENTAL_MAX`)."""
    F, Y = predicted_force(data, p, gain)
    inertial = Y[0] * data.harmonic.accel[0]  # Y already holds the gain
    return float(abs(((data.harmonic.force[0] - F[0]) / inertial).real))
