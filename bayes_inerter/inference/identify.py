"""The paper's own identification: eq. (4)'s least-squares fit and eq. (5)'s phi.

Lin et al. tune the parameters so that the simulated acceleration follows the measured
one (eq. 4) and report how well it does as

    phi = (1 - ||a_est - a_m||_2 / ||a_m - mean(a_m)||_2)      (eq. 5)

on the record as measured. :func:`identify` does the same by machine: least squares on
the **unfiltered** record (the likelihood's window: the record less its ``edge`` at each
end), from the optimiser's start (:func:`.optimize.find_start`) and ``starts - 1``
scrambled Sobol points in the prior's box, each polished by
:func:`scipy.optimize.least_squares` in the sampled parameters; the best is kept. phi is
the fraction, not a percentage.

An interval for b, optionally, from a bootstrap over drive cycles (a moving-block
bootstrap whose blocks are whole cycles, so the residual's correlation within a cycle
is kept): the fitted acceleration plus the fit's residual cycles drawn with
replacement, refitted from the best point. It says how much the point estimate moves
with the noise and misfit the record shows, not what a posterior says.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
from scipy import optimize
from scipy.stats import qmc

from .model import PosteriorModel
from .optimize import find_start

__all__ = ["Identification", "identify", "STARTS", "BOOTSTRAP_LEVEL"]

#: Least-squares starts (the optimiser's and Sobol points in the prior's box).
STARTS = 4
#: The bootstrap interval's level.
BOOTSTRAP_LEVEL = 0.94


@dataclass(frozen=True)
class Identification:
    """The least-squares fit of one record (see module docstring).

    ``values``: the model's physical parameters by name (b in kg; the noise's sigma and
    rho are not fitted by least squares and left out); ``phi``: eq. 5 on the
    unfiltered record; ``phi_filtered``: the same on the likelihood's low-passed
    signals; ``b_interval``: the bootstrap's ``level`` interval of b (None without a
    bootstrap); ``b_draws``: the bootstrap's b's.
    """

    values: dict
    phi: float
    phi_filtered: float
    sse: float
    starts: int
    b_interval: tuple[float, float] | None = None
    level: float | None = None
    b_draws: tuple = ()

    @property
    def b(self) -> float:
        return float(self.values["b"])


def _residual(model: PosteriorModel, phys, target: np.ndarray, noise: np.ndarray) -> np.ndarray:
    theta = np.concatenate([phys, noise])
    w = model.window
    try:
        r = model.simulate_unfiltered(theta)[w] - target[w]
    except (ValueError, RuntimeError):  # out of range, or the simulation gave up
        return np.full(len(w), 1e6)
    return r if np.all(np.isfinite(r)) else np.full(len(w), 1e6)


def _polish(model, x0, target, noise, lo, hi) -> np.ndarray:
    x0 = np.clip(x0, lo + 1e-9 * (hi - lo), hi - 1e-9 * (hi - lo))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        got = optimize.least_squares(lambda x: _residual(model, x, target, noise), x0, bounds=(lo, hi),
                                     x_scale="jac", max_nfev=100 * len(x0))
    return got.x


def _starts(model: PosteriorModel, n: int, rng: np.random.Generator, lo, hi) -> list[np.ndarray]:
    first = find_start(model, rng)[0][: model.n_phys]
    if n <= 1:
        return [first]
    sobol = qmc.Sobol(len(lo), scramble=True, seed=rng).random(n - 1)
    return [first] + [lo + u * (hi - lo) for u in sobol]


def identify(model: PosteriorModel, *, starts: int = STARTS, seed: int = 0, bootstrap: int = 0,
             level: float = BOOTSTRAP_LEVEL) -> Identification:
    """Eq. (4)'s least-squares fit of ``model``'s record, with phi (eq. 5) and, with
    ``bootstrap`` replicates, an interval for b (see module docstring)."""
    if not (isinstance(starts, int) and starts >= 1):
        raise ValueError(f"starts must be a whole number of at least 1, got {starts!r}")
    if not (isinstance(bootstrap, int) and bootstrap >= 0):
        raise ValueError(f"bootstrap replicates must be a whole number, got {bootstrap!r}")
    if not 0.0 < level < 1.0:
        raise ValueError(f"interval level must lie in (0, 1), got {level}")
    rng = np.random.default_rng(seed)
    bounds = model.bounds()
    lo, hi = bounds[: model.n_phys, 0], bounds[: model.n_phys, 1]
    noise = bounds[model.n_phys:].mean(axis=1)
    measured = np.asarray(model.record.accel, dtype=float)
    fits = [_polish(model, x, measured, noise, lo, hi) for x in _starts(model, starts, rng, lo, hi)]
    sse = [float(np.sum(_residual(model, x, measured, noise) ** 2)) for x in fits]
    best = fits[int(np.argmin(sse))]
    theta = np.concatenate([best, noise])
    w = model.window
    m = measured[w]
    fitted = model.simulate_unfiltered(theta)
    phi = 1.0 - math.sqrt(min(sse)) / float(np.linalg.norm(m - m.mean()))
    values = {k: v for k, v in model.values(theta).items() if k not in ("sigma", "rho")}  # noise: not fitted
    draws, interval = (), None
    if bootstrap:
        draws = tuple(_bootstrap_b(model, best, fitted, measured, noise, lo, hi, bootstrap, rng))
        interval = tuple(float(q) for q in np.quantile(draws, [(1 - level) / 2, (1 + level) / 2]))
    return Identification({k: float(v) for k, v in values.items()}, phi,
                          model.phi(model.simulate_lp(theta)), min(sse), starts, interval,
                          level if bootstrap else None, draws)


def _bootstrap_b(model, best, fitted, measured, noise, lo, hi, n, rng) -> list[float]:
    """b refitted on ``n`` records made of the fit plus its residual's drive cycles drawn
    with replacement (within the likelihood's window)."""
    w = model.window
    freq = model.record.metadata.get("drive_frequency_hz")
    period = int(round(model.fs / freq)) if freq else len(w) // 10
    r = measured[w] - fitted[w]
    blocks = [r[i:i + period] for i in range(0, len(r) - period + 1, period)]
    if len(blocks) < 2:
        raise ValueError("the bootstrap over cycles needs at least two drive cycles in the record")
    out = []
    for _ in range(n):
        picked = np.concatenate([blocks[k] for k in rng.integers(len(blocks), size=len(blocks))])
        target = measured.copy()
        target[w[: len(picked)]] = fitted[w[: len(picked)]] + picked
        x = _polish(model, best, target, noise, lo, hi)
        out.append(float(model.values(np.concatenate([x, noise]))["b"]))
    return out
