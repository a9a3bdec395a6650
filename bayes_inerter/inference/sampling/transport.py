"""A triangular transport map learnt from draws (:class:`TriangularScores`).

The chain's normal scores (:class:`.marginals.NormalScores`) make each coordinate's
draws standard normal on its own; where the posterior bends (a coordinate's mean given
the others is not linear in them: measured in results/chain-geometry, f_0 against c_f)
a t fitted there still misses the shape. This map goes one step further, a
lower-triangular map in the sense of Knothe and Rosenblatt (Parno and Marzouk 2018,
"Transport map accelerated Markov chain Monte Carlo"): in the normal scores z, ordered
from the least identified coordinate to the best, each is replaced by its residual from
a quadratic regression on the ones before it, over the residual's sd,

    w_i = (z_i - g_i(z_1, ..., z_{i-1})) / s_i,

so w is nearer a standard normal in every direction than z. The regressions take the
earlier scores clipped to +-``CLIP``: composed down the triangle, quadratics of the
scores themselves would grow as a polynomial of degree 2^(d-1) in w, and a proposal in
the t's tails would map to infinity (seen on a 12-parameter chain); clipped, each g_i is
bounded. Whatever each g_i is, the map is one to one, its inverse is forward
substitution, and its log-Jacobian is the normal scores' less the sum of log s_i (the
triangular part's determinant is constant). It serves as the ``scores``
of :class:`.moves.IndependenceMove`, which needs only a bijection with its Jacobian; not
of :class:`.moves.BlockMove`, which keeps the coordinates outside a block exactly and so
needs a map of each coordinate alone.
"""

from __future__ import annotations

import numpy as np

from .marginals import KNOTS, NormalScores

__all__ = ["TriangularScores", "quadratic_features", "CLIP"]

#: The regressions' inputs, the earlier coordinates' normal scores, are clipped to
#: +-CLIP (a draw beyond 3 sd is one in 370): see the module docstring.
CLIP = 3.0


def quadratic_features(z: np.ndarray, clip: float | None = None) -> np.ndarray:
    """(n, 1 + k + k (k + 1) / 2): a constant, the k columns of ``z`` (clipped to
    +-``clip`` where given) and their products in pairs (squares included)."""
    if clip is not None:
        z = np.clip(z, -clip, clip)
    n, k = z.shape
    cols = [np.ones(n)] + [z[:, a] for a in range(k)] + [z[:, a] * z[:, b] for a in range(k) for b in range(a, k)]
    return np.column_stack(cols)


class TriangularScores:
    """The map w = T(x) of the module docstring, fitted to draws by :meth:`fit`.

    Attributes
    ----------
    scores : the normal-scores map of each coordinate alone.
    order : the coordinates' order in the triangle (least identified first: largest
        variance given the others, in the scores).
    coef : per place in the order, its regression's coefficients on
        :func:`quadratic_features` of the places before it.
    sd : per place, its residual's sd.
    """

    def __init__(self, scores: NormalScores, order, coef, sd):
        self.scores = scores
        self.order = np.asarray(order, dtype=int)
        self.coef = [np.asarray(c, dtype=float) for c in coef]
        self.sd = np.asarray(sd, dtype=float)
        d = scores.ndim
        if sorted(self.order.tolist()) != list(range(d)) or len(self.coef) != d or self.sd.shape != (d,):
            raise ValueError("order, coefficients and sds must cover each coordinate once")
        if not np.all(self.sd > 0):
            raise ValueError("every residual sd must be positive")

    @property
    def ndim(self) -> int:
        return self.scores.ndim

    @classmethod
    def fit(cls, draws, knots: int = KNOTS) -> "TriangularScores":
        """The map fitted to ``draws`` (n, ndim): their normal scores with ``knots`` knots,
        then the regressions by least squares. ValueError where the draws cannot define it
        (too few for the largest regression, or a coordinate the others fix exactly)."""
        x = np.asarray(draws, dtype=float)
        scores = NormalScores.fit(x, knots)
        z = scores.forward(x)[0]
        d = z.shape[1]
        if len(z) <= 2 * quadratic_features(z[:1, : d - 1]).shape[1]:
            raise ValueError(f"{len(z)} draws are too few for a quadratic map in {d} coordinates")
        conditional = 1.0 / np.diag(np.linalg.inv(np.cov(z, rowvar=False)))
        order = np.argsort(-conditional, kind="stable")
        zo = z[:, order]
        coef, sd = [], []
        for i in range(d):
            f = quadratic_features(zo[:, :i], CLIP)
            c = np.linalg.lstsq(f, zo[:, i], rcond=None)[0]
            coef.append(c)
            sd.append(float(np.std(zo[:, i] - f @ c)))
        return cls(scores, order, coef, sd)

    def forward(self, x):
        """(w, log |det dw / dx|) at the rows of ``x`` (n, ndim)."""
        z, log_jac = self.scores.forward(np.atleast_2d(x))
        zo = z[:, self.order]
        w = np.empty_like(zo)
        for i in range(zo.shape[1]):
            w[:, i] = (zo[:, i] - quadratic_features(zo[:, :i], CLIP) @ self.coef[i]) / self.sd[i]
        return w, log_jac - np.sum(np.log(self.sd))

    def inverse(self, w):
        """x at the rows of ``w`` (n, ndim), by forward substitution."""
        w = np.atleast_2d(np.asarray(w, dtype=float))
        zo = np.empty_like(w)
        for i in range(w.shape[1]):
            zo[:, i] = w[:, i] * self.sd[i] + quadratic_features(zo[:, :i], CLIP) @ self.coef[i]
        z = np.empty_like(zo)
        z[:, self.order] = zo
        return self.scores.inverse(z)
