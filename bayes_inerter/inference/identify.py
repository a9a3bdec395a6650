"""The paper's own identification: eq. (4)'s least-squares fit and eq. (5)'s phi.

Lin et al. tune the parameters so that the simulated acceleration follows the measured
one (eq. 4) and report how well it does as

    phi = (1 - ||a_est - a_m||_2 / ||a_m - mean(a_m)||_2)      (eq. 5)

on the record as measured. :func:`identify` does the same by machine: least squares on
the **unfiltered** record (the likelihood's window: the record less its ``edge`` at each
end), from the optimiser's start (:func:`.sampling.optimize.find_start`) and ``starts - 1``
scrambled Sobol points in the prior's box, each polished by
:func:`scipy.optimize.least_squares` in the sampled parameters; the best is kept. phi is
the fraction, not a percentage.

An interval for b, in one of two ways (``interval``), each saying how much the point
estimate would move with the noise and misfit the record shows, not what a posterior
says:

- ``"hessian"`` (the default; no refits): the least-squares Jacobian J at the best
  point gives the sandwich A^-1 B A^-1 with A = J'J and B the sum over whole drive
  cycles of (J_c' r_c)(J_c' r_c)' (cycle-clustered, so the residual's correlation within a
  cycle is kept), scaled by C / (C - 1) for C cycles; the interval is b's estimate
  +- Student's t with C - 1 degrees of freedom times its sd, in log b where b is sampled
  in log. **Assumption**: the cycles' residuals are independent of each other. Where J'J
  is singular (a direction the record leaves flat) no interval is given.
- ``"bootstrap"``: a moving-block bootstrap whose blocks are whole cycles: the fitted
  acceleration plus the fit's residual cycles drawn with replacement, each refitted from
  the best point (``bootstrap`` replicates; seconds each).
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
from scipy import optimize
from scipy.stats import qmc

from .posterior.likelihood import LikelihoodSettings
from .posterior.model import PosteriorModel
from .sampling.optimize import find_start

__all__ = ["Identification", "identify", "STARTS", "LEVEL", "BOOTSTRAP_LEVEL", "INTERVALS", "LEAST_SQUARES"]

#: The model :func:`identify` fits: the paper's comparison, the low-passed acceleration
#: sample by sample (its residual's model only sets the noise entries it leaves alone).
LEAST_SQUARES = LikelihoodSettings(residual="ar1")

#: Least-squares starts (the optimiser's and Sobol points in the prior's box).
STARTS = 4
#: The interval's level.
LEVEL = 0.94
BOOTSTRAP_LEVEL = LEVEL  # the name before the Hessian interval
#: The ways of making b's interval (see module docstring).
INTERVALS = ("hessian", "bootstrap")
#: J'J whose columns, scaled to unit length, have a condition number above this is
#: taken as singular: the record leaves a direction flat.
MAX_CONDITION = 1e12


@dataclass(frozen=True)
class Identification:
    """The least-squares fit of one record (see module docstring).

    ``values``: the model's physical parameters by name (b in kg; the noise's sigma and
    rho are not fitted by least squares and left out); ``phi``: eq. 5 on the
    unfiltered record; ``phi_filtered``: the same on the likelihood's low-passed
    signals; ``b_interval``: b's ``level`` interval made by ``interval`` (None where
    none could be made, ``why`` then says why); ``b_draws``: the bootstrap's b's;
    ``cycles``: the whole drive cycles the interval used; ``at_bounds``: the parameters
    whose least-squares value lies on a bound of their prior (the fit would go further).
    """

    values: dict
    phi: float
    phi_filtered: float
    sse: float
    starts: int
    b_interval: tuple[float, float] | None = None
    level: float | None = None
    b_draws: tuple = ()
    interval: str | None = None
    cycles: int = 0
    why: str = ""
    at_bounds: tuple = ()

    @property
    def b(self) -> float:
        return float(self.values["b"])

    def as_dict(self) -> dict:
        """The fit as JSON takes it (what the command line and the study write)."""
        return {"b": self.b, "b_interval": list(self.b_interval) if self.b_interval else None, "level": self.level,
                "interval": self.interval, "cycles": self.cycles, "why_no_interval": self.why, "phi": self.phi,
                "phi_filtered": self.phi_filtered, "sse": self.sse, "starts": self.starts, "values": self.values,
                "at_bounds": list(self.at_bounds), "b_draws": list(self.b_draws)}


def _residual(model: PosteriorModel, phys, target: np.ndarray, noise: np.ndarray) -> np.ndarray:
    theta = np.concatenate([phys, noise])
    w = model.window
    try:
        r = model.simulate_unfiltered(theta)[w] - target[w]
    except (ValueError, RuntimeError):  # out of range, or the simulation gave up
        return np.full(len(w), 1e6)
    return r if np.all(np.isfinite(r)) else np.full(len(w), 1e6)


def _least_squares(model, x0, target, noise, lo, hi):
    x0 = np.clip(x0, lo + 1e-9 * (hi - lo), hi - 1e-9 * (hi - lo))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return optimize.least_squares(lambda x: _residual(model, x, target, noise), x0, bounds=(lo, hi),
                                      x_scale="jac", max_nfev=100 * len(x0))


def _polish(model, x0, target, noise, lo, hi) -> np.ndarray:
    return _least_squares(model, x0, target, noise, lo, hi).x


def _starts(model: PosteriorModel, n: int, rng: np.random.Generator, lo, hi) -> list[np.ndarray]:
    first = find_start(model, rng, objectives=("sse",))[0][: model.n_phys]
    if n <= 1:
        return [first]
    sobol = qmc.Sobol(len(lo), scramble=True, seed=rng).random_base2(math.ceil(math.log2(n - 1)))[: n - 1]
    return [first] + [lo + u * (hi - lo) for u in sobol]


def identify(model: PosteriorModel, *, starts: int = STARTS, seed: int = 0, interval: str | None = "hessian",
             bootstrap: int = 0, level: float = LEVEL) -> Identification:
    """Eq. (4)'s least-squares fit of ``model``'s record, with phi (eq. 5) and b's
    interval made by ``interval`` (one of :data:`INTERVALS`, or None for none; see module
    docstring). ``bootstrap`` replicates, if given, make it a bootstrap interval."""
    if not (isinstance(starts, int) and starts >= 1):
        raise ValueError(f"starts must be a whole number of at least 1, got {starts!r}")
    if not (isinstance(bootstrap, int) and bootstrap >= 0):
        raise ValueError(f"bootstrap replicates must be a whole number, got {bootstrap!r}")
    if not (isinstance(seed, (int, np.integer)) and seed >= 0):
        raise ValueError(f"the seed must be a whole number of 0 or more, got {seed!r}")
    if bootstrap:
        interval = "bootstrap"
    if interval is not None and interval not in INTERVALS:
        raise ValueError(f"interval must be one of {', '.join(INTERVALS)} or None, got {interval!r}")
    if interval == "bootstrap" and not bootstrap:
        raise ValueError("a bootstrap interval needs bootstrap replicates (bootstrap=N, N of 50 or more)")
    if not 0.0 < level < 1.0:
        raise ValueError(f"interval level must lie in (0, 1), got {level}")
    rng = np.random.default_rng(seed)
    bounds = model.bounds()
    lo, hi = bounds[: model.n_phys, 0], bounds[: model.n_phys, 1]
    noise = bounds[model.n_phys:].mean(axis=1)
    measured = np.asarray(model.record.accel, dtype=float)
    fits = [_least_squares(model, x, measured, noise, lo, hi) for x in _starts(model, starts, rng, lo, hi)]
    sse = [2.0 * float(f.cost) for f in fits]  # least_squares' cost is half the sum of squares
    chosen = fits[int(np.argmin(sse))]
    best = chosen.x
    theta = np.concatenate([best, noise])
    w = model.window
    m = measured[w]
    fitted = model.simulate_unfiltered(theta)
    phi = 1.0 - math.sqrt(min(sse)) / float(np.linalg.norm(m - m.mean()))
    values = {k: v for k, v in model.values(theta).items() if k not in ("sigma", "rho")}  # noise: not fitted
    draws, b_interval, why = (), None, ""
    blocks = _cycles(model, len(w))
    if interval == "bootstrap":
        draws = tuple(_bootstrap_b(model, best, fitted, measured, noise, lo, hi, bootstrap, rng, blocks))
        b_interval = tuple(float(q) for q in np.quantile(draws, [(1 - level) / 2, (1 + level) / 2]))
    elif interval == "hessian":
        b_interval, why = _sandwich_interval(model, best, chosen.jac, measured[w] - fitted[w], blocks, level)
    edge = 1e-6 * (hi - lo)
    at_bounds = tuple(n for n, x, a, z, e in zip(model.names, best, lo, hi, edge) if x <= a + e or x >= z - e)
    return Identification({k: float(v) for k, v in values.items()}, phi,
                          model.phi(model.simulate_lp(theta)), min(sse), starts, b_interval,
                          level if interval else None, draws, interval, len(blocks), why, at_bounds)


def _cycles(model: PosteriorModel, n: int) -> list[slice]:
    """The whole drive cycles in the likelihood's window (of ``n`` samples), as slices."""
    freq = model.record.drive_frequency  # settled by the model (``PosteriorModel.drive``)
    period = int(round(model.fs / freq))
    return [slice(i, i + period) for i in range(0, n - period + 1, period)]


def _sandwich_interval(model: PosteriorModel, best, jac, resid, blocks, level):
    """(b's interval, "") from the cycle-clustered sandwich, or (None, why not)."""
    from scipy import stats

    if len(blocks) < 2:
        return None, "the record holds fewer than two whole drive cycles"
    k = model.names.index("b")
    scale = np.linalg.norm(jac, axis=0)
    if np.any(scale == 0):
        return None, "the fit does not depend on some parameter at its best point"
    js = jac / scale
    a = js.T @ js
    if np.linalg.cond(a) > MAX_CONDITION:
        return None, "the record leaves a direction of the parameters flat at the least-squares point"
    # each cycle's share of the estimate's move, x_b - x_b(true) ~ sum over cycles of
    # row' J_c' r_c, row = (J'J)^-1 e_b (in the columns' scaled coordinates, then back)
    row = np.linalg.solve(a, np.eye(len(a))[k]) / scale[k]
    gains = [float(row @ (js[c].T @ resid[c])) for c in blocks]
    n_c = len(blocks)
    sd = math.sqrt(n_c / (n_c - 1) * sum(v * v for v in gains))
    t = float(stats.t.ppf((1 + level) / 2, n_c - 1))
    x_b = float(best[k])
    lo, hi = x_b - t * sd, x_b + t * sd
    if model.all_priors["b"].log_scale:
        return (math.exp(lo), math.exp(hi)), ""
    return (lo, hi), ""


def _bootstrap_b(model, best, fitted, measured, noise, lo, hi, n, rng, cycles) -> list[float]:
    """b refitted on ``n`` records made of the fit plus its residual's drive cycles drawn
    with replacement (within the likelihood's window)."""
    w = model.window
    r = measured[w] - fitted[w]
    blocks = [r[c] for c in cycles]
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
