"""Sampling with emcee: HDF5 checkpoints, resume, and a convergence loop.

The chain is written at every step, with the sampler's random state, to two HDF5 files
in turn (``chain.h5`` and ``chain.twin.h5``, see :mod:`.checkpoint`), so a run that is
killed, even inside a write, can be continued: running again adds only the missing
steps, keeps the steps already taken as they are, and gives the chain an uninterrupted
run gives. A checkpoint written for another model, record or number of walkers is
refused with a one-line error rather than overwritten; a damaged file is moved aside and
the run continues from its intact twin, or, with no intact copy left, stops with a
one-line error.

The walkers move in the model's sampler coordinates (:mod:`.coordinates`: by default
the impedance coordinates, with the posterior carried over by its Jacobian), and the
checkpoint holds them; everything read back from a run (:meth:`SamplerRun.chain`,
convergence, summaries) is in the model's parameters theta.

Convergence (documented defaults, :class:`Convergence`): emcee's integrated
autocorrelation time tau (``emcee.autocorr.integrated_time(tol=0)`` on the chain in
theta, the reported parameters) per parameter, checked every
``check_every`` steps, on the chain after its warm-up: its :func:`transient` (the steps
before the walkers reach equilibrium, none for a chain that starts there) or its first
``warmup`` share, whichever is longer; converged when the chain after the warm-up is
longer than ``n_tau`` times the largest tau (and than ``n_tau`` times the last check's,
if that was larger), tau grew by less than ``tau_rtol`` since the last check (a tau that
still grows with the chain is underestimated), and, after discarding 2 tau more, R-hat
< ``max_rhat`` and bulk ESS >= ``min_ess`` (arviz, treating walkers as chains: they are
not independent, so R-hat here is a check that no walker is stuck apart from the
others, not a proof). Or stops at ``max_steps``. The draws kept for the posterior
(:func:`.results.posterior_sample`) are the same: after the warm-up and 2 tau more.

Adaptation (documented defaults, :class:`Adaptation`): at every multiple of ``every``
steps, a multivariate t (or a mixture of ``components`` t's, by EM) is fitted to the
chain so far after its transient, in its normal scores (``knots``; or in sampler
coordinates), and :class:`.moves.IndependenceMove` proposes from it, with
:class:`.moves.BlockMove` from a normal in the same scores in ``blocks`` of their
share, in ``weight`` of the following steps, the ensemble moves in the rest. The
proposals change only at those steps and are fitted to a growing chain (diminishing
adaptation, Roberts and Rosenthal 2007); between two of them they are fixed and every
move leaves the posterior invariant.
A continued chain refits from the same stored steps, so it is the chain an
uninterrupted run gives.
"""

from __future__ import annotations

import math
import multiprocessing
import signal
from dataclasses import dataclass

import emcee
import numpy as np

from .checkpoint import WRITE_SECONDS, CheckpointError, new_checkpoint, open_checkpoint
from .coordinates import Coordinates, default_coordinates
from .identity import run_identity
from .marginals import KNOTS
from .model import PosteriorModel
from .moves import BlockMove, IndependenceMove, NutRidgeMove, ridge_indices
from .optimize import find_start, laplace_ensemble, sse

__all__ = ["Convergence", "Adaptation", "CheckpointError", "SamplerRun", "SamplerStatus", "run_sampler",
           "check_run_options", "default_moves", "transient"]

#: Stretch and differential-evolution moves: DE moves travel along the friction ridges.
DEFAULT_MOVES = [(emcee.moves.DEMove(), 0.6), (emcee.moves.DESnookerMove(), 0.1), (emcee.moves.StretchMove(), 0.3)]

#: Share of a chain left out as warm-up before its convergence is judged and its draws
#: kept (:class:`Convergence`), unless its transient is longer.
WARMUP = 1 / 3

#: Share of the steps that jump along the nut's ridge (:class:`.moves.NutRidgeMove`)
#: in models that have one; the other moves keep their proportions in the rest.
RIDGE_WEIGHT = 0.2


def default_moves(model, ridge_weight: float = RIDGE_WEIGHT, coordinates: Coordinates | None = None) -> list:
    """emcee's moves for ``model``: :data:`DEFAULT_MOVES`, and where the walkers move in
    theta itself (``coordinates`` None or "physical") and the model samples b, k_n and
    c_n in log scale, :class:`.moves.NutRidgeMove` in ``ridge_weight`` of the steps (0:
    none). The impedance coordinates make the nut's ridge a coordinate axis, so there
    the move has nothing to do."""
    if not 0.0 <= ridge_weight < 1.0:
        raise ValueError(f"ridge move weight must lie in [0, 1), got {ridge_weight}")
    if coordinates is not None and coordinates.kind != "physical":
        return list(DEFAULT_MOVES)
    idx = ridge_indices(model.names, [model.all_priors[n].log_scale for n in model.names])
    if idx is None or ridge_weight == 0.0:
        return list(DEFAULT_MOVES)
    k, c, b = idx
    return [(m, w * (1.0 - ridge_weight)) for m, w in DEFAULT_MOVES] + [(NutRidgeMove(k, c, b), ridge_weight)]


@dataclass(frozen=True)
class SamplerStatus:
    """What a run knows of itself, for progress reports: told once when it starts
    (``resumed_at`` > 0 when it continues a checkpoint) and after each convergence check.

    ``tau_max``: the largest autocorrelation time, steps (NaN before the first check);
    ``acceptance``: the walkers' mean acceptance fraction; ``steps_needed``: the steps
    still needed before the chain after its warm-up is ``n_tau`` tau long (an estimate,
    None before tau is known); ``target``: the steps asked for (None: until converged).
    """

    iteration: int
    resumed_at: int
    target: int | None
    tau_max: float = math.nan
    acceptance: float = math.nan
    steps_needed: int | None = None


def default_walkers(ndim: int) -> int:
    """Default walkers: twice the parameters plus two (24 for the two-port model's 11).
    A converged run costs walkers x 50 tau evaluations, so the default is near the
    fewest the moves need (2 ndim), with a margin; more walkers is an option."""
    return 2 * ndim + 2


@dataclass(frozen=True)
class Convergence:
    """When an open-ended run stops (see module docstring).

    ``check_every`` is 250 steps (the adaptation's period): against 500, a
    chain stops on average 125 steps nearer the point where the rule first holds: the
    full study's 27-record joint chain (``results/joint-rerun``), checked again step by
    step from its checkpoint, meets the rule at 3,250 steps where it stopped at 3,500.

    ``warmup`` (default :data:`WARMUP`, a third; 0 leaves out only the transient): the share of the chain left out before tau, R-hat and ESS
    are computed, and from the kept draws. The fitted moves learn the posterior from the
    chain itself, so its first several hundred steps mix several times slower than the
    rest: on A3 at 1 Hz (5,000 steps, seed 0) tau over the whole chain was 81 steps at
    4,250 and over its last two thirds 30 at 2,500, and tau taken over everything
    counted that early stretch against the chain for as long as it ran. The chain kept
    must still be 50 times its own tau, so a chain whose warm-up is longer than a third
    waits until it is not (``benchmarks/bench_warmup.py`` replays both rules on the same
    chains).
    """

    n_tau: float = 50.0
    tau_rtol: float = 0.05
    max_rhat: float = 1.05
    min_ess: float = 400.0
    check_every: int = 250
    max_steps: int = 20_000
    warmup: float = WARMUP

    def __post_init__(self) -> None:
        if not 0.0 <= self.warmup <= 0.5:
            raise ValueError(f"convergence setting warmup (a share of the chain) must lie in [0, 0.5], "
                             f"got {self.warmup}")
        for name in ("n_tau", "tau_rtol", "max_rhat", "min_ess"):
            if not getattr(self, name) > 0:
                raise ValueError(f"convergence setting {name} must be positive, got {getattr(self, name)}")
        for name in ("check_every", "max_steps"):
            value = getattr(self, name)
            if not (isinstance(value, int) and value >= 1):
                raise ValueError(f"convergence setting {name} must be a positive whole number, got {value!r}")


@dataclass(frozen=True)
class Adaptation:
    """The fitted moves' share of the steps, and when they are refitted (see module
    docstring). By default the independence move's t is fitted in the chain's normal
    scores (:mod:`.marginals`), and half of the fitted moves' share goes to block moves
    (:class:`.moves.BlockMove`) from a normal in the same scores; ``knots=None,
    blocks=0`` is one t in the sampler's coordinates, the earlier default. Measured side by side with it (same starts and seeds): on the joint model
    of 9 records (``studies/joint_mixing.py``, 3,000 steps) the largest autocorrelation
    time over the last four fifths fell from 115.0 to 30.0 steps; on single records to
    convergence (``benchmarks/bench_adaptation.py``), A3 at 1 Hz took 4,500 steps
    against 8,000, B2 at 1 Hz 2,000 against 1,500. Earlier, on A3 at 1 Hz (3,000 steps
    from the optimum's ensemble, 24 walkers, one seed): the largest autocorrelation time
    over steps 1,000-3,000 was 96.3 steps with the ensemble moves alone, 44.8 with the
    fitted t alone (``wide=0``) and 38.4 with the t and its wide part.

    Attributes
    ----------
    weight : share of the steps that propose from the fitted t once there is one
        (default 0.5); the ensemble moves keep their proportions in the rest.
    every : the proposal is refitted at every multiple of this many steps (default 250),
        from the chain's steps after its transient, if at least ``every // 2`` of them.
    dof, scale : the t's degrees of freedom and the factor on its covariance's square
        root (:class:`.moves.IndependenceMove`; defaults 10 and 1.1).
    wide, wide_scale : share of proposals drawn from the same t ``wide_scale`` times
        wider (defaults 0.2 and 3; see :class:`.moves.IndependenceMove`).
    components : the t's fitted as one (default 1) or, above 1, as a mixture of that
        many, by EM on the chain (``moves.IndependenceMove.fit``).
    knots : the t's fitted in the chain's normal scores (:mod:`.marginals`) with this
        many knots per coordinate (default 200), or (None) in the sampler's coordinates.
    blocks : share of ``weight`` given to a :class:`.moves.BlockMove` fitted in the
        same normal scores (needs ``knots``; default 0.5; 0: none).
    """

    weight: float = 0.5
    every: int = 250
    dof: float = 10.0
    scale: float = 1.1
    wide: float = 0.2
    wide_scale: float = 3.0
    components: int = 1
    knots: int | None = KNOTS
    blocks: float = 0.5

    def __post_init__(self) -> None:
        if not 0.0 <= self.blocks < 1.0:
            raise ValueError(f"adaptation's block share must lie in [0, 1), got {self.blocks}")
        if self.blocks > 0.0 and self.knots is None:
            raise ValueError("adaptation block moves are fitted in normal scores: give knots too")
        if self.knots is not None and not (isinstance(self.knots, int) and self.knots >= 4):
            raise ValueError(f"adaptation knots must be a whole number of at least 4 or None, got {self.knots!r}")
        if not (isinstance(self.components, int) and self.components >= 1):
            raise ValueError(f"adaptation components must be a positive whole number, got {self.components!r}")
        if not 0.0 < self.weight < 1.0:
            raise ValueError(f"adaptation weight must lie in (0, 1), got {self.weight}")
        if not (isinstance(self.every, int) and self.every >= 2):
            raise ValueError(f"adaptation period must be a whole number of at least 2 steps, got {self.every!r}")
        if not (self.dof > 0 and self.scale > 0 and self.wide_scale > 0):
            raise ValueError(f"adaptation dof and scales must be positive, got {self.dof}, {self.scale} "
                             f"and {self.wide_scale}")
        if not 0.0 <= self.wide < 1.0:
            raise ValueError(f"adaptation's wide share must lie in [0, 1), got {self.wide}")

    def fit(self, chain: np.ndarray, log_prob: np.ndarray) -> tuple[IndependenceMove | None, BlockMove | None]:
        """The moves fitted to ``chain`` (steps, walkers, ndim; sampler coordinates) after
        its :func:`transient` (from ``log_prob``, steps x walkers): the independence move,
        and with ``blocks`` the block move in the same normal-scores map (fitted once, to
        the same draws). Each None where fewer than ``every // 2`` steps follow the
        transient or the draws define none."""
        skip = transient(log_prob)
        if len(chain) - skip < self.every // 2:
            return None, None
        draws = chain[skip:].reshape(-1, chain.shape[-1])
        proposal = IndependenceMove.fit(draws, components=self.components, knots=self.knots, dof=self.dof,
                                        scale=self.scale, wide=self.wide, wide_scale=self.wide_scale)
        if self.blocks == 0.0:
            return proposal, None
        scores = proposal.scores if proposal is not None else None
        return proposal, BlockMove.fit(draws, knots=self.knots, scores=scores)

    def moves(self, base: list, proposal: IndependenceMove | None, block: BlockMove | None = None) -> list:
        """``base`` moves, with ``proposal`` (and ``block``, in ``blocks`` of their share)
        in ``weight`` of the steps where there is one."""
        if proposal is None:
            return list(base)
        fitted = [(proposal, self.weight)] if block is None else [
            (proposal, self.weight * (1.0 - self.blocks)), (block, self.weight * self.blocks)]
        return [(m, w * (1.0 - self.weight)) for m, w in base] + fitted

    def describe(self) -> str:
        law = "t" if self.components == 1 else f"mixture of {self.components} t's fitted by EM"
        if self.knots is not None:
            law += f" in normal scores ({self.knots} knots)"
        if self.blocks > 0.0:
            law += f"; {self.blocks:g} of its share to block moves from a normal in the same scores"
        return (f"IndependenceMove {self.weight:.3g} ({law}, dof {self.dof:g}, scale {self.scale:g}, "
                f"{self.wide:g} of it {self.wide_scale:g} x wider, refitted every {self.every} steps; "
                f"the others scaled by {1 - self.weight:.3g} once fitted)")


@dataclass
class SamplerRun:
    """What a run produced: the sampler (chain in its backend, in sampler coordinates)
    and convergence facts (in theta)."""

    sampler: emcee.EnsembleSampler
    converged: bool
    tau: np.ndarray
    reason: str
    start_theta: np.ndarray | None = None
    #: what was done to continue a damaged checkpoint ("" when nothing was)
    recovered: str = ""
    #: the moves of this run and their weights ("DEMove 0.48", ...)
    moves: tuple = ()
    #: where the walkers moved (``coordinates.describe()`` names them)
    coordinates: Coordinates | None = None
    #: steps before the walkers reached equilibrium (:func:`transient`)
    transient: int = 0
    #: steps the checkpoint held when this run began (0 for a new chain)
    resumed_at: int = 0
    #: steps left out of tau, R-hat, ESS and the kept draws: the transient or the
    #: convergence rule's warm-up share of the chain, whichever is longer
    warmup: int = 0

    @property
    def iteration(self) -> int:
        return self.sampler.iteration

    def chain(self, discard: int = 0, thin: int = 1) -> np.ndarray:
        """The chain in theta, shape (steps, walkers, ndim)."""
        return _theta_chain(self.sampler, self.coordinates, discard, thin)

    def log_prob(self, discard: int = 0, thin: int = 1) -> np.ndarray:
        """The log posterior in theta (without the coordinates' Jacobian), (steps, walkers)."""
        lp = self.sampler.get_log_prob(discard=discard, thin=thin)
        if self.coordinates is None:
            return lp
        return lp - self.coordinates.log_jacobian(self.sampler.get_chain(discard=discard, thin=thin))


def _theta_chain(sampler, coords, discard=0, thin=1):
    chain = sampler.get_chain(discard=discard, thin=thin)
    return chain if coords is None else coords.to_theta(chain)


# The log-probability for worker processes: a top-level function over a module global set
# before the pool forks, so that only the parameter vector is pickled per call.
_MODEL: PosteriorModel | None = None
_COORDS: Coordinates | None = None
_POOL = None


def _model_log_prob(theta):
    return _MODEL.log_prob(theta)


def _log_prob_many(us):
    """The target in sampler coordinates for a batch of walkers (emcee's ``vectorize``):
    log p(theta(u)) + log |d theta / d u|, as a list of (value, phi). The coordinates'
    map is taken for the whole batch at once (numpy over the walkers: 0.13 ms for 12 walkers
    on A3 at 1 Hz against 0.86 ms walker by walker, medians of 200), the model
    walker by walker, on the worker processes if any."""
    us = np.atleast_2d(np.asarray(us, dtype=float))
    thetas, logj = _COORDS.transform(us)
    logj = np.broadcast_to(logj, us.shape[:1])
    good = np.flatnonzero(np.all(np.isfinite(thetas), axis=1) & np.isfinite(logj))
    points = [thetas[i] for i in good]
    # one walker per task: the pool's default chunks (a quarter of a worker's share each)
    # left one worker a chunk behind at the end of every batch (21 walkers on 2 workers:
    # 12 against 9)
    got = _POOL.map(_model_log_prob, points, chunksize=1) if _POOL is not None else map(_model_log_prob, points)
    out = [(-np.inf, np.nan)] * len(us)
    for i, (lp, phi) in zip(good, got):
        if np.isfinite(lp):
            out[i] = (lp + float(logj[i]), phi)
    return out


def _log_prob(u):
    """The target at one point u (see :func:`_log_prob_many`)."""
    return _log_prob_many(np.asarray(u, dtype=float)[None, :])[0]


def _ignore_interrupt():
    """Worker processes leave Ctrl-C (SIGINT, sent to the whole process group) to the
    parent, which stops the run and ends them: a worker that died of it mid-task would
    leave the parent waiting for its result for ever."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


def _sse(phys):
    return sse(_MODEL, phys)


def transient(log_prob: np.ndarray) -> int:
    """Steps at the start of a chain before its walkers reach equilibrium: the first step
    at which the walkers' median log posterior comes within three robust spreads (at
    least 1 nat) of its median over the chain's last half. 0 for a chain that starts in
    equilibrium; a start in a worse basin (the full study's A2 at 0.5 Hz: 2,000 steps
    about 440 nats below) would otherwise inflate tau, estimated on the whole chain, by
    an order of magnitude. ``log_prob``: shape (steps, walkers)."""
    m = np.median(np.asarray(log_prob, dtype=float), axis=1)
    if len(m) < 4:
        return 0
    late = m[len(m) // 2:]
    ref = np.median(late)
    spread = max(3.0 * 1.4826 * np.median(np.abs(late - ref)), 1.0)
    return int(np.argmax(m >= ref - spread))


@dataclass(frozen=True)
class _Check:
    """One convergence check: tau, R-hat and ESS after the warm-up (in theta), the
    warm-up's steps and the transient's among them."""

    tau: np.ndarray
    rhat: np.ndarray
    ess: np.ndarray
    warmup: int
    transient: int


def _diagnostics(sampler, coords, conv: Convergence, upto: int | None = None, rhat_if=None) -> _Check:
    """:func:`_check_chain` of the sampler's chain in theta (the reported parameters), of
    its first ``upto`` steps if given."""
    n = sampler.iteration if upto is None else upto
    return _check_chain(_theta_chain(sampler, coords)[:n], sampler.get_log_prob()[:n], conv, rhat_if)


def _check_chain(chain: np.ndarray, log_prob: np.ndarray, conv: Convergence, rhat_if=None) -> _Check:
    """tau, R-hat and bulk ESS of ``chain`` (steps, walkers, ndim) after its warm-up (its
    :func:`transient` from ``log_prob``, at most half the chain, or ``conv.warmup`` of
    it, whichever is longer).

    ``rhat_if(steps after the warm-up, tau)``: where it says no, R-hat (inf) and ESS
    (0) are not computed. arviz takes about half a second per thousand steps of a
    single-record chain, a tenth of the sampling between two checks of a long chain,
    and they decide nothing while the chain is still too short for its tau."""
    from .diagnostics import rhat_ess

    n = len(chain)
    skip = min(transient(log_prob), n // 2)
    warm = max(skip, int(conv.warmup * n))
    with np.errstate(invalid="ignore", divide="ignore"):  # a parameter that never moved: tau NaN, handled below
        tau = emcee.autocorr.integrated_time(chain[warm:], tol=0)
    if rhat_if is not None and not rhat_if(n - warm, tau):
        return _Check(tau, np.full(len(tau), np.inf), np.zeros(len(tau)), warm, skip)
    burn = warm + (int(2 * np.nanmax(tau)) if np.all(np.isfinite(tau)) else (n - warm) // 2)
    rhat, ess = rhat_ess(chain[min(burn, n - 2):])
    return _Check(tau, rhat, ess, warm, skip)


def check_run_options(ndim: int, nwalkers: int | None, steps: int | None) -> int:
    """Validate walkers and steps; return the number of walkers (default
    :func:`default_walkers`)."""
    nwalkers = nwalkers or default_walkers(ndim)
    if nwalkers < 2 * ndim or nwalkers % 2:
        raise ValueError(f"walkers must be even and at least {2 * ndim} (twice the parameters), got {nwalkers}")
    if steps is not None and steps < 1:
        raise ValueError(f"steps must be a positive number, got {steps}")
    return nwalkers


def run_sampler(
    model: PosteriorModel,
    checkpoint,
    *,
    nwalkers: int | None = None,
    steps: int | None = None,
    seed: int = 0,
    fresh: bool = False,
    processes: int = 1,
    convergence: Convergence | None = None,
    moves=None,
    progress=None,
    report=None,
    start=None,
    coordinates: str | Coordinates = "impedance",
    adaptation: Adaptation | None = Adaptation(),
    checkpoint_seconds: float = WRITE_SECONDS,
) -> SamplerRun:
    """Sample the posterior of ``model`` into the HDF5 file ``checkpoint``.

    Parameters
    ----------
    nwalkers : walkers (default: twice the parameters plus two).
    steps : run exactly this many steps in all (continuing a checkpoint adds only what is
        missing); None runs until converged or ``convergence.max_steps``.
    seed : seeds the optimiser, the initial ensemble and the sampler's random state.
    fresh : start over even if the checkpoint holds steps.
    processes : worker processes evaluating walkers in parallel (1: none).
    progress : callable(iteration, target or None), called after each step.
    report : callable(:class:`SamplerStatus`), called when the run starts and after each
        convergence check.
    start : optional (theta, log prob) to start from instead of the optimiser, or a
        callable returning one, called only when the chain starts over (a continued
        checkpoint needs no start); the walkers are drawn around it by
        ``optimize.laplace_ensemble``.
    coordinates : where the walkers move: a :class:`.coordinates.Coordinates` or the name
        of one (``coordinates.COORDINATES``; default "impedance", which falls back to
        "unconstrained" for models without an impedance map). A checkpoint continues
        only in the coordinates it was written in.
    adaptation : the fitted independence move (:class:`Adaptation`); None: the ensemble
        moves alone.
    checkpoint_seconds : steps are written to the checkpoint at most this many seconds
        apart (``checkpoint.WRITE_SECONDS``; 0: every step); a kill loses at most that.
    """
    from pathlib import Path

    global _MODEL, _COORDS, _POOL
    conv = convergence or Convergence()
    checkpoint = Path(checkpoint)
    nwalkers = check_run_options(model.ndim, nwalkers, steps)
    coords = coordinates if isinstance(coordinates, Coordinates) else default_coordinates(model, coordinates)
    moves = moves or default_moves(model, coordinates=coords)
    identity = run_identity(model, coords, adaptation, moves, nwalkers)
    kernel = adaptation.describe() if adaptation is not None else None
    opened = open_checkpoint(checkpoint, identity=identity, fresh=fresh, write_seconds=checkpoint_seconds)
    recovered = opened.recovered if opened else ""
    if opened is None or opened.steps == 0:
        backend = new_checkpoint(checkpoint, identity=identity, write_seconds=checkpoint_seconds)
        done = 0
    else:
        backend, done = opened.backend, opened.steps
    if report:
        report(SamplerStatus(done, done, steps))
    _MODEL, _COORDS = model, coords
    ensemble = tuple(f"{type(m).__name__} {w:.3g}" for m, w in moves)
    pool = multiprocessing.get_context("fork").Pool(processes, initializer=_ignore_interrupt) if processes > 1 else None
    _POOL = pool
    fitted: dict[int, tuple[IndependenceMove | None, BlockMove | None]] = {}

    def used() -> tuple:
        """The moves the chain's steps used: the fitted t's only where one was fitted
        (at least one refit had enough steps after the transient)."""
        proposed = any(m[0] is not None for m in fitted.values())
        return ensemble + ((kernel,) if adaptation is not None and proposed else ())

    def new_sampler(step: int) -> emcee.EnsembleSampler:
        """The sampler for the steps from ``step`` to the next adaptation: its moves hold the
        proposal fitted at the last multiple of ``adaptation.every`` at or before it."""
        chunk_moves = moves
        if adaptation is not None:
            at = (step // adaptation.every) * adaptation.every
            if at > 0 and at not in fitted:
                chain, log_prob = backend.get_chain()[:at], backend.get_log_prob()[:at]
                fitted[at] = adaptation.fit(chain, log_prob)
            chunk_moves = adaptation.moves(moves, *fitted.get(at, (None, None)))
        return emcee.EnsembleSampler(nwalkers, model.ndim, _log_prob_many, vectorize=True, moves=chunk_moves,
                                     backend=backend, blobs_dtype=float)

    try:
        sampler = new_sampler(done)
        start_theta = None
        if done == 0:
            rng = np.random.default_rng(seed)
            if start is None:
                sse_many = (lambda xs: pool.map(_sse, xs)) if pool is not None else None
                start = find_start(model, rng, sse_many=sse_many)
            elif callable(start):
                start = start()
            start_theta = np.asarray(start[0], dtype=float)
            if not math.isfinite(model.log_prob(start_theta)[0]):
                raise ValueError("no parameters within the priors reproduce this record (the best start found "
                                 "has zero posterior density): check its columns, units and masses with "
                                 "bayes-inerter inspect, and the model")
            if not np.all(np.isfinite(coords.to_u(start_theta))):
                advice = ("use --coordinates unconstrained, which covers the whole prior"
                          if coords.kind == "impedance" else "check the record and the priors")
                raise ValueError(f"the start lies outside the {coords.kind} coordinates' domain; {advice}")
            # a walker drawn outside the coordinates' domain is drawn again
            walkers, _ = laplace_ensemble(model, start_theta, nwalkers, rng,
                                          accept=lambda t: bool(np.all(np.isfinite(coords.to_u(t)))))
            state = emcee.State(coords.to_u(walkers), random_state=np.random.RandomState(seed).get_state())
        else:
            # continue from the checkpoint's last state, with its random state
            state = backend.get_last_sample()

        def advance(until: int, target) -> None:
            """Sample up to step ``until``, in pieces that end where the proposal is refitted,
            each with the sampler :func:`new_sampler` gives for its first step."""
            nonlocal sampler, state
            while sampler.iteration < until:
                step = sampler.iteration
                end = until if adaptation is None else min(until, (step // adaptation.every + 1) * adaptation.every)
                sampler = new_sampler(step)
                for _ in sampler.sample(state, iterations=end - step, store=True):
                    if progress:
                        progress(sampler.iteration, target)
                backend.flush()
                state = sampler.get_last_sample()

        def finish(check: _Check, ok: bool) -> SamplerRun:
            reason = "converged" if ok else _why_not(sampler.iteration, check, conv)
            return SamplerRun(sampler, ok, check.tau, reason, start_theta, recovered, used(), coords,
                              check.transient, done, check.warmup)

        if steps is not None:
            advance(steps, steps)
            check = _diagnostics(sampler, coords, conv)
            return finish(check, _is_converged(sampler.iteration - check.warmup, check.tau, None, check.rhat,
                                               check.ess, conv))
        # Checks fall on multiples of check_every, so that a continued chain is checked
        # (and stops) where an uninterrupted run would be; a continued chain takes the
        # tau of that run's previous check from the stored chain, and one that stands
        # on a check is checked before it samples more (a converged chain comes back
        # as it is).
        previous = None
        last = ((done - 1) // conv.check_every) * conv.check_every if done else 0
        if last > 0:
            previous = _diagnostics(sampler, coords, conv, upto=last, rhat_if=lambda *_: False).tau
        check_now = done > 0 and done % conv.check_every == 0
        while True:
            chunk = 0 if check_now else min(conv.check_every - sampler.iteration % conv.check_every,
                                            conv.max_steps - sampler.iteration)
            check_now = False
            if chunk > 0:
                advance(sampler.iteration + chunk, None)
            last_check = sampler.iteration >= conv.max_steps  # its message names R-hat and ESS too
            check = _diagnostics(
                sampler, coords, conv, rhat_if=lambda n, t: last_check or _tau_settled(n, t, previous, conv))
            if report:
                report(_status(sampler, check, done, conv))
            if _is_converged(sampler.iteration - check.warmup, check.tau, previous, check.rhat, check.ess, conv):
                return finish(check, True)
            if sampler.iteration >= conv.max_steps:
                return finish(check, False)
            previous = check.tau
    finally:
        if pool is not None:  # nothing is left to compute; after Ctrl-C a task may still be running
            pool.terminate()
            pool.join()
        _MODEL, _COORDS, _POOL = None, None, None
        try:  # a run stopped by Ctrl-C or an error: bring the twin up to date if possible
            backend.flush()
        except OSError:  # chain.h5 holds every step; the twin is only behind
            pass


def _status(sampler, check, done: int, conv: Convergence) -> SamplerStatus:
    """The run's :class:`SamplerStatus` after a convergence check."""
    n = sampler.iteration
    tau_max = float(np.max(check.tau)) if np.all(np.isfinite(check.tau)) else math.nan
    needed = None
    if math.isfinite(tau_max):  # the warm-up takes its share of the longer chain too
        needed = max(0, math.ceil(conv.n_tau * tau_max / (1.0 - conv.warmup)) - n, check.warmup + math.ceil(
            conv.n_tau * tau_max) - n)
    return SamplerStatus(n, done, None, tau_max, float(np.mean(sampler.acceptance_fraction)), needed)


def _tau_settled(iteration, tau, previous, conv: Convergence) -> bool:
    """The autocorrelation part of the rule: ``iteration`` (the chain's steps after its
    warm-up) at least ``n_tau`` tau, and tau settled since the ``previous`` check."""
    if not np.all(np.isfinite(tau)):
        return False
    if iteration < conv.n_tau * np.max(tau):
        return False
    if previous is not None and np.all(np.isfinite(previous)):
        # a tau that grows is not yet to be trusted; one that falls (an early stretch of
        # slow exploration weighing less as the chain grows) is, but the chain must also
        # be long enough for the last check's larger estimate
        if np.max((tau - previous) / previous) > conv.tau_rtol or iteration < conv.n_tau * np.max(previous):
            return False
    return True


def _is_converged(iteration, tau, previous, rhat, ess, conv: Convergence) -> bool:
    """``iteration``: the chain's steps after its warm-up."""
    if not _tau_settled(iteration, tau, previous, conv):
        return False
    return bool(np.nanmax(rhat) < conv.max_rhat and np.nanmin(ess) >= conv.min_ess)


def _why_not(iteration, check: _Check, conv: Convergence) -> str:
    tau, rhat, ess, skip = check.tau, check.rhat, check.ess, check.warmup
    parts = []
    if np.all(np.isfinite(tau)):
        need = conv.n_tau * np.max(tau)
        if iteration - skip < need:
            after = f" after a warm-up of {skip}" if skip else ""
            parts.append(f"chain of {iteration - skip} steps{after} is shorter than {conv.n_tau:g} tau = {need:.0f}")
    else:
        parts.append("autocorrelation time not estimable")
    if not np.nanmax(rhat) < conv.max_rhat:
        parts.append(f"max R-hat {np.nanmax(rhat):.3f} >= {conv.max_rhat}")
    if not np.nanmin(ess) >= conv.min_ess:
        parts.append(f"min bulk ESS {np.nanmin(ess):.0f} < {conv.min_ess:g}")
    return "not converged: " + ("; ".join(parts) if parts else "tau still growing, or the chain shorter than "
                                f"{conv.n_tau:g} times the last check's tau")
