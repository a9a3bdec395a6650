"""The harmonic likelihood: errors in both signals, the model's discrepancy sampled.

A record driven by a steady sinusoid is, after its start-up, periodic. Over its whole
steady drive periods p = 1..P (``records.drive.steady_periods``) each period's force and
acceleration are projected on the drive's harmonics k = 1..K up to ``cutoff``
(least squares on a basis of harmonics up to twice the cut-off, so that what lies above
the cut-off does not leak into the kept ones): complex amplitudes F_pk and A_pk, with
x(t) ~ Re(sum_k X_k exp(i k omega t)). Their means over the periods, F_k and A_k, carry
the signal; their scatter across the periods carries the noise, whatever its colour
(the sample maximum-likelihood idea of Schoukens, Pintelon, Vandersteen and Guillaume,
Automatica 33, 1997; Pintelon and Schoukens, *System Identification: A Frequency Domain
Approach*, 2012):

    s2_A,k, s2_F,k, c_k = sample variances of A_pk and F_pk and their covariance
                          E[(A - A_k) conj(F - F_k)], each averaged over the harmonics
                          within ``pool`` of k (**assumption**: the noise's spectrum is
                          smooth across neighbouring harmonics; with 3 periods a single
                          harmonic's variance has only 4 degrees of freedom).

The simulation is driven by the measured force over the whole record and projected the
same way over the same periods: S_k(theta). The residual A_k - g S_k(theta) (g: the
acceleration channel's gain relative to the force channel's, sampled) is complex normal
with variance

    V_k = (s2_A,k + |g G_k|^2 s2_F,k - 2 Re(conj(g G_k) c_k)) / P  +  tau^2 k^(-2 alpha)

- the first term is the noise of both channels: the force's noise reaches the predicted
  acceleration through the model's own transfer G_k from force to acceleration at
  k omega (the network linearised, its Coulomb forces left out: the transfer of a
  perturbation while it slides), the errors-in-variables term that a time-domain
  likelihood taking the force as exact leaves out;
- the second is the model's discrepancy, what no parameter of the model reproduces,
  with its scale tau (m/s^2) and its spectral decay alpha **sampled** with the physical
  parameters, so every interval widens by what the chain finds, not by a rule applied
  afterwards (Kennedy and O'Hagan 2001; in the frequency domain as gravitational-wave
  inference marginalises waveform error).

    log L = sum_k [ -log(pi V_k) - |A_k - g S_k|^2 / V_k ]

Only whole steady periods count: the start-up and the ramp feed the simulation but not
the comparison.

Where a period is not a whole number of samples (1.5 Hz at 1 kHz: 666.67), a period's
window is not a whole period and what lies above the basis leaks into its amplitudes;
then the means F_k and A_k are taken over the longest span of whole periods that is a
whole number of samples (q periods, the fewest with q fs / f whole, at most
:data:`MAX_SPAN_PERIODS`; 3 at 1.5 Hz and 1 kHz), where the harmonics are exactly the
span's DFT bins and nothing leaks. The scatter stays per period (a leak shared by the
periods does not enter it). On the generator's noise-free B2 record at 1.5 Hz the
per-period means put 0.3 to 0.5 N of even harmonics into the force predicted at the truth
(0.02 N measured), which the discrepancy's tau took up as 0.23 N; with the span's, tau
fell to its floor (docs/inference.md, "Whole-sample spans"). The fit accuracy phi is still the paper's, on the low-passed time
signals in the window (``model.PosteriorModel.phi``).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ...records.drive import steady_periods
from ...records.record import Record

__all__ = ["HarmonicData", "harmonic_data", "linear_transfer", "harmonic_variance", "harmonic_loglik", "at_times",
           "whole_sample_periods", "MAX_SPAN_PERIODS"]

#: The most drive periods a whole-sample span may need (:func:`whole_sample_periods`);
#: a record whose fs / f needs more keeps the means over its periods' own windows, and
#: 1 gives every record those (the likelihood before the spans).
MAX_SPAN_PERIODS = 10


def whole_sample_periods(fs: float, freq: float, max_periods: int = MAX_SPAN_PERIODS) -> int | None:
    """The fewest drive periods that are a whole number of samples (q with q fs / freq
    whole to 1e-9 of a sample), at most ``max_periods``; None if there is none."""
    per = fs / freq
    for q in range(1, max_periods + 1):
        if abs(q * per - round(q * per)) < 1e-9 * max(1.0, q * per):
            return q
    return None


@dataclass(frozen=True)
class HarmonicData:
    """What the harmonic likelihood compares with, made once per record.

    Attributes
    ----------
    index : (P, n) sample indices of each steady period (n samples each).
    projector : (K, n) complex; ``projector @ x[index[p]]`` is period p's amplitudes at
        harmonics 1..K in the period's own time (from its first sample).
    rotation : (P, K) complex; those times ``rotation[p]`` are the amplitudes in the
        record's time, exp(-i k omega t_p) with t_p the period's first sample's time.
    omega : (K,) rad/s, the harmonics' angular frequencies.
    accel, force : (K,) complex, the measured means over the periods.
    var_accel, var_force : (K,) the pooled sample variances of one period's amplitude.
    cov : (K,) complex, the pooled sample covariance E[(A - A_k) conj(F - F_k)].
    span : None where a period is a whole number of samples; else (first sample, samples,
        periods) of the whole-sample span the means are taken over.
    periods : P, the periods the means are taken over.
    """

    index: np.ndarray
    projector: np.ndarray
    rotation: np.ndarray
    omega: np.ndarray
    accel: np.ndarray
    force: np.ndarray
    var_accel: np.ndarray
    var_force: np.ndarray
    cov: np.ndarray
    span: tuple | None = None

    @property
    def periods(self) -> int:
        return int(self.index.shape[0]) if self.span is None else int(self.span[2])

    @property
    def harmonics(self) -> int:
        return int(self.omega.shape[0])

    def amplitudes(self, x: np.ndarray) -> np.ndarray:
        """(P, K) complex amplitudes of ``x`` (a whole record's samples) in each period."""
        return (np.asarray(x, dtype=float)[self.index] @ self.projector.T) * self.rotation

    def mean_amplitudes(self, x: np.ndarray) -> np.ndarray:
        """(K,) complex amplitudes of ``x`` averaged over the periods (over the
        whole-sample span where there is one)."""
        if self.span is None:
            return self.amplitudes(x).mean(axis=0)
        first, n, m = self.span
        bins = np.fft.rfft(np.asarray(x, dtype=float)[first: first + n])[m * np.arange(1, self.harmonics + 1)]
        return bins * (2.0 / n) * self.rotation[0]  # the span starts at period 0's first sample


def _pooled(x: np.ndarray, pool: int) -> np.ndarray:
    """Each entry averaged with its neighbours within ``pool`` (fewer at the ends)."""
    if pool <= 0:
        return x
    out = np.empty_like(x)
    for k in range(len(x)):
        out[k] = x[max(0, k - pool): k + pool + 1].mean()
    return out


def harmonic_data(record: Record, freq: float, *, cutoff: float, pool: int = 2, settle: int = 1,
                  min_periods: int = 3) -> HarmonicData:
    """:class:`HarmonicData` of ``record`` driven at ``freq`` Hz (see module docstring).

    ``settle``: whole periods left out after the start of the steady part (the start-up's
    transient decays there); ``min_periods``: fewer steady periods than this are refused.
    """
    fs = record.fs
    if not 0 < freq * 2 <= cutoff < fs / 2:
        raise ValueError(f"the harmonic likelihood needs a drive frequency ({freq:g} Hz) with at least two "
                         f"harmonics below the cut-off ({cutoff:g} Hz), itself below half the sampling rate")
    start, count = steady_periods(record, freq)
    start_t = record.time[0] + start / fs + settle / freq
    count -= settle
    if count < min_periods:
        raise ValueError(f"the record holds {max(count, 0)} steady drive periods after the start-up, fewer than "
                         f"the {min_periods} the harmonic likelihood needs for its noise; use a longer record or "
                         f"--residual ar1")
    n = int(math.floor(fs / freq))
    first = [int(math.ceil((start_t - record.time[0]) * fs + p * fs / freq - 1e-9)) for p in range(count)]
    if first[-1] + n > len(record.time):
        count -= 1
        first = first[:count]
    index = np.array([np.arange(s, s + n) for s in first], dtype=np.int64)
    K = int(math.floor(cutoff / freq + 1e-9))
    K_fit = max(K, min(int(math.floor(2 * cutoff / freq)), int(0.45 * n)))
    w = 2 * math.pi * freq
    ks = np.arange(1, K_fit + 1)
    # every period has the same samples in its own time: one least-squares projector,
    # turned into the record's time by each period's phase
    phase = np.outer(np.arange(n) / fs, ks) * w
    basis = np.column_stack([np.ones(n), np.cos(phase), np.sin(phase)])
    pinv = np.linalg.pinv(basis)  # rows: offset, cos 1..K_fit, sin 1..K_fit
    projector = pinv[1: K + 1] - 1j * pinv[K_fit + 1: K_fit + 1 + K]
    omega = w * np.arange(1, K + 1)
    rotation = np.exp(-1j * np.outer(record.time[index[:, 0]], omega))
    data = HarmonicData(index, projector, rotation, omega, np.zeros(K, complex), np.zeros(K, complex),
                        np.zeros(K), np.zeros(K), np.zeros(K, complex),
                        _whole_sample_span(first[0], count, fs, freq, len(record.time)))
    A = data.amplitudes(record.accel)
    F = data.amplitudes(record.force)
    dA, dF = A - A.mean(axis=0), F - F.mean(axis=0)
    dof = count - 1
    whole = data.span is None  # each period's window is whole: its means are the span's
    return dataclasses.replace(data, accel=A.mean(axis=0) if whole else data.mean_amplitudes(record.accel),
                               force=F.mean(axis=0) if whole else data.mean_amplitudes(record.force),
                               var_accel=_pooled((np.abs(dA) ** 2).sum(axis=0) / dof, pool),
                               var_force=_pooled((np.abs(dF) ** 2).sum(axis=0) / dof, pool),
                               cov=_pooled((dA * np.conj(dF)).sum(axis=0) / dof, pool))


def _whole_sample_span(first: int, count: int, fs: float, freq: float, length: int) -> tuple | None:
    """(first sample, samples, periods) of the longest span of whole periods from sample
    ``first`` that is a whole number of samples and ends inside the record's ``length``
    samples (:data:`HarmonicData.span`); None where each period is already a whole number
    of samples, or no span of at most :data:`MAX_SPAN_PERIODS` periods fits."""
    q = whole_sample_periods(fs, freq, MAX_SPAN_PERIODS)  # read at each call: 1 restores the periods' means
    if q is None or q == 1:
        return None
    m = (count // q) * q
    while m > 0 and first + round(m * fs / freq) > length:
        m -= q
    return (int(first), int(round(m * fs / freq)), m) if m > 0 else None


def at_times(X: np.ndarray, omega: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The periodic signal with harmonics ``X`` (complex amplitudes at ``omega``, rad/s) at
    the times ``t`` (s): Re sum_k X_k exp(i omega_k t)."""
    return np.real(np.exp(1j * np.outer(t, omega)) @ X)


def linear_transfer(A: np.ndarray, B: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """The driven node's acceleration per unit force at each ``omega`` (rad/s) of the
    linear state space x' = A x + B F, whose first state is that node's velocity:
    G = A[0] (i omega - A)^-1 B + B[0]."""
    M = 1j * np.asarray(omega)[:, None, None] * np.eye(A.shape[0]) - A
    x = np.linalg.solve(M, np.broadcast_to(B.astype(complex)[:, None], (len(omega), A.shape[0], 1)))
    return x[:, :, 0] @ A[0] + B[0]


def harmonic_variance(data: HarmonicData, transfer: np.ndarray, tau: float, alpha: float,
                      gain: float = 1.0) -> np.ndarray:
    """V_k of the module docstring: the variance of each harmonic's mean residual."""
    G = gain * transfer
    noise = (data.var_accel + np.abs(G) ** 2 * data.var_force - 2.0 * np.real(np.conj(G) * data.cov)) / data.periods
    k = np.arange(1, data.harmonics + 1)
    return np.maximum(noise, 0.0) + tau * tau * k ** (-2.0 * alpha)


def harmonic_loglik(data: HarmonicData, sim: np.ndarray, transfer: np.ndarray, tau: float, alpha: float,
                    gain: float = 1.0, *, pointwise: bool = False):
    """log L of the module docstring for the simulated acceleration ``sim`` (the whole
    record's samples) and the model's force-to-acceleration ``transfer`` at the
    harmonics; with ``pointwise``, each harmonic's term (an array)."""
    V = harmonic_variance(data, transfer, tau, alpha, gain)
    r = data.accel - gain * data.mean_amplitudes(sim)
    with np.errstate(divide="ignore", invalid="ignore"):
        terms = -np.log(math.pi * V) - (r.real ** 2 + r.imag ** 2) / V
    terms = np.where(V > 0, terms, -math.inf)
    return terms if pointwise else float(terms.sum())
