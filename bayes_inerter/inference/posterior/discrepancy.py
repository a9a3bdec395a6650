"""Model discrepancy: how far b may move for a misfit as large as the one the record shows.

A fitted model that is not the device leaves a residual that repeats every drive cycle:
harmonics of the drive frequency that no parameter reproduces. Part of such a
discrepancy may also lie along b's own signature (the change of the simulated
acceleration with b, mostly at the fundamental), where the fit cannot see it: it moves
b instead. Following Kennedy and O'Hagan, the discrepancy is given a prior, here its
coefficients at the drive's harmonics, independent normal, the pair at harmonic k with
variance ``tau^2 k^(-2 decay)``; the share of it along b's signature is uncertainty in
b that no amount of data removes:

    var(log b) += sum_j g_j^2 tau^2 k_j^(-2 decay)

with ``g`` the linear response of the posterior's mean of log b to a unit coefficient
``j`` of the discrepancy (harmonic k_j, cosine or sine): ``g = C J' W H``, ``C`` the
posterior covariance of the parameters, ``J`` the simulation's derivatives in them,
``W`` the likelihood's noise precision (AR(1) whitened) and ``H`` the harmonics on the
likelihood's grid. The other parameters take up their share of the discrepancy as the
posterior would. Without ``C`` they are held and ``g = d / ||d||^2``, with ``d`` the
harmonic coefficients of b's signature d a / d log b (the least-squares projection onto
it), which errs on the wide side.

``tau^2`` is learnt from the record: the residual's coefficients at harmonics 2 to
``harmonics`` + 1 of the drive frequency (within the likelihood's low-pass) are each
normal with variance ``tau^2 k^(-2 decay) + n_j``, ``n_j`` what the residual's
non-periodic part (noise) puts into coefficient j, and ``tau^2`` is their maximum
marginal likelihood (zero when the harmonics hold no more than noise: a record of the
model itself gets next to no discrepancy). The fundamental is left out: the fit's
parameters absorb most of the misfit there, which is the very bias this term is for.

**Assumptions.**

- ``HARMONICS`` (default 5): the harmonics that set the discrepancy's size.
- ``DECAY`` (default 1): how the discrepancy's harmonics fall with their order. A
  force that jumps where the motion reverses (friction breaking away, a nut crossing its
  backlash) has Fourier coefficients that fall as 1/k, so the fundamental's share is
  larger than the harmonics above it show; ``decay=0`` takes it as large as their mean.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["Discrepancy", "harmonic_discrepancy", "HARMONICS", "DECAY", "B_STEP"]

#: Harmonics above the fundamental whose residual sets the discrepancy's size.
HARMONICS = 5
#: Exponent of the discrepancy's fall with harmonic order (1: a force with jumps).
DECAY = 1.0
#: Step in log b of the central difference that gives b's signature.
B_STEP = 1e-3


@dataclass(frozen=True)
class Discrepancy:
    """``tau``: the discrepancy's rms coefficient at the fundamental, m/s^2; ``sd_log_b``:
    the sd it adds to log b; ``harmonics``: the harmonics it was learnt from;
    ``power``: the residual's mean squared coefficient at each of them, noise removed
    (m^2/s^4); ``decay``: the exponent used."""

    tau: float
    sd_log_b: float
    harmonics: tuple[int, ...]
    power: tuple[float, ...] = ()
    decay: float = DECAY


def _design(t: np.ndarray, freq: float, ks) -> np.ndarray:
    w = 2.0 * math.pi * freq * t
    return np.column_stack([f(k * w) for k in ks for f in (np.cos, np.sin)])


def _check(harmonics, decay) -> None:
    if not (isinstance(harmonics, int) and harmonics >= 1):
        raise ValueError(f"harmonics must be a whole number of at least 1, got {harmonics!r}")
    if not (isinstance(decay, (int, float)) and math.isfinite(decay) and decay >= 0):
        raise ValueError(f"decay must be a number of at least 0, got {decay!r}")


def _derivative(model, theta: np.ndarray, i: int, step: float, rows: np.ndarray) -> np.ndarray:
    """d (filtered simulation)[rows] / d theta_i by central differences of ``step``,
    one-sided where theta_i is within a step of its prior bound."""
    lo, hi = model.bounds()[i]
    up, down = theta.copy(), theta.copy()
    up[i] = min(theta[i] + step, hi)
    down[i] = max(theta[i] - step, lo)
    return (model.simulate_lp(up)[rows] - model.simulate_lp(down)[rows]) / (up[i] - down[i])


def _signature(model, theta, b_name: str) -> np.ndarray:
    """d a / d log b of the filtered simulation over the model's window."""
    i = model.names.index(b_name)
    log_b = model.all_priors[b_name].log_scale
    signature = _derivative(model, theta, i, B_STEP if log_b else B_STEP * float(theta[i]), model.window)
    return signature * float(theta[i]) if not log_b else signature


def _marginal_tau2(coef: np.ndarray, noise: np.ndarray, shape: np.ndarray) -> float:
    """The tau^2 >= 0 that maximises the likelihood of coefficients ``coef`` ~ N(0, tau^2
    ``shape`` + ``noise``), independent."""
    from scipy.optimize import minimize_scalar

    c2 = coef ** 2

    def minus_log_lik(t2: float) -> float:
        v = t2 * shape + noise
        return float(np.sum(np.log(v) + c2 / v))

    top = float(np.max(c2 / shape))
    if top <= 0:
        return 0.0
    got = minimize_scalar(minus_log_lik, bounds=(0.0, 2.0 * top), method="bounded",
                          options={"xatol": 1e-6 * top})
    return float(got.x) if minus_log_lik(got.x) < minus_log_lik(0.0) else 0.0


def _whiten(x: np.ndarray, rho: float) -> np.ndarray:
    """Rows of ``x`` (on the likelihood's grid) as the AR(1) likelihood weighs them."""
    out = np.empty_like(x)
    out[0] = x[0] * math.sqrt(1.0 - rho * rho)
    out[1:] = x[1:] - rho * x[:-1]
    return out


def _response(model, theta, cov, t_grid, freq, ks) -> np.ndarray:
    """g: the change of the posterior mean of each parameter (rows) per unit coefficient of
    each harmonic (columns, cosine and sine per k in ``ks``), ``C J' W H``."""
    p = model.n_phys
    width = np.diff(model.bounds(), axis=1)[:, 0]
    cols = [_derivative(model, theta, i, B_STEP if model.all_priors[model.names[i]].log_scale else B_STEP * width[i],
                        model.grid) for i in range(p)]
    sigma, rho = model.noise(theta)
    J = _whiten(np.column_stack(cols), rho)
    H = _whiten(_design(t_grid, freq, ks), rho)
    return np.asarray(cov)[:p, :p] @ (J.T @ H) / sigma ** 2


def harmonic_discrepancy(model, theta, *, cov=None, harmonics: int = HARMONICS, decay: float = DECAY,
                         b_name: str = "b") -> Discrepancy:
    """The discrepancy of ``model`` (a single-record posterior) at ``theta`` (see module
    docstring). ``cov``: the posterior covariance of theta (at least of its physical
    parameters, which come first), from the draws or the Laplace approximation; None
    holds the other parameters."""
    _check(harmonics, decay)
    rec = model.record
    freq = rec.drive_frequency  # settled by the model (``PosteriorModel.drive``), as everywhere in a fit
    w = model.window
    t = rec.time[w] - rec.time[w[0]]
    theta = np.asarray(theta, dtype=float)
    r = model.measured_lp[w] - model.simulate_lp(theta)[w]
    top = int(model.likelihood.cutoff // freq)
    ks = [k for k in range(2, harmonics + 2) if k <= top]
    if not ks:
        return Discrepancy(0.0, 0.0, (), (), float(decay))
    phi = _design(t, freq, ks)
    coef, *_ = np.linalg.lstsq(phi, r, rcond=None)
    rest = r - phi @ coef
    # what noise alone puts into each coefficient: its variance through the fit
    noise = float(np.var(rest)) * np.diag(np.linalg.inv(phi.T @ phi))
    excess = (coef ** 2 - noise).reshape(len(ks), 2).mean(axis=1)  # per harmonic
    tau2 = _marginal_tau2(coef, noise, np.repeat(np.array(ks, dtype=float) ** (-2.0 * decay), 2))
    var_k = tau2 * np.array([1] + ks, dtype=float) ** (-2.0 * decay)
    if cov is None:
        d, *_ = np.linalg.lstsq(_design(t, freq, [1] + ks), _signature(model, theta, b_name), rcond=None)
        total = float(d @ d)
        g = d / total if total > 0 else np.zeros_like(d)
    else:
        t_grid = rec.time[model.grid] - rec.time[w[0]]
        g = _response(model, theta, cov, t_grid, freq, [1] + ks)[model.names.index(b_name)]
        if not model.all_priors[b_name].log_scale:  # d b to d log b
            g = g / float(theta[model.names.index(b_name)])
    sd = math.sqrt(float((g ** 2).reshape(len(ks) + 1, 2).sum(axis=1) @ var_k))
    return Discrepancy(math.sqrt(tau2), sd, tuple(ks), tuple(float(e) for e in excess), float(decay))
