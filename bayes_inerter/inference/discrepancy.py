"""Model discrepancy: how far b may move for a misfit as large as the one the record shows.

A fitted model that is not the device leaves a residual that repeats every drive cycle:
harmonics of the drive frequency that no parameter reproduces. Part of such a
discrepancy may also lie along b's own signature (the change of the simulated
acceleration with b, mostly at the fundamental), where the fit cannot see it: it moves
b instead. Following Kennedy and O'Hagan, the discrepancy is given a prior, here its
coefficients at the drive's harmonics, independent normal with a common variance
``tau^2``; the share of it along b's signature is uncertainty in b that no amount of
data removes:

    var(log b) += tau^2 / ||d||^2

with ``d`` the harmonic coefficients of b's signature d a / d log b (the generalised
least-squares projection of the discrepancy onto it, the other parameters held, which
errs on the wide side).

``tau^2`` is learnt from the record: the mean squared coefficient of the residual at
harmonics 2 to ``harmonics`` + 1 of the drive frequency (within the likelihood's
low-pass), less what the residual's non-periodic part (noise) puts there. The
fundamental is left out: the fit's parameters absorb most of the misfit there, which
is the very bias this term is for. **Assumption** (named ``HARMONICS``, default 5): the
discrepancy at the fundamental is as large as at the next five harmonics on average.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["Discrepancy", "harmonic_discrepancy", "HARMONICS", "B_STEP"]

#: Harmonics above the fundamental whose residual sets the discrepancy's size.
HARMONICS = 5
#: Step in log b of the central difference that gives b's signature.
B_STEP = 1e-3


@dataclass(frozen=True)
class Discrepancy:
    """``tau``: the discrepancy's rms coefficient, m/s^2; ``sd_log_b``: the sd it adds to
    log b; ``harmonics``: the harmonics it was learnt from."""

    tau: float
    sd_log_b: float
    harmonics: tuple[int, ...]


def _design(t: np.ndarray, freq: float, ks) -> np.ndarray:
    w = 2.0 * math.pi * freq * t
    return np.column_stack([f(k * w) for k in ks for f in (np.cos, np.sin)])


def harmonic_discrepancy(model, theta, *, harmonics: int = HARMONICS, b_name: str = "b") -> Discrepancy:
    """The discrepancy of ``model`` (a single-record posterior) at ``theta`` (see module
    docstring)."""
    if not (isinstance(harmonics, int) and harmonics >= 1):
        raise ValueError(f"harmonics must be a whole number of at least 1, got {harmonics!r}")
    rec = model.record
    freq = rec.drive_frequency
    if not freq or not math.isfinite(freq):
        raise ValueError("the record's drive frequency is unknown: the discrepancy needs it")
    w = model.window
    t = rec.time[w] - rec.time[w[0]]
    theta = np.asarray(theta, dtype=float)
    sim = model.simulate_lp(theta)[w]
    r = model.measured_lp[w] - sim
    top = int(model.likelihood.cutoff // freq)
    ks = [k for k in range(2, harmonics + 2) if k <= top]
    if not ks:
        return Discrepancy(0.0, 0.0, ())
    phi = _design(t, freq, ks)
    coef, *_ = np.linalg.lstsq(phi, r, rcond=None)
    rest = r - phi @ coef
    # what noise alone would put into each coefficient: its variance through the fit
    noise = float(np.var(rest)) * float(np.mean(np.diag(np.linalg.inv(phi.T @ phi))))
    tau2 = max(0.0, float(np.mean(coef ** 2)) - noise)
    i = model.names.index(b_name)
    up, down = theta.copy(), theta.copy()
    log_b = model.all_priors[b_name].log_scale
    step = B_STEP if log_b else B_STEP * float(theta[i])
    up[i] += step
    down[i] -= step
    signature = (model.simulate_lp(up)[w] - model.simulate_lp(down)[w]) / (2 * step)
    if not log_b:  # d a / d b: to d a / d log b
        signature = signature * float(theta[i])
    d, *_ = np.linalg.lstsq(_design(t, freq, [1] + ks), signature, rcond=None)
    sd = math.sqrt(tau2 / float(d @ d)) if float(d @ d) > 0 else 0.0
    return Discrepancy(math.sqrt(tau2), sd, tuple(ks))
