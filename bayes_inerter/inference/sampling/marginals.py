"""Monotone per-coordinate maps that make draws' marginals normal (normal scores).

The adaptive sampler's independence proposal (:class:`.moves.IndependenceMove`) is a t
fitted by the draws' mean and covariance. Where a marginal of the posterior is far from
normal (the nut stiffness's plateau ending in a long tail, the bearing damping piled
against its prior's wall, the friction shares), a t fitted to it is thin where the
posterior is not: a walker that reaches such a place is rarely moved by the proposal
(its weight p / q is large there) and waits for the ensemble moves. Drawing the
proposal in normal scores instead, z_i = T_i(x_i) for each coordinate, and fitting the
t to z (a Gaussian copula with the draws' own marginals, in the sense of Sklar 1959),
follows every marginal's shape while the t keeps the correlations.

:class:`NormalScores` is T: for each coordinate a piecewise-linear map through ``knots``
quantiles of the draws (at probabilities (j + 1/2) / knots) to the standard normal's
quantiles at the same probabilities, continued beyond the outermost knots as straight
lines with the slope of the outer tenth of the knots (so the proposal's tails in x are
those of the t in z, stretched linearly: they do not end at the draws' range). Knots of
equal value (a walker that stayed put, repeated values) are spread by a thousandth of
the coordinate's knot range divided among them, so T is strictly increasing and the
density q(x) = q_z(T(x)) prod_i T_i'(x_i) is defined everywhere.

Measured on the full study's converged joint chain (27 records, 20 parameters;
``benchmarks/bench_proposal.py``, proposals fitted to its steps 130-9,000 with the
adaptation's dof, scale and wide part): a t in normal scores (200 knots) was accepted
0.42 of the time, one t in the sampler's coordinates 0.07 and a mixture of five 0.27;
the largest weight p / q over the chain's second half was e^3.2 times its median with
normal scores, e^12.4 with one t and e^7.8 with five (a walker there waits about that
many proposals).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
from scipy.special import ndtri

__all__ = ["NormalScores", "KNOTS"]

#: default number of knots (quantiles) per coordinate
KNOTS = 200


@dataclass(frozen=True)
class NormalScores:
    """The map x -> z of every coordinate through its knots (see module docstring).

    Attributes
    ----------
    x_knots : (knots, ndim) strictly increasing in each column.
    z_knots : (knots,) the standard normal's quantiles they map to (strictly increasing).
    """

    x_knots: np.ndarray
    z_knots: np.ndarray

    def __post_init__(self) -> None:
        xk, zk = np.asarray(self.x_knots, dtype=float), np.asarray(self.z_knots, dtype=float)
        if xk.ndim != 2 or zk.shape != (len(xk),) or len(zk) < 4:
            raise ValueError(f"knots must be (k, ndim) and (k,) with k >= 4, got {xk.shape} and {zk.shape}")
        if not (np.all(np.isfinite(xk)) and np.all(np.isfinite(zk))):
            raise ValueError("knots must be finite")
        if not (np.all(np.diff(xk, axis=0) > 0) and np.all(np.diff(zk) > 0)):
            raise ValueError("knots must be strictly increasing")
        object.__setattr__(self, "x_knots", xk)
        object.__setattr__(self, "z_knots", zk)

    @classmethod
    def fit(cls, draws, knots: int = KNOTS) -> "NormalScores":
        """The map whose knots are ``knots`` quantiles of ``draws`` (n, ndim), at most
        n / 10 of them (a knot per ten draws at least). Raises ValueError for fewer than
        40 draws or non-finite ones."""
        x = np.asarray(draws, dtype=float)
        if x.ndim != 2 or not np.all(np.isfinite(x)):
            raise ValueError("draws must be a finite (n, ndim) array")
        if len(x) < 40:
            raise ValueError(f"{len(x)} draws are too few for a normal-scores map (need 40)")
        if not (isinstance(knots, int) and knots >= 4):
            raise ValueError(f"knots must be a whole number of at least 4, got {knots!r}")
        k = min(knots, len(x) // 10)
        p = (np.arange(k) + 0.5) / k
        xk = np.quantile(x, p, axis=0)
        span = xk[-1] - xk[0]
        scale = np.where(span > 0, span, np.maximum(np.abs(xk[0]), 1.0))
        # spread ties: cumulative floor of a thousandth of the span shared among the steps
        step = np.maximum(np.diff(xk, axis=0), 1e-3 * scale / k)
        xk = np.vstack([xk[:1], xk[:1] + np.cumsum(step, axis=0)])
        return cls(xk, ndtri(p))

    @property
    def ndim(self) -> int:
        return self.x_knots.shape[1]

    @cached_property
    def _derived(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(slopes between the knots (knots - 1, ndim), the slopes dz/dx of the straight
        continuations below and above the knots (ndim,) each): formed once, kept."""
        xk, zk = self.x_knots, self.z_knots
        j = max(1, len(zk) // 10)
        return (np.diff(zk)[:, None] / np.diff(xk, axis=0),
                (zk[j] - zk[0]) / (xk[j] - xk[0]), (zk[-1] - zk[-1 - j]) / (xk[-1] - xk[-1 - j]))

    def forward(self, x) -> tuple[np.ndarray, np.ndarray]:
        """z = T(x) for the rows of ``x`` (n, ndim), and log prod_i T_i'(x_i) (n,)."""
        x = np.atleast_2d(np.asarray(x, dtype=float))
        xk, zk = self.x_knots, self.z_knots
        slopes, lo, hi = self._derived
        n, d = x.shape
        j = np.empty((n, d), dtype=np.intp)
        for i in range(d):  # a knot's column at a time; the arithmetic below on all at once
            j[:, i] = np.searchsorted(xk[:, i], x[:, i], side="right")
        j = np.clip(j - 1, 0, len(zk) - 2)
        cols = np.arange(d)
        s = slopes[j, cols]
        z = zk[j] + s * (x - xk[j, cols])
        below, above = x < xk[0], x > xk[-1]
        z = np.where(below, zk[0] + lo * (x - xk[0]), z)
        z = np.where(above, zk[-1] + hi * (x - xk[-1]), z)
        logs = np.log(np.where(below, lo, np.where(above, hi, s)))
        log_jac = np.zeros(n)
        for i in range(d):  # summed in the coordinates' order
            log_jac += logs[:, i]
        return z, log_jac

    def inverse(self, z) -> np.ndarray:
        """x = T^-1(z) for the rows of ``z`` (n, ndim): on all coordinates at once, with
        the arithmetic of ``np.interp`` between the knots (the same digits)."""
        z = np.atleast_2d(np.asarray(z, dtype=float))
        xk, zk = self.x_knots, self.z_knots
        _, lo, hi = self._derived
        last = len(zk) - 1
        j = np.clip(np.searchsorted(zk, z, side="right") - 1, 0, last - 1)
        cols = np.arange(z.shape[1])
        x0 = xk[j, cols]
        x = (xk[j + 1, cols] - x0) / (zk[j + 1] - zk[j]) * (z - zk[j]) + x0
        x = np.where(z == zk[last], xk[last], x)  # np.interp's value on the last knot
        x = np.where(z < zk[0], xk[0] + (z - zk[0]) / lo, x)
        return np.where(z > zk[last], xk[last] + (z - zk[last]) / hi, x)
