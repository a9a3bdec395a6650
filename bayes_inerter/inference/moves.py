"""Moves beside emcee's own: a jump along the nut's ridge, differential evolution in
random subspaces, independence proposals from a fitted multivariate t (or a mixture of
them, or a t in normal scores), and Metropolis-within-Gibbs block proposals from a
fitted normal in normal scores.

The nut's deformation (c_n + k_n / s) sits in series with the inertance b s; at the
drive frequencies the pair acts as a damper in series with an inerter of
1 / b_app = 1 / b - k_n / c_n^2 (``device.apparent_inertance``). The records fix b_app
tightly and leave k_n free over decades (a plateau of the log posterior, then a cliff):
a ridge, curved in the sampled log coordinates, that the ensemble moves cross only by
creeping (the README's long-chain study: the autocorrelation time of b grows with the
chain).

:class:`NutRidgeMove` jumps along it. Each walker draws a step delta of log k_n from a
zero-mean normal whose sd is itself drawn log-uniformly between ``scale_min`` and
``scale_max`` (a symmetric mixture: short steps near the cliff, long ones across the
plateau) and moves every inertance so that 1 / b - k_n / c_n^2 stays as it was:

    log k_n' = log k_n + delta,    1 / b' = 1 / b + (k_n' - k_n) / c_n^2.

The map is its own inverse with -delta, and its Jacobian in the sampled coordinates
(log b, log k_n) is the product of b' / b over the inertances, which enters the
acceptance ratio (Green 1995). So the move leaves any posterior invariant, whatever
the model: the ridge only decides how often it is accepted. 1 / b' is always positive
(1 / b_app > 0 and k_n' > 0 wherever the step starts from a point with b_app > 0).

:class:`SubspaceDEMove` is differential evolution that moves each walker along only a
random subset of the coordinates (the randomised subspaces of DREAM, Vrugt et al. 2009,
within emcee's red-blue ensemble): each walker picks a crossover probability CR from
``crossovers`` and keeps each coordinate of the difference of two walkers of the other
half with probability CR (at least one), scaled by gamma = 2.38 / sqrt(2 d') for the d'
coordinates it moves. Which coordinates move does not depend on the state, so each
proposal stays symmetric and the move leaves the posterior invariant. Full-dimensional DE
in 20 dimensions takes short steps (gamma 0.38); a step in a few coordinates is longer.
Measured on a joint model of 9 records it did not mix faster than the default moves
(``studies/joint_mixing.py``), so no default uses it.

:class:`IndependenceMove` proposes, for every walker, a point drawn afresh from a fixed
multivariate Student t (a mean, a covariance and degrees of freedom), whatever the
walker's own position, and accepts it with probability min(1, p(x') q(x) / (p(x) q(x')))
(independence Metropolis-Hastings, Tierney 1994): with the proposal fixed, it leaves any
posterior invariant. The sampler fits the t to the chain's own draws so far and refits
it as the chain grows (:class:`.sampler.Adaptation`); a share of the proposals comes from
the same t made wider, so that tails the fit has not yet seen are proposed too. Where the posterior is roughly
that t, a walker crosses it in one step instead of diffusing across it as the ensemble
moves do (their autocorrelation time grows with the dimension); where it is not (the
nut's plateau against its cliff), the proposal is refused more often and the ensemble
moves, which stay in the mixture, do the work. A proposal of several t's, fitted as a
normal mixture by EM (:mod:`.mixture`), follows such a shape more closely: on the joint
model's converged chain, five t's proposals were accepted 3.3 times as often as one t's
(``benchmarks/bench_proposal.py``). Yet a joint chain run with them from the start mixed
no faster over its first 1,683 steps (the README's "Where the walkers move"), so no
default uses them. Fitted in the draws' normal scores instead (:mod:`.marginals`: each
coordinate mapped monotonically so that its draws are standard normal, the t fitted
there), the proposal follows every marginal's shape, the plateau's long tail included.

:class:`BlockMove` proposes, for each walker, new values for a few coordinates chosen at
random, from their conditional law given the walker's other coordinates under a normal
fitted in normal scores (Metropolis-within-Gibbs with an independence proposal per
block): a coordinate the records leave to its prior crosses its range without the
others having to be proposed well at the same time.
"""

from __future__ import annotations

import numpy as np
from emcee.moves import MHMove, RedBlueMove

from .marginals import NormalScores
from .mixture import fit_normal_mixture

__all__ = ["NutRidgeMove", "SubspaceDEMove", "IndependenceMove", "BlockMove", "ridge_indices", "MIXTURE_DRAWS"]

#: At most this many draws (evenly spaced) go into a mixture proposal's EM fit.
MIXTURE_DRAWS = 5_000


def _usable(draws) -> np.ndarray | None:
    """``draws`` as an (n, ndim) float array if a proposal can be fitted to them (finite,
    more draws than dimensions); else None."""
    draws = np.asarray(draws, dtype=float)
    if draws.ndim != 2 or len(draws) <= draws.shape[1] or not np.all(np.isfinite(draws)):
        return None
    return draws


def ridge_indices(names, log_scale) -> tuple[int, int, list[int]] | None:
    """(index of k_n, index of c_n, indices of the inertances) in a parameter vector
    named ``names``, or None if it has no nut ridge (a model without b, k_n or c_n, or
    with any of them not sampled in log scale)."""
    names = list(names)
    b_idx = [i for i, n in enumerate(names) if n == "b" or n.startswith("b_")]
    if "k_n" not in names or "c_n" not in names or not b_idx:
        return None
    k, c = names.index("k_n"), names.index("c_n")
    if not all(log_scale[i] for i in [k, c, *b_idx]):
        return None
    return k, c, b_idx


class NutRidgeMove(MHMove):
    """Jump along log k_n keeping every 1 / b - k_n / c_n^2 (see module docstring).

    Parameters
    ----------
    k_index, c_index : positions of log k_n and log c_n in the sampled vector.
    b_indices : positions of the log inertances (one per record, or per setting).
    scale_min, scale_max : range (natural log units) of the step's sd, drawn
        log-uniformly per walker and step. Defaults 0.1 and 4 (a step of a few
        percent to about two decades of k_n).
    """

    def __init__(self, k_index: int, c_index: int, b_indices, *, scale_min: float = 0.1, scale_max: float = 4.0):
        if not 0 < scale_min <= scale_max:
            raise ValueError(f"ridge step sds must satisfy 0 < min <= max, got {scale_min}, {scale_max}")
        self.k_index, self.c_index = int(k_index), int(c_index)
        self.b_indices = np.asarray(b_indices, dtype=int)
        if self.b_indices.size == 0:
            raise ValueError("the ridge move needs at least one inertance")
        self.scale_min, self.scale_max = float(scale_min), float(scale_max)
        super().__init__(self._propose)

    def _propose(self, coords, random):
        coords = np.asarray(coords, dtype=float)
        n = len(coords)
        sd = np.exp(random.uniform(np.log(self.scale_min), np.log(self.scale_max), size=n))
        delta = sd * random.randn(n)
        q = coords.copy()
        log_k = coords[:, self.k_index]
        inv_c2 = np.exp(-2.0 * coords[:, self.c_index])
        dkappa = (np.exp(log_k + delta) - np.exp(log_k)) * inv_c2
        log_b = coords[:, self.b_indices]
        inv_b = np.exp(-log_b) + dkappa[:, None]
        with np.errstate(invalid="ignore", divide="ignore"):
            new_log_b = -np.log(inv_b)  # inv_b > 0 on the ridge; NaN elsewhere is rejected below
        q[:, self.k_index] = log_k + delta
        q[:, self.b_indices] = new_log_b
        factors = np.sum(new_log_b - log_b, axis=1)  # log |Jacobian|: sum of log(b' / b)
        bad = ~np.all(np.isfinite(q), axis=1)
        q[bad] = coords[bad]
        factors[bad] = -np.inf
        return q, factors


class SubspaceDEMove(RedBlueMove):
    """Differential evolution in random subspaces (see module docstring).

    Parameters
    ----------
    crossovers : crossover probabilities CR, one drawn uniformly per walker and step
        (default 1/3, 2/3 and 1: DREAM's three).
    sigma : relative spread of gamma about 2.38 / sqrt(2 d') (emcee's DEMove: 1e-5).
    """

    def __init__(self, crossovers=(1 / 3, 2 / 3, 1.0), sigma: float = 1.0e-5, **kwargs):
        cr = np.asarray(crossovers, dtype=float)
        if cr.ndim != 1 or cr.size == 0 or not np.all((cr > 0) & (cr <= 1)):
            raise ValueError(f"crossover probabilities must lie in (0, 1], got {crossovers!r}")
        self.crossovers, self.sigma = cr, float(sigma)
        super().__init__(**kwargs)

    def get_proposal(self, s, c, random):
        c = np.concatenate(c, axis=0)
        ns, ndim = s.shape
        nc = len(c)
        first = random.randint(nc, size=ns)
        second = (first + 1 + random.randint(nc - 1, size=ns)) % nc  # a different walker
        diffs = c[second] - c[first]
        cr = self.crossovers[random.randint(len(self.crossovers), size=ns)]
        mask = random.rand(ns, ndim) < cr[:, None]
        empty = ~mask.any(axis=1)
        mask[empty, random.randint(ndim, size=int(empty.sum()))] = True
        moved = mask.sum(axis=1, keepdims=True)
        gamma = 2.38 / np.sqrt(2.0 * moved) * (1.0 + self.sigma * random.randn(ns, 1))
        return s + gamma * diffs * mask, np.zeros(ns)


class IndependenceMove(MHMove):
    """Independence proposals from a fixed defensive mixture of multivariate t's (see
    module docstring): the fitted one, and in a share ``wide`` of the draws the same t
    ``wide_scale`` times wider (Hesterberg's defensive importance sampling). Without the
    wide part a proposal fitted to an ensemble that has not yet spread over the
    posterior (the start's cluster, a few hundred steps in) proposes only that cluster:
    a walker out in a tail it does not cover is rarely moved by it, and half the steps
    pull walkers back to the cluster (measured on A3 at 1 Hz: the unidentified bearing
    damping's tail took 1,000 steps to fill instead of 500).

    The fitted part may itself be a mixture of ``k`` t's (``mean`` (k, ndim), ``cov``
    (k, ndim, ndim), ``weights`` (k,)), each with its own wide twin: :meth:`fit` with
    ``components > 1`` fits one by EM (:mod:`.mixture`).

    Parameters
    ----------
    mean : (ndim,) centre of the proposal, or (k, ndim) centres of its components.
    cov : (ndim, ndim) covariance it is fitted to (positive definite), or (k, ndim, ndim).
    weights : (k,) the components' shares (positive; normalised); default equal.
    dof : degrees of freedom of every t (``np.inf``: normals). Default 10.
    scale : factor on the covariances' square roots (default 1.1: a little wider).
    wide, wide_scale : share of the wide part and its width against the fitted one
        (defaults 0.2 and 3; ``wide=0``: the fitted t alone).
    scores : a :class:`.marginals.NormalScores` map z = T(x); the t's (mean, cov) then
        live in z, proposals are drawn there and mapped back, and the density carries
        T's Jacobian. Default None: the t's live in the sampler's coordinates.
    """

    def __init__(self, mean, cov, *, weights=None, dof: float = 10.0, scale: float = 1.1, wide: float = 0.2,
                 wide_scale: float = 3.0, scores: NormalScores | None = None):
        means = np.asarray(mean, dtype=float)
        covs = np.asarray(cov, dtype=float)
        if means.ndim == 1:
            means, covs = means[None], np.atleast_2d(covs)[None]
        k, d = means.shape if means.ndim == 2 else (0, 0)
        if means.ndim != 2 or covs.shape != (k, d, d):
            raise ValueError(f"mean and covariance do not match: {np.shape(mean)} and {np.shape(cov)}")
        w = np.ones(k) if weights is None else np.asarray(weights, dtype=float)
        if w.shape != (k,) or not np.all(w > 0) or not np.all(np.isfinite(w)):
            raise ValueError(f"weights must be {k} positive numbers, got {weights!r}")
        if not (dof > 0 and scale > 0 and wide_scale > 0):
            raise ValueError(f"degrees of freedom and scales must be positive, got {dof}, {scale} and {wide_scale}")
        if not 0.0 <= wide < 1.0:
            raise ValueError(f"the wide part's share must lie in [0, 1), got {wide}")
        if not (np.all(np.isfinite(means)) and np.all(np.isfinite(covs))):
            raise ValueError("the proposal's mean and covariance must be finite")
        self.means, self.weights = means, w / w.sum()
        self.dof, self.scale = float(dof), float(scale)
        self.wide, self.wide_scale = float(wide), float(wide_scale)
        if scores is not None and scores.ndim != d:
            raise ValueError(f"the normal-scores map has {scores.ndim} coordinates, the proposal {d}")
        self.scores = scores
        self.chols = np.linalg.cholesky(covs * self.scale ** 2)  # LinAlgError if not positive definite
        super().__init__(self._propose)

    @property
    def components(self) -> int:
        return len(self.weights)

    @property
    def mean(self) -> np.ndarray:
        """The centre of a one-component proposal."""
        self._one("mean")
        return self.means[0]

    @property
    def chol(self) -> np.ndarray:
        """The Cholesky factor (scaled) of a one-component proposal."""
        self._one("chol")
        return self.chols[0]

    def _one(self, what: str) -> None:
        if self.components != 1:
            raise AttributeError(f"a proposal of {self.components} components has no single {what}")

    @classmethod
    def fit(cls, draws, *, components: int = 1, seed: int = 0, max_draws: int = MIXTURE_DRAWS,
            knots: int | None = None, **kwargs) -> "IndependenceMove | None":
        """The move fitted to ``draws`` (n, ndim): by their mean and covariance, or with
        ``components > 1`` a normal mixture fitted by EM (seeded by ``seed``, on at most
        ``max_draws`` of them, evenly spaced) whose weights, means and covariances its
        t's take; with ``knots``, fitted in the draws' normal scores
        (:class:`.marginals.NormalScores` with that many knots). None where they cannot
        define one (fewer draws than dimensions, or a singular covariance); a mixture that
        cannot be fitted falls back to one t, and draws too few for a normal-scores map to
        the t's in their own coordinates."""
        draws = _usable(draws)
        if draws is None:
            return None
        if knots is not None:
            try:
                scores = NormalScores.fit(draws, knots)
            except ValueError:
                scores = None
            if scores is not None:
                return cls.fit(scores.forward(draws)[0], components=components, seed=seed, max_draws=max_draws,
                               scores=scores, **kwargs)
        if components > 1:
            step = max(1, -(-len(draws) // max_draws))
            try:
                w, m, c = fit_normal_mixture(draws[::step], components, seed=seed)
                return cls(m, c, weights=w, **kwargs)
            except (ValueError, np.linalg.LinAlgError):
                pass
        try:
            return cls(draws.mean(axis=0), np.cov(draws, rowvar=False), **kwargs)
        except np.linalg.LinAlgError:
            return None

    def _log_t(self, x, j: int, width: float) -> np.ndarray:
        """Log density of component ``j``'s t widened by ``width``, up to a constant common
        to every width and component (the t's normalisation less its determinant, which
        enters where there are several components)."""
        L = self.chols[j]
        z = np.linalg.solve(L, (np.atleast_2d(x) - self.means[j]).T) / width
        m2 = np.sum(z * z, axis=0)
        d = self.means.shape[1]
        core = -0.5 * m2 if np.isinf(self.dof) else -0.5 * (self.dof + d) * np.log1p(m2 / self.dof)
        out = core - d * np.log(width)
        if self.components > 1:
            out = out + np.log(self.weights[j]) - np.sum(np.log(np.diag(L)))
        return out

    def log_density(self, x) -> np.ndarray:
        """Log density of the proposal at the rows of ``x``, up to a constant."""
        if self.scores is not None:
            z, log_jac = self.scores.forward(x)
            return self._log_density(z) + log_jac
        return self._log_density(x)

    def _log_density(self, x) -> np.ndarray:
        """Log density of the t's (in z where there is a normal-scores map)."""
        parts = []
        for j in range(self.components):
            if self.wide == 0.0:
                parts.append(self._log_t(x, j, 1.0))
            else:
                parts.append(np.logaddexp(np.log1p(-self.wide) + self._log_t(x, j, 1.0),
                                          np.log(self.wide) + self._log_t(x, j, self.wide_scale)))
        return parts[0] if len(parts) == 1 else np.logaddexp.reduce(np.array(parts), axis=0)

    def _propose(self, coords, random):
        coords = np.asarray(coords, dtype=float)
        n = len(coords)
        z = random.randn(*coords.shape)
        if np.isfinite(self.dof):
            z = z / np.sqrt(random.chisquare(self.dof, size=n) / self.dof)[:, None]
        width = np.where(random.rand(n) < self.wide, self.wide_scale, 1.0)
        if self.components == 1:
            q = self.means[0] + (z * width[:, None]) @ self.chols[0].T
        else:
            j = np.minimum(np.searchsorted(np.cumsum(self.weights), random.rand(n), side="right"),
                           self.components - 1)
            q = self.means[j] + np.einsum("nij,nj->ni", self.chols[j], z * width[:, None])
        if self.scores is not None:
            q = self.scores.inverse(q)
        return q, self.log_density(coords) - self.log_density(q)


class BlockMove(MHMove):
    """Metropolis-within-Gibbs from a fitted normal law in normal scores: each walker
    picks a block of coordinates at random (its size drawn from ``sizes``, the
    coordinates uniformly among all) and proposes new values for them alone from the
    conditional law of that block given the walker's other coordinates, the rest kept.

    The law is a normal N(mean, cov) in z = T(x) (``scores``, :class:`.marginals.NormalScores`),
    the block's conditional normal widened by ``scale`` and, in a share ``wide`` of the
    proposals, by ``wide_scale`` more. Which coordinates move does not depend on the
    state, and the conditional law of the block given the others is the same before and
    after the move, so the Hastings factor is the ratio of the block's proposal densities
    (in x: with T's Jacobian for the block's coordinates) at the old and new values, and
    the move leaves any posterior invariant.

    A coordinate the records leave to its prior (the nut stiffness on its plateau) is
    proposed across its whole conditional range in one step without the other
    coordinates having to fit the proposal too, which a proposal in all coordinates at
    once needs: on the 9-record joint model's chain of ``studies/joint_mixing.py
    --variants scores`` (its first 1,745 steps; a normal fitted to steps 200-872, 150
    proposals per parameter from draws of steps 872-1,745, evaluated), one-coordinate
    proposals (scale 1.2, no wide part) were accepted 0.63-0.80 of the time for every
    shared parameter, the nut stiffness 0.63.
    """

    def __init__(self, mean, cov, scores: NormalScores, *, sizes=(1, 2, 3), scale: float = 1.2,
                 wide: float = 0.1, wide_scale: float = 3.0):
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
        self.mean, self.scores, self.sizes = mean, scores, sizes
        np.linalg.cholesky(cov)  # LinAlgError if not positive definite
        self.precision = np.linalg.inv(cov)
        self.scale, self.wide, self.wide_scale = float(scale), float(wide), float(wide_scale)
        super().__init__(self._propose)

    @classmethod
    def fit(cls, draws, *, knots: int | None = None, scores: NormalScores | None = None,
            **kwargs) -> "BlockMove | None":
        """The move fitted to ``draws`` (n, ndim): the mean and covariance of their normal
        scores, in the map ``scores`` if given (one already fitted to the same draws, such
        as an :class:`IndependenceMove`'s) or else in their map with ``knots`` knots; None
        where they define none."""
        if scores is None and knots is None:
            raise ValueError("a block move needs a normal-scores map or the knots to fit one")
        draws = _usable(draws)
        if draws is None:
            return None
        try:
            scores = scores if scores is not None else NormalScores.fit(draws, knots)
            z = scores.forward(draws)[0]
            return cls(z.mean(axis=0), np.cov(z, rowvar=False), scores, **kwargs)
        except (ValueError, np.linalg.LinAlgError):
            return None

    def _log_q(self, w) -> np.ndarray:
        """Log density of the block's proposal (the defensive pair of normals, up to a
        constant) at the rows of ``w`` (n, m), whitened by its conditional law."""
        r2 = np.sum(w ** 2, axis=1)
        m = w.shape[1]
        narrow = -0.5 * r2
        if self.wide == 0.0:
            return narrow
        wide = -0.5 * r2 / self.wide_scale ** 2 - m * np.log(self.wide_scale)
        return np.logaddexp(np.log1p(-self.wide) + narrow, np.log(self.wide) + wide)

    def _propose(self, coords, random):
        x = np.array(coords, dtype=float)
        n, d = x.shape
        z, jac_old = self.scores.forward(x)
        znew = z.copy()
        moved = np.zeros((n, d), dtype=bool)
        log_q = np.zeros(n)  # log q(old block) - log q(new block), in whitened block coordinates
        sizes = np.asarray(self.sizes)[random.randint(len(self.sizes), size=n)]
        for i in range(n):
            block = np.sort(random.choice(d, size=sizes[i], replace=False))
            rest = np.setdiff1d(np.arange(d), block)
            # the block's conditional normal given the rest, from the precision matrix
            cov_b = np.linalg.inv(self.precision[np.ix_(block, block)])
            mean_b = self.mean[block] - cov_b @ (self.precision[np.ix_(block, rest)] @ (z[i, rest] - self.mean[rest]))
            chol = np.linalg.cholesky(cov_b) * self.scale
            width = self.wide_scale if random.rand() < self.wide else 1.0
            w_new = width * random.randn(len(block))
            znew[i, block] = mean_b + chol @ w_new
            w_old = np.linalg.solve(chol, z[i, block] - mean_b)
            log_q[i] = self._log_q(w_old[None])[0] - self._log_q(w_new[None])[0]
            moved[i, block] = True
        q = np.where(moved, self.scores.inverse(znew), x)  # the rest kept exactly
        _, jac_new = self.scores.forward(q)  # the rest's slopes are the same in both
        return q, log_q + jac_old - jac_new
