"""Sampling with emcee: a step-by-step generator, HDF5 checkpoints, resume, and a
convergence loop.

:func:`sample` is the sampler itself, in emcee's shape: a generator that yields the
walkers' state after each step and stores it in the checkpoint, with the moves that
:class:`.adaptation.Schedule` gives each stretch of the run. :func:`run_sampler` is a
thin loop over it: it opens or starts the checkpoint, draws the first walkers, and
stops after ``steps`` or where :class:`.convergence.Monitor` finds the chain converged.

The chain is written at every step, with the sampler's random state, to two HDF5 files
in turn (``chain.h5`` and ``chain.twin.h5``, see :mod:`.checkpoint`), so a run that is
killed, even inside a write, can be continued: running again adds only the missing
steps, keeps the steps already taken as they are, and gives the chain an uninterrupted
run gives. A checkpoint written for another model, record or number of walkers is
refused with a one-line error rather than overwritten; a damaged file is moved aside and
the run continues from its intact twin, or, with no intact copy left, stops with a
one-line error.

The walkers move in the model's sampler coordinates (:mod:`.coordinates`: by default
the impedance coordinates, with the posterior carried over by its Jacobian,
:class:`.target.Target`), and the checkpoint holds them; everything read back from a
run (:meth:`SamplerRun.chain`, convergence, summaries) is in the model's parameters
theta. The convergence rule: :mod:`.convergence`; the fitted moves: :mod:`.adaptation`.
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Iterator

import emcee
import numpy as np

from ...executor import Executor, interrupt_raised, interrupts_held, make_executor
from .adaptation import Adaptation, Schedule
from .checkpoint import WRITE_SECONDS, CheckpointError, new_checkpoint, open_checkpoint, stored_identity
from .convergence import (WARMUP, Check, Convergence, Monitor, check_chain, is_converged, steps_for, transient,
                          why_not)
from .coordinates import Coordinates, continue_at, default_coordinates, reference_tolerance
from .identity import run_identity
from ..posterior.model import PosteriorModel
from .moves import NutRidgeMove, ridge_indices
from .optimize import find_start, held_modes, laplace_ensemble, mirrored_modes
from .target import Target, objective_at, on_model
from .tempering import Tempering, replica_trajectories, sample_tempered, swap_rates

__all__ = ["Convergence", "Adaptation", "Tempering", "CheckpointError", "SamplerRun", "SamplerStatus", "sample",
           "run_sampler", "check_run_options", "default_moves", "default_walkers", "transient", "WARMUP",
           "START_PHASES"]

#: The phases of a new chain's start that ``SamplerRun.start_seconds`` times: the
#: optimiser's search for the start (``optimize.find_start``, with the likelihood's
#: reference point), the modes its walkers are shared among (``optimize.mirrored_modes``
#: and ``optimize.held_modes``), and the initial ensemble drawn around each
#: (``optimize.laplace_ensemble``).
START_PHASES = ("search", "modes", "ensemble")

#: Stretch and differential-evolution moves: DE moves travel along the friction ridges.
DEFAULT_MOVES = [(emcee.moves.DEMove(), 0.6), (emcee.moves.DESnookerMove(), 0.1), (emcee.moves.StretchMove(), 0.3)]

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
    #: the model the chain sampled: the one given, with its likelihood's reference point
    #: where it takes one (``PosteriorModel.with_reference``)
    model: object = None
    #: the tempering ladder (:class:`.tempering.Tempering`; None: none)
    tempering: Tempering | None = None
    #: each adjacent pair of temperatures' share of accepted swaps over the whole chain
    swap_rates: tuple = ()
    #: seconds of a new chain's start, by phase (:data:`START_PHASES`); empty where the
    #: run continued a checkpoint
    start_seconds: dict = field(default_factory=dict)
    #: the replicas' own tau (theta) where the rule read it (``Convergence.replicas``;
    #: ``tau`` is then each parameter's larger of it and the posterior's slots'), else None
    replica_tau: np.ndarray | None = None

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


def check_run_options(ndim: int, nwalkers: int | None, steps: int | None) -> int:
    """Validate walkers and steps; return the number of walkers (default
    :func:`default_walkers`)."""
    nwalkers = nwalkers or default_walkers(ndim)
    if nwalkers < 2 * ndim or nwalkers % 2:
        raise ValueError(f"walkers must be even and at least {2 * ndim} (twice the parameters), got {nwalkers}")
    if steps is not None and steps < 1:
        raise ValueError(f"steps must be a positive number, got {steps}")
    return nwalkers


def sample(target: Target, backend, state: emcee.State, *, schedule: Schedule, iterations: int,
           executor: Executor | None = None) -> Iterator[emcee.State]:
    """Yield the walkers' state after each of ``iterations`` steps from ``state`` (the
    back end's last step, or the first walkers), storing each step in ``backend``.

    Each stretch of ``schedule`` runs with its moves on an emcee sampler of its own,
    which goes on with the state's random state; the checkpoint's twin is brought up to
    date at the end of each stretch. ``executor``: where the walkers are evaluated (made
    with ``target`` as its state; None: here). Ctrl-C comes out between steps, after the
    step it came in is stored (:func:`...executor.interrupts_held`)."""
    nwalkers, ndim = np.shape(state.coords)
    log_prob = functools.partial(target.batch, executor=executor)
    until = backend.iteration + iterations
    while backend.iteration < until:
        step = backend.iteration
        end = min(until, schedule.end_of_stretch(step))
        sampler = emcee.EnsembleSampler(nwalkers, ndim, log_prob, vectorize=True, moves=schedule.moves_at(
            step, backend), backend=backend, blobs_dtype=float)
        steps = sampler.sample(state, iterations=end - step, store=True)
        while True:
            with interrupts_held():
                got = next(steps, None)
            if got is None:
                break
            yield got
        with interrupts_held():
            backend.flush()
        state = backend.get_last_sample()


def run_sampler(model: PosteriorModel, checkpoint, *, nwalkers: int | None = None, steps: int | None = None,
                seed: int = 0, fresh: bool = False, processes: int = 1, convergence: Convergence | None = None,
                moves=None, progress=None, report=None, start=None, coordinates: str | Coordinates = "impedance",
                adaptation: Adaptation | None = Adaptation(), checkpoint_seconds: float = WRITE_SECONDS,
                tempering: Tempering | None = None) -> SamplerRun:
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
        callable returning one, called only when the chain starts over; the walkers are
        drawn around it by ``optimize.laplace_ensemble``.
    coordinates : where the walkers move: a :class:`.coordinates.Coordinates` or the name
        of one (``coordinates.COORDINATES``; default "impedance", which falls back to
        "unconstrained" for models without an impedance map, and for the motion-in
        likelihood where its start lies outside the map's domain). A checkpoint
        continues only in the coordinates it was written in.
    adaptation : the fitted moves (:class:`.adaptation.Adaptation`); None: the ensemble
        moves alone.
    checkpoint_seconds : steps are written to the checkpoint at most this many seconds
        apart (``checkpoint.WRITE_SECONDS``; 0: every step); a kill loses at most that.
    tempering : parallel tempering's ladder (:class:`.tempering.Tempering`); None (the
        default): the posterior's ensemble alone. ``steps`` and the convergence rule
        count the cold ensemble's steps; each costs the ladder's temperatures times the
        evaluations of an untempered one.
    """
    conv = convergence or Convergence()
    nwalkers = check_run_options(model.ndim, nwalkers, steps)
    coords = coordinates if isinstance(coordinates, Coordinates) else default_coordinates(model, coordinates)
    stored = None if fresh else (stored_identity(checkpoint) or {})  # read once: the file is opened each time
    if stored is not None:  # a checkpoint at a reference frequency within the records' resolution goes on in its own
        coords = continue_at(coords, stored.get("coordinates"), reference_tolerance(model))
    searched = start is None  # the search's start: its mirrored modes get walkers too (_first_walkers)
    seconds = {}
    needs_reference = getattr(model, "needs_reference", False)
    # the motion-in likelihood without a reference point (normaliser "full" and the
    # deviations' sd at each walker's own) searches its start here too, as the reference
    # point's is, so that the coordinates can fall back where it lies outside their domain
    # a caller's start function (the joint fit's search) likewise: its optimum may lie outside
    search_first = (not needs_reference and coords.kind == "impedance" and not stored
                    and ((start is None and getattr(model, "motion", None) is not None) or callable(start)))
    if needs_reference or search_first:
        t0 = time.perf_counter()
        with interrupt_raised():  # Ctrl-C in a search's compiled code: a KeyboardInterrupt
            if needs_reference:
                model, start = _with_reference(model, stored, start, seed, processes, coords)
            elif callable(start):
                start = start()
            else:
                start = _searched_start(model, seed, processes, coords)
        seconds["search"] = time.perf_counter() - t0  # kept only where the chain is new
        if coords.kind == "impedance":
            coords = _reachable(model, coords, start, stored)
    target = Target(model, coords)
    schedule = Schedule(moves or default_moves(model, coordinates=coords), adaptation)
    identity = run_identity(model, coords, adaptation, schedule.base, nwalkers, tempering)
    backend, done, recovered = _open(Path(checkpoint), identity, fresh, checkpoint_seconds)
    if report:
        report(SamplerStatus(done, done, steps))
    # Ctrl-C in the start search's compiled code: a KeyboardInterrupt, not numba's SystemError
    with make_executor(processes, state=target) as executor, interrupt_raised():
        try:
            if done == 0:
                betas = (1.0,) if tempering is None else tuple(float(b) for b in tempering.betas)
                state, hot_starts, start_theta, first = _first_walkers(target, nwalkers, seed, start, executor,
                                                                       searched, betas)
                seconds = {k: seconds.get(k, 0.0) + first.get(k, 0.0) for k in START_PHASES}
            else:
                state, start_theta, hot_starts = backend.get_last_sample(), None, None
            iterations = max(0, (steps if steps is not None else conv.max_steps) - done)
            if tempering is None:
                stepping = sample(target, backend, state, schedule=schedule, executor=executor,
                                  iterations=iterations)
            else:
                stepping = sample_tempered(target, backend, state, tempering=tempering, schedule=schedule,
                                           iterations=iterations, seed=seed, executor=executor,
                                           hot_starts=hot_starts)
            if steps is not None:
                check, ok = _take_steps(stepping, backend, coords, conv, progress, steps, tempering is not None)
            else:
                check, ok = _until_converged(stepping, backend, coords, conv, done, progress, report,
                                             tempering is not None)
            reason = "converged" if ok else why_not(backend.iteration, check, conv)
            sampler = emcee.EnsembleSampler(nwalkers, model.ndim, target.batch, vectorize=True, backend=backend,
                                            blobs_dtype=float)
            rates = tuple(swap_rates(backend.extra, backend.iteration)) if tempering is not None else ()
            return SamplerRun(sampler, ok, check.tau, reason, start_theta, recovered, schedule.used(), coords,
                              check.transient, done, check.warmup, model, tempering, rates,
                              seconds if done == 0 else {}, check.replica_tau)
        finally:
            try:  # a run stopped by Ctrl-C or an error: bring the twin up to date if possible
                with interrupts_held():
                    backend.flush()
            except OSError:  # chain.h5 holds every step; the twin is only behind
                pass


class _ThetaSoFar:
    """The chain so far in theta for the convergence checks, each step carried from the
    sampler's coordinates once: a check at step n transforms only the steps since the
    last one (the whole chain at every check cost, measured on a paper-like record of
    20,000 steps, about an eighth of the run, growing with the square of its length).
    ``read(start)``: the steps from ``start`` on, in the sampler's coordinates (default:
    the chain's; :func:`_replicas_so_far` reads the replicas' trajectories)."""

    def __init__(self, backend, coords, read=None):
        self.backend, self.coords = backend, coords
        self.read = read or (lambda start: backend.get_chain()[start:])
        self.theta = None

    def __call__(self) -> np.ndarray:
        if self.coords is None:
            return self.read(0)
        have = 0 if self.theta is None else len(self.theta)
        n = self.backend.iteration
        if have > n:  # not this chain's (never within one run): start again
            self.theta, have = None, 0
        if have < n:
            new = self.coords.to_theta(self.read(have))
            self.theta = new if self.theta is None else np.concatenate([self.theta, new])
        return self.theta


def _replicas_so_far(backend, coords, on: bool):
    """A tempered chain's replicas' trajectories so far in theta
    (:func:`.tempering.replica_trajectories`, from the cold chain and the hot ensembles'
    walkers and labels the checkpoint keeps at every step), carried as
    :class:`_ThetaSoFar` carries the chain; called, None where ``on`` is False or the
    chain keeps no replicas (a checkpoint written before they were kept)."""
    if not (on and backend.has_rows("hot_chain")):
        return lambda: None
    return _ThetaSoFar(backend, coords, lambda start: replica_trajectories(
        backend.get_chain()[start:], backend.get_rows("hot_chain", start), backend.get_rows("replicas", start)))


def _take_steps(stepping, backend, coords, conv: Convergence, progress, steps: int,
                tempered: bool = False) -> tuple[Check, bool]:
    """Take the steps asked for; then the whole rule's check (R-hat and ESS included)."""
    for _ in stepping:
        if progress:
            progress(backend.iteration, steps)
    replicas = _replicas_so_far(backend, coords, tempered and conv.replicas)()
    check = check_chain(_theta_chain(backend, coords), backend.get_log_prob(), conv, replicas=replicas)
    return check, is_converged(backend.iteration - check.warmup, check.tau, None, check.rhat, check.ess, conv)


def _until_converged(stepping, backend, coords, conv: Convergence, done: int, progress, report,
                     tempered: bool = False):
    """Step until the chain converges or reaches ``conv.max_steps``, checking it at every
    multiple of ``conv.check_every``: a continued chain is checked (and stops) where an
    uninterrupted run would be, taking the tau of that run's previous check from the
    stored chain; one that stands on a check is checked before it samples more (a
    converged chain comes back as it is). A ``tempered`` run's replicas are read too
    where ``conv.replicas`` says so (:func:`.convergence.check_chain`)."""
    monitor = Monitor(conv)
    theta = _ThetaSoFar(backend, coords)
    replicas = _replicas_so_far(backend, coords, tempered and conv.replicas)
    if done:
        monitor.resume(theta(), backend.get_log_prob(), done, replicas())

    def check() -> tuple[Check, bool]:
        got = monitor.check(theta(), backend.get_log_prob(), replicas())
        if report:
            report(_status(backend, got[0], done, conv))
        return got

    if done and (done % conv.check_every == 0 or done >= conv.max_steps):
        got = check()
        if got[1] or done >= conv.max_steps:
            return got
    for _ in stepping:
        n = backend.iteration
        if progress:
            progress(n, None)
        if n % conv.check_every == 0 or n >= conv.max_steps:
            got = check()
            if got[1] or n >= conv.max_steps:
                return got
    return check()  # not reached: the last step is a check at max_steps


def _open(checkpoint: Path, identity: dict, fresh: bool, write_seconds: float):
    """The checkpoint's back end for the run ``identity`` (:mod:`.identity`), the steps it
    holds, and what was done to recover it."""
    opened = open_checkpoint(checkpoint, identity=identity, fresh=fresh, write_seconds=write_seconds)
    if opened is not None and opened.steps > 0:
        return opened.backend, opened.steps, opened.recovered
    backend = new_checkpoint(checkpoint, identity=identity, write_seconds=write_seconds)
    return backend, 0, opened.recovered if opened else ""


def _many(executor: Executor):
    """The start search's evaluator of many points on ``executor``'s workers (None: one
    process)."""
    if executor.workers <= 1:
        return None
    return lambda name, xs: executor.map_state(objective_at, [(name, x) for x in xs])


def _model_map(executor: Executor):
    """``fn(model, item)`` for many items on ``executor``'s workers, each holding the
    target's model (None: one process): the start's independent polishes and the held
    ladder's walks at once (``optimize.find_start``'s and ``held_modes``' ``map``)."""
    if executor.workers <= 1:
        return None
    return lambda fn, items: executor.map_state(functools.partial(on_model, fn), list(items))


def _with_reference(model, stored: dict | None, start, seed: int, processes: int, coords):
    """``model`` with its likelihood's reference point (``PosteriorModel.with_reference``)
    and the start to use: the reference of the checkpoint's identity ``stored`` where it
    continues one, else the start (``start`` or the optimiser's, with the parameters' own
    normaliser) becomes it."""
    kept = (stored or {}).get("reference")
    if kept is not None:
        return model.with_reference(kept), start
    if start is None:
        start = _searched_start(model, seed, processes, coords)
    elif callable(start):
        start = start()
    theta = np.asarray(start[0], dtype=float)
    model = model.with_reference(theta)
    return model, (theta, model.log_prob(theta)[0])


def _searched_start(model, seed: int, processes, coords: Coordinates):
    """The optimiser's start (``optimize.find_start``, seeded by ``seed``), its search on
    ``processes``."""
    with make_executor(processes, state=Target(model, coords)) as executor, interrupt_raised():
        return find_start(model, np.random.default_rng(seed), many=_many(executor), map=_model_map(executor))


def _reachable(model, coords: Coordinates, start, stored: dict | None) -> Coordinates:
    """The default impedance coordinates, or the unconstrained ones where the start lies
    outside their domain (measured: a paper-like B2 record at 1.5 Hz whose optimum did)
    or the checkpoint continued was written in them."""
    kind = ((stored or {}).get("coordinates") or {}).get("kind")
    if kind == "unconstrained" or (kind is None and start is not None and not callable(start)
                                   and not coords.contains(start[0])):
        return default_coordinates(model, "unconstrained")
    return coords


def _first_walkers(target: Target, nwalkers: int, seed: int, start, executor: Executor, searched: bool = False,
                   betas: tuple = (1.0,)):
    """The first state of a new chain, the first walkers of its hot ensembles (one
    array each, for ``betas[1:]``; none untempered), the point the walkers were drawn
    around, and the start's phases' seconds. The point: the optimiser's start (its
    search on ``executor``), or ``start``. Where the start is the search's
    (``searched``, or ``start`` None) and its mirror ends in a mode of its own
    (``optimize.mirrored_modes``), or a held parameter's polish ends in one
    (``optimize.held_modes``), the walkers are shared equally among the modes: a chain
    whose walkers all begin in one mode of the friction's split may never visit the
    other, and neither tau nor R-hat can see a mode no walker visits. Each ensemble of a
    tempered chain is drawn at its own temperature's spread
    (``optimize.laplace_ensemble``'s ``beta``)."""
    model, coords = target.model, target.coords
    rng = np.random.default_rng(seed)
    seconds = dict.fromkeys(START_PHASES, 0.0)
    t0 = time.perf_counter()
    if start is None:
        searched = True
        start = find_start(model, rng, many=_many(executor), map=_model_map(executor))
        seconds["search"] = time.perf_counter() - t0
    elif callable(start):
        start = start()
    start_theta = np.asarray(start[0], dtype=float)
    if not math.isfinite(model.log_prob(start_theta)[0]):
        raise ValueError("no parameters within the priors reproduce this record (the best start found "
                         "has zero posterior density): check its columns, units and masses with "
                         "bayes-inerter inspect, and the model")
    if not coords.contains(start_theta):
        advice = ("use --coordinates unconstrained, which covers the whole prior"
                  if coords.kind == "impedance" else "check the record and the priors")
        raise ValueError(f"the start lies outside the {coords.kind} coordinates' domain; {advice}")

    centres = [start_theta]
    t0 = time.perf_counter()
    if searched:
        lp = float(start[1]) if len(start) > 1 and start[1] is not None else model.log_prob(start_theta)[0]
        centres += [theta for theta, _ in mirrored_modes(model, start_theta, lp, map=_model_map(executor))
                    if coords.contains(theta)]
        centres += [theta for theta, _ in held_modes(model, start_theta, lp, map=_model_map(executor))
                    if coords.contains(theta)]
    seconds["modes"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    counts = [nwalkers // len(centres) + (k < nwalkers % len(centres)) for k in range(len(centres))]
    ensembles = [coords.to_u(np.vstack([laplace_ensemble(model, centre, n, rng, accept=coords.contains, beta=beta)[0]
                                        for centre, n in zip(centres, counts)])) for beta in betas]
    state = emcee.State(ensembles[0], random_state=np.random.RandomState(seed).get_state())
    seconds["ensemble"] = time.perf_counter() - t0
    return state, ensembles[1:], start_theta, seconds


def _status(backend, check: Check, done: int, conv: Convergence) -> SamplerStatus:
    """The run's :class:`SamplerStatus` after a convergence check."""
    n = backend.iteration
    tau_max = float(np.max(check.tau)) if np.all(np.isfinite(check.tau)) else math.nan
    needed = None
    if math.isfinite(tau_max):  # the warm-up takes its share of the longer chain too
        needed = max(0, steps_for(tau_max, conv) - n, check.warmup + math.ceil(conv.n_tau * tau_max) - n)
    return SamplerStatus(n, done, None, tau_max, float(np.mean(backend.accepted / n)), needed)
