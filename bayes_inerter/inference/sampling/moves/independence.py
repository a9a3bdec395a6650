"""Independence proposals from a fitted multivariate t (:class:`IndependenceMove`).

For every walker the move proposes a point drawn afresh from a fixed multivariate
Student t (a mean, a covariance and degrees of freedom), whatever the walker's own
position, and accepts it with probability min(1, p(x') q(x) / (p(x) q(x'))) (independence
Metropolis-Hastings, Tierney 1994): with the proposal fixed, it leaves any posterior
invariant. The sampler fits the t to the chain's own draws so far and refits it as the
chain grows (``sampler.Adaptation``); a share of the proposals comes from the same t
made wider, so that tails the fit has not yet seen are proposed too. Where the posterior
is roughly that t, a walker crosses it in one step instead of diffusing across it as the
ensemble moves do; where it is not, the proposal is refused more often and the ensemble
moves, which stay in the mixture, do the work. Fitted in the draws' normal scores instead
(``marginals.NormalScores``: each coordinate mapped monotonically so that its draws are
standard normal, the t fitted there), the proposal follows every marginal's shape, a
long tail included.
"""

from __future__ import annotations

import numpy as np
from emcee.moves import MHMove

from ..marginals import NormalScores
from ._draws import usable_draws

__all__ = ["IndependenceMove"]


class IndependenceMove(MHMove):
    """Independence proposals from a fixed defensive mixture of two multivariate t's (see
    the module docstring): the fitted one, and in a share ``wide`` of the draws the same t
    ``wide_scale`` times wider (Hesterberg's defensive importance sampling). Without the
    wide part a proposal fitted to an ensemble that has not yet spread over the posterior
    (the start's cluster, a few hundred steps in) proposes only that cluster: a walker out
    in a tail it does not cover is rarely moved by it, and half the steps pull walkers back
    to the cluster (measured: docs/inference.md, "Adaptation").

    Parameters
    ----------
    mean : (ndim,) centre of the proposal.
    cov : (ndim, ndim) covariance it is fitted to (positive definite).
    dof : degrees of freedom of the t (``np.inf``: a normal). Default 10.
    scale : factor on the covariance's square root (default 1.1: a little wider).
    wide, wide_scale : share of the wide part and its width against the fitted one
        (defaults 0.2 and 3; ``wide=0``: the fitted t alone).
    scores : a ``marginals.NormalScores`` map z = T(x); the t's (mean, cov) then live in z,
        proposals are drawn there and mapped back, and the density carries T's Jacobian.
        Default None: the t lives in the sampler's coordinates.
    """

    def __init__(self, mean, cov, *, dof: float = 10.0, scale: float = 1.1, wide: float = 0.2,
                 wide_scale: float = 3.0, scores: NormalScores | None = None):
        mean = np.asarray(mean, dtype=float)
        cov = np.atleast_2d(np.asarray(cov, dtype=float))
        d = len(mean) if mean.ndim == 1 else 0
        if mean.ndim != 1 or cov.shape != (d, d):
            raise ValueError(f"mean and covariance do not match: {mean.shape} and {cov.shape}")
        if not (dof > 0 and scale > 0 and wide_scale > 0):
            raise ValueError(f"degrees of freedom and scales must be positive, got {dof}, {scale} and {wide_scale}")
        if not 0.0 <= wide < 1.0:
            raise ValueError(f"the wide part's share must lie in [0, 1), got {wide}")
        if not (np.all(np.isfinite(mean)) and np.all(np.isfinite(cov))):
            raise ValueError("the proposal's mean and covariance must be finite")
        self.mean = mean
        self.dof, self.scale = float(dof), float(scale)
        self.wide, self.wide_scale = float(wide), float(wide_scale)
        if scores is not None and scores.ndim != d:
            raise ValueError(f"the normal-scores map has {scores.ndim} coordinates, the proposal {d}")
        self.scores = scores
        #: the Cholesky factor of the covariance times ``scale ** 2``
        self.chol = np.linalg.cholesky(cov * self.scale ** 2)  # LinAlgError if not positive definite
        super().__init__(self._propose)

    @classmethod
    def fit(cls, draws, *, knots: int | None = None, **kwargs) -> "IndependenceMove | None":
        """The move fitted to ``draws`` (n, ndim) by their mean and covariance; with
        ``knots``, in the draws' normal scores (``marginals.NormalScores`` with that many
        knots). None where they cannot define one (fewer draws than dimensions, or a
        singular covariance); draws too few for a normal-scores map give the t in their own
        coordinates."""
        return cls.fit_scored(draws, knots=knots, **kwargs)[0]

    @classmethod
    def fit_scored(cls, draws, *, knots: int | None = None,
                   **kwargs) -> tuple["IndependenceMove | None", np.ndarray | None]:
        """:meth:`fit`, and the draws mapped to the normal scores it fitted them in (None
        where it fitted none): a block move fitted to the same draws in the same scores
        takes them (``BlockMove.fit(z=)``) rather than mapping the draws again."""
        draws = usable_draws(draws)
        if draws is None:
            return None, None
        if knots is not None:
            try:
                scores = NormalScores.fit(draws, knots)
            except ValueError:
                scores = None
            if scores is not None:
                z = scores.forward(draws)[0]
                return cls.fit(z, scores=scores, **kwargs), z
        try:
            return cls(draws.mean(axis=0), np.cov(draws, rowvar=False), **kwargs), None
        except np.linalg.LinAlgError:
            return None, None

    @classmethod
    def fit_in(cls, draws, scores, **kwargs) -> "IndependenceMove | None":
        """The move fitted (as :meth:`fit` without knots) to ``draws`` mapped by ``scores``,
        a bijection with ``forward`` (values and log-Jacobian) and ``inverse``
        (``marginals.NormalScores``, ``transport.TriangularScores``), and proposing through
        it; None where the mapped draws define none."""
        return cls.fit(scores.forward(draws)[0], scores=scores, **kwargs)

    def _log_t(self, x, width: float) -> np.ndarray:
        """Log density of the t widened by ``width``, up to a constant common to every
        width."""
        z = np.linalg.solve(self.chol, (np.atleast_2d(x) - self.mean).T) / width
        m2 = np.sum(z * z, axis=0)
        d = len(self.mean)
        core = -0.5 * m2 if np.isinf(self.dof) else -0.5 * (self.dof + d) * np.log1p(m2 / self.dof)
        return core - d * np.log(width)

    def log_density(self, x) -> np.ndarray:
        """Log density of the proposal at the rows of ``x``, up to a constant."""
        if self.scores is not None:
            z, log_jac = self.scores.forward(x)
            return self._log_density(z) + log_jac
        return self._log_density(x)

    def _log_density(self, x) -> np.ndarray:
        """Log density of the defensive pair of t's (in z where there is a normal-scores map)."""
        if self.wide == 0.0:
            return self._log_t(x, 1.0)
        return np.logaddexp(np.log1p(-self.wide) + self._log_t(x, 1.0),
                            np.log(self.wide) + self._log_t(x, self.wide_scale))

    def draw(self, n: int, random) -> np.ndarray:
        """``n`` draws of the proposal (its defensive pair of t's, mapped back through its
        normal scores where it has them); ``random``: a ``numpy.random.RandomState``."""
        z = random.randn(n, len(self.mean))
        if np.isfinite(self.dof):
            z = z / np.sqrt(random.chisquare(self.dof, size=n) / self.dof)[:, None]
        width = np.where(random.rand(n) < self.wide, self.wide_scale, 1.0)
        q = self.mean + (z * width[:, None]) @ self.chol.T
        return self.scores.inverse(q) if self.scores is not None else q

    def _propose(self, coords, random):
        coords = np.asarray(coords, dtype=float)
        q = self.draw(len(coords), random)
        return q, self.log_density(coords) - self.log_density(q)
