"""A mixture of multivariate normals fitted to draws by expectation-maximisation.

The adaptive sampler's independence proposal (:class:`.moves.IndependenceMove`) is a
single t fitted to the chain by its mean and covariance unless asked for more
components; where the posterior is not one ellipsoid (the nut's plateau against its
cliff, the bearing damping piled against its prior's wall) a few components follow its
shape more closely and their proposals are accepted more often.

:func:`fit_normal_mixture` is plain EM with full covariances (Dempster, Laird and Rubin
1977), started from k-means++ centres (Arthur and Vassilvitskii 2007) in coordinates
whitened by the draws' own covariance, with ``reg`` times the identity added to every
covariance there (a floor that keeps a component from collapsing onto a few draws).
Deterministic for a given ``seed``: a chain refitted from the same stored steps gets the
same proposal.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import solve_triangular
from scipy.special import logsumexp

__all__ = ["fit_normal_mixture"]


def _log_components(z, weights, means, chols) -> np.ndarray:
    """(k, n) log of each weighted component's density at the rows of z (less the
    normal's constant, common to all)."""
    out = np.empty((len(weights), len(z)))
    for j, (w, m, L) in enumerate(zip(weights, means, chols)):
        y = solve_triangular(L, (z - m).T, lower=True, check_finite=False)
        out[j] = np.log(w) - 0.5 * np.sum(y * y, axis=0) - np.sum(np.log(np.diag(L)))
    return out


def fit_normal_mixture(draws, k: int, *, seed: int = 0, max_iter: int = 100, tol: float = 1e-5,
                       reg: float = 1e-6):
    """Weights (k',), means (k', d) and covariances (k', d, d) of a normal mixture fitted
    to ``draws`` (n, d) by EM; k' <= k (a component left with fewer than 2 d draws'
    worth of responsibility is dropped). Stops when the mean log-likelihood per draw
    changes by less than ``tol`` or after ``max_iter`` iterations. Raises ValueError for
    fewer draws than 2 d k or a singular covariance of the draws."""
    x = np.asarray(draws, dtype=float)
    if x.ndim != 2 or not np.all(np.isfinite(x)):
        raise ValueError("draws must be a finite (n, d) array")
    n, d = x.shape
    if not (isinstance(k, int) and k >= 1):
        raise ValueError(f"the number of components must be a positive whole number, got {k!r}")
    if n < 2 * d * k:
        raise ValueError(f"{n} draws are too few for {k} components in {d} dimensions (need {2 * d * k})")
    centre = x.mean(axis=0)
    L0 = np.linalg.cholesky(np.cov(x, rowvar=False))  # LinAlgError (a ValueError's cousin) if singular
    z = solve_triangular(L0, (x - centre).T, lower=True).T

    rng = np.random.default_rng(seed)
    centres = [z[rng.integers(n)]]
    d2 = np.sum((z - centres[0]) ** 2, axis=1)
    for _ in range(1, k):
        c = z[rng.choice(n, p=d2 / d2.sum())] if d2.sum() > 0 else z[rng.integers(n)]
        centres.append(c)
        d2 = np.minimum(d2, np.sum((z - c) ** 2, axis=1))
    nearest = np.argmin(np.stack([np.sum((z - c) ** 2, axis=1) for c in centres]), axis=0)
    resp = np.zeros((k, n))
    resp[nearest, np.arange(n)] = 1.0

    eye = np.eye(d)
    last = -np.inf
    for _ in range(max_iter):
        nk = resp.sum(axis=1)
        keep = nk >= 2 * d
        if not keep.any():
            raise ValueError(f"no component keeps {2 * d} draws' worth of responsibility")
        resp, nk = resp[keep], nk[keep]  # a dropped component's draws go to the others at the next E step
        weights = nk / nk.sum()
        means = (resp @ z) / nk[:, None]
        chols = []
        for r, m, c in zip(resp, means, nk):
            y = z - m
            chols.append(np.linalg.cholesky((y * r[:, None]).T @ y / c + reg * eye))
        logp = _log_components(z, weights, means, chols)
        total = logsumexp(logp, axis=0)
        resp = np.exp(logp - total)
        ll = float(np.mean(total))
        if abs(ll - last) < tol:
            break
        last = ll
    covs = np.array([L0 @ (L @ L.T) @ L0.T for L in chols])
    return weights, centre + means @ L0.T, covs
