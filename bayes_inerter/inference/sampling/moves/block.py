"""Metropolis-within-Gibbs block proposals from a normal in normal scores (:class:`BlockMove`).

Each walker redraws a few coordinates chosen at random from their conditional law given
its other coordinates under a normal fitted in the draws' normal scores (an independence
proposal per block): a coordinate the records leave to its prior (the nut stiffness on its
plateau) crosses its whole conditional range in one step without the other coordinates
having to be proposed well at the same time, which a proposal in all coordinates at once
needs (measured: docs/inference.md, "Adaptation").
"""

from __future__ import annotations

import numpy as np
from emcee.moves import MHMove

from ..marginals import NormalScores
from ._draws import usable_draws

__all__ = ["BlockMove", "PARTNERS"]

#: How a block's coordinates are chosen (:class:`BlockMove`'s ``partners``).
PARTNERS = ("random", "correlated")


class BlockMove(MHMove):
    """Metropolis-within-Gibbs from a fitted normal law in normal scores: each walker
    picks a block of coordinates at random (its size drawn from ``sizes``, the
    coordinates uniformly among all) and proposes new values for them alone from the
    conditional law of that block given the walker's other coordinates, the rest kept.

    With ``partners="correlated"`` a block is one coordinate drawn uniformly and, for a
    block of m, the m - 1 others most correlated with it under the fitted normal (by
    |correlation|; fixed once fitted): the coordinates the records tie together, such as
    the Coulomb force and the viscous coefficient, or the nut's and the bearing's
    stiffness and damping, then move together, where a block of random coordinates
    seldom holds both of a tied pair and each alone can move only as far as its narrow
    conditional law allows.

    The law is a normal N(mean, cov) in z = T(x) (``scores``, ``marginals.NormalScores``),
    the block's conditional normal widened by ``scale`` and, in a share ``wide`` of the
    proposals, by ``wide_scale`` more. Which coordinates move does not depend on the
    state, and the conditional law of the block given the others is the same before and
    after the move, so the Hastings factor is the ratio of the block's proposal densities
    (in x: with T's Jacobian for the block's coordinates) at the old and new values, and
    the move leaves any posterior invariant.
    """

    def __init__(self, mean, cov, scores: NormalScores, *, sizes=(1, 2, 3), scale: float = 1.2,
                 wide: float = 0.1, wide_scale: float = 3.0, partners: str = "random"):
        mean = np.asarray(mean, dtype=float)
        cov = np.asarray(cov, dtype=float)
        d = len(mean)
        if mean.ndim != 1 or cov.shape != (d, d) or scores.ndim != d:
            raise ValueError(f"mean, covariance and map do not match: {mean.shape}, {cov.shape}, {scores.ndim}")
        sizes = tuple(int(m) for m in sizes)
        if not sizes or min(sizes) < 1 or max(sizes) > d:
            raise ValueError(f"block sizes must lie in 1..{d}, got {sizes!r}")
        if not (scale > 0 and wide_scale > 0 and 0.0 <= wide < 1.0):
            raise ValueError(f"scales must be positive and the wide share in [0, 1), got {scale}, {wide_scale}, {wide}")
        if partners not in PARTNERS:
            raise ValueError(f"block partners must be one of {', '.join(PARTNERS)}, got {partners!r}")
        self.mean, self.scores, self.sizes, self.partners = mean, scores, sizes, partners
        np.linalg.cholesky(cov)  # LinAlgError if not positive definite
        self.precision = np.linalg.inv(cov)
        sd = np.sqrt(np.diag(cov))
        strength = np.abs(cov / np.outer(sd, sd))
        np.fill_diagonal(strength, np.inf)  # a coordinate first, then its partners, most correlated first
        self.neighbours = np.argsort(-strength, axis=1, kind="stable")
        self.scale, self.wide, self.wide_scale = float(scale), float(wide), float(wide_scale)
        super().__init__(self._propose)

    @classmethod
    def fit(cls, draws, *, knots: int | None = None, scores: NormalScores | None = None, z=None,
            **kwargs) -> "BlockMove | None":
        """The move fitted to ``draws`` (n, ndim): the mean and covariance of their normal
        scores, in the map ``scores`` if given (one already fitted to the same draws, such
        as an ``IndependenceMove``'s) or else in their map with ``knots`` knots; None
        where they define none. ``z``: the draws mapped by ``scores``, where the caller
        has them already (the same numbers, without mapping 50,000 draws again)."""
        if scores is None and knots is None:
            raise ValueError("a block move needs a normal-scores map or the knots to fit one")
        draws = usable_draws(draws)
        if draws is None:
            return None
        try:
            if scores is None:
                scores, z = NormalScores.fit(draws, knots), None
            z = scores.forward(draws)[0] if z is None else z
            return cls(z.mean(axis=0), np.cov(z, rowvar=False), scores, **kwargs)
        except (ValueError, np.linalg.LinAlgError):
            return None

    def _log_q(self, w, m) -> np.ndarray:
        """Log density of the block's proposal (the defensive pair of normals, up to a
        constant) at the rows of ``w`` (n, k), whitened by its conditional law and zero
        beyond each row's block size ``m`` (n,)."""
        r2 = np.sum(w ** 2, axis=1)
        narrow = -0.5 * r2
        if self.wide == 0.0:
            return narrow
        wide = -0.5 * r2 / self.wide_scale ** 2 - m * np.log(self.wide_scale)
        return np.logaddexp(np.log1p(-self.wide) + narrow, np.log(self.wide) + wide)

    def _propose(self, coords, random):
        """Every walker's proposal at once. A walker's block is the first of its sizes'
        coordinates in a random order; blocks are padded to the largest size with
        coordinates that the conditional law leaves where they are (unit precision, no
        coupling), so one batched inverse and Cholesky factor serve all walkers."""
        x = np.array(coords, dtype=float)
        n, d = x.shape
        z, jac_old = self.scores.forward(x)
        k = max(self.sizes)
        sizes = np.asarray(self.sizes)[random.randint(len(self.sizes), size=n)]
        if self.partners == "correlated":
            order = self.neighbours[random.randint(d, size=n), :k]
        else:
            order = np.argsort(random.rand(n, d), axis=1)[:, :k]
        active = np.arange(k) < sizes[:, None]  # (n, k): the slots that are the block
        idx = np.where(active, order, 0)
        both = active[:, :, None] & active[:, None, :]
        # the block's precision, the padding's the identity: its conditional covariance
        # and factor come out block-diagonal, the padding's part the identity
        prec_b = np.where(both, self.precision[idx[:, :, None], idx[:, None, :]], np.eye(k))
        cov_b = np.linalg.inv(prec_b)
        chol = np.linalg.cholesky(cov_b) * self.scale
        # the block's conditional mean given the rest: z_B - cov_B (precision (z - mean))_B
        rows = np.arange(n)[:, None]
        grad = np.where(active, ((z - self.mean) @ self.precision)[rows, idx], 0.0)
        z_b = z[rows, idx]
        mean_b = z_b - np.einsum("nij,nj->ni", cov_b, grad)
        width = np.where(random.rand(n) < self.wide, self.wide_scale, 1.0)
        w_new = np.where(active, width[:, None] * random.randn(n, k), 0.0)
        new_b = mean_b + np.einsum("nij,nj->ni", chol, w_new)
        w_old = np.linalg.solve(chol, (z_b - mean_b)[:, :, None])[:, :, 0]
        log_q = self._log_q(w_old, sizes) - self._log_q(w_new, sizes)
        i, j = np.nonzero(active)
        znew = z.copy()
        znew[i, idx[i, j]] = new_b[i, j]
        moved = np.zeros((n, d), dtype=bool)
        moved[i, idx[i, j]] = True
        q = np.where(moved, self.scores.inverse(znew), x)  # the rest kept exactly
        _, jac_new = self.scores.forward(q)  # the rest's slopes are the same in both
        return q, log_q + jac_old - jac_new
