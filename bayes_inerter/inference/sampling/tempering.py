"""Parallel tempering: hotter copies of the posterior whose walkers swap into it.

Beside the posterior (beta = 1), ``temps - 1`` ensembles sample prior x
likelihood^beta, beta geometric from 1 down to ``beta_min``. Each takes one step of its
moves (the cold ensemble the run's moves, fitted ones included; the hot ones the
ensemble moves alone, since a proposal fitted to the posterior is too narrow for them,
or with ``Tempering.adapt_hot`` moves fitted to their own walkers),
and then each walker of one temperature is offered a swap with a walker of the next
hotter one (a random pairing, hottest pair first), accepted with probability
min(1, exp((beta_k - beta_k+1) (log L_j - log L_i))). Every move and swap leaves the
product of the tempered targets invariant, so the cold ensemble's chain is the
posterior's; the hot ones cross the valleys between its humps and hand the walkers down.

Why: single-record posteriors are far from one hump (results/chain-geometry: a third to
two thirds of the midpoints between two draws lie more than 10 nats down), and chains
that the default kernel leaves at the step cap met the convergence rule tempered
(``studies/tempering_probe.py``; docs/inference.md). Checked on a two-mode target whose
weights are known (tests/test_inference_tempering.py).

The cold ensemble's steps go to the checkpoint as every run's do; the hot ensembles'
states (walkers, their log-likelihoods and random states), the swaps' random state and
the swap counts are written beside them with each write, and its seal vouches for them
(:class:`.twin_backend.TwinBackend`'s ``extra``), so a continued tempered run is the
chain the uninterrupted one gives. The hot ensembles' walkers and every slot's replica
label are also kept at every step (the back end's per-step ``rows``), for the
convergence rule to follow each replica through the swaps
(:func:`replica_trajectories`, :func:`.convergence.check_chain`). The ladder is part of the run's identity
(:func:`.identity.run_identity`). The run's acceptance fraction counts the cold
ensemble's moves, not its swaps.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import Iterator

import emcee
import numpy as np

from ...executor import Executor, interrupts_held
from .checkpoint import CheckpointError
from .target import Target

__all__ = ["Tempering", "TemperedTarget", "sample_tempered", "swap_rates", "replica_trajectories", "MAX_STEPS",
           "default_convergence"]

#: A tempered fit's default cap, in the posterior's ensemble's steps: 10,000, each
#: costing ``temps`` times the evaluations (40,000 steps' worth with 4 temperatures,
#: twice the untempered cap, ``Convergence.max_steps``). The cap of the runs that
#: measured the tempered fit's calibration (results/coverage-sbc-v8 and -v9,
#: results/coverage-paper-like-tempered).
MAX_STEPS = 10_000


def default_convergence(tempering: "Tempering | None"):
    """The convergence rule a fit takes when none is given: the package's
    (``Convergence()``), capped at :data:`MAX_STEPS` where it is tempered."""
    from .convergence import Convergence

    return Convergence() if tempering is None else Convergence(max_steps=MAX_STEPS)


@dataclass(frozen=True)
class Tempering:
    """The ladder: ``temps`` ensembles (the posterior's included), their betas geometric
    from 1 down to ``beta_min``. Defaults (4 and 0.1) are the ladder measured in
    ``studies/tempering_probe.py``; on noise-free records, whose likelihood is far more
    peaked, its hottest pair swapped 2 to 3 % of the time, too seldom to leave a basin,
    and 10 temperatures down to beta 0.001 did not help: their swaps stalled between
    beta 1 and 0.1 (results/noise-free-chains-tempered)."""

    temps: int = 4
    beta_min: float = 0.1
    #: whether each hot ensemble also proposes from moves fitted to its own walkers so far
    #: (``adaptation.Schedule.hot_moves_at``; the run's adaptation's settings), where
    #: False (the default) gives them the ensemble moves alone. Measured: on a
    #: calibration record the hottest ensemble's own tau was the ladder's largest, 180
    #: steps against the posterior's ensemble's 8 (docs/inference.md).
    adapt_hot: bool = False

    def __post_init__(self) -> None:
        if not (isinstance(self.temps, (int, np.integer)) and self.temps >= 2):
            raise ValueError(f"tempering needs at least 2 temperatures, got {self.temps}")
        if not 0.0 < self.beta_min < 1.0:
            raise ValueError(f"the hottest beta must lie in (0, 1), got {self.beta_min}")

    @classmethod
    def of(cls, temps: int | None, beta_min: float | None = None) -> Tempering | None:
        """The ladder of ``temps`` temperatures down to ``beta_min`` (None: the default
        hottest beta), or None where ``temps`` is None (the ensemble alone): what a
        command line's ``--tempering`` and ``--hottest-beta`` ask for."""
        if temps is None:
            return None
        return cls(temps) if beta_min is None else cls(temps, beta_min)

    @property
    def betas(self) -> np.ndarray:
        """The inverse temperatures, 1 first."""
        return np.geomspace(1.0, self.beta_min, self.temps)

    def describe(self) -> str:
        return (f"parallel tempering, {self.temps} temperatures, beta " + ", ".join(f"{b:.3g}" for b in self.betas)
                + ("; hot ensembles with moves fitted to their own walkers" if self.adapt_hot else ""))


@dataclass(frozen=True)
class TemperedTarget:
    """``target`` at inverse temperature ``beta``: log prior (with the coordinates'
    Jacobian) + ``beta`` x log-likelihood, for a batch of walkers (emcee's
    ``vectorize``), each with the blobs (log-likelihood, phi). The model is evaluated as
    :meth:`.target.Target.batch` evaluates it (on the executor's workers; the coordinates'
    map once, :meth:`.target.Target.evaluate`); the prior, cheap, here, and the
    log-likelihood is the difference. At beta = 1 the value is the
    target's own."""

    target: Target
    beta: float

    def batch(self, us, executor: Executor | None = None) -> list:
        thetas, logj, got = self.target.evaluate(us, executor)
        out = []
        for (lp, phi), theta, lj in zip(got, thetas, logj):
            if not math.isfinite(lp):
                out.append((-math.inf, -math.inf, math.nan))
                continue
            prior = self.target.model.log_prior(theta) + float(lj)
            loglik = lp - prior
            out.append((lp if self.beta == 1.0 else prior + self.beta * loglik, loglik, phi))
        return out


def _extra(states: list, swap_rng: np.random.RandomState, swaps: np.ndarray, replicas: np.ndarray) -> dict:
    """What a continued run needs beyond the cold ensemble's stored step, as named arrays
    of fixed shapes (:meth:`.twin_backend.TwinBackend.save_step`'s ``extra``): the hot
    ensembles' walkers, tempered log probabilities and blobs, the cold ensemble's
    log-likelihoods, the random states of the hot ensembles and of the swaps, the
    swaps accepted so far at each adjacent pair, and which replica each walker of each
    ensemble is (``replicas``, temperatures x walkers: a walker keeps its label through
    the moves, and two walkers that swap swap labels; :func:`replica_trajectories`)."""
    hot = states[1:]
    rss = [h.random_state for h in hot] + [swap_rng.get_state()]
    return {"hot_coords": np.array([h.coords for h in hot]), "hot_log_prob": np.array([h.log_prob for h in hot]),
            "hot_blobs": np.array([h.blobs for h in hot]), "cold_loglik": np.array(states[0].blobs[:, 0]),
            "random_keys": np.array([rs[1] for rs in rss], dtype=np.uint32),
            "random_rest": np.array([[rs[2], rs[3], rs[4]] for rs in rss], dtype=float),
            "swaps": np.array(swaps, dtype=np.int64), "replicas": np.array(replicas, dtype=np.int64)}


def _random_state(extra: dict, k: int) -> tuple:
    rest = extra["random_rest"][k]
    return ("MT19937", np.array(extra["random_keys"][k], dtype=np.uint32), int(rest[0]), int(rest[1]),
            float(rest[2]))


def replica_trajectories(cold: np.ndarray, hot: np.ndarray, replicas: np.ndarray) -> np.ndarray:
    """Each replica's positions step by step, whatever temperature it was at: ``cold``
    (steps, walkers, ndim), the posterior's ensemble; ``hot`` (steps, temperatures - 1,
    walkers, ndim), the hot ensembles after each step; ``replicas`` (steps, temperatures,
    walkers), each slot's label (``extra["replicas"]``). Returns (steps, replicas, ndim).
    A swap relabels the slots of a temperature but moves no replica, so the
    autocorrelation of these trajectories measures how fast the ladder as a whole
    mixes, where the posterior's slots' own decorrelate at every accepted swap."""
    slots = np.concatenate([np.asarray(cold)[:, None], np.asarray(hot)], axis=1)  # steps, temps, walkers, ndim
    n, temps, walkers, ndim = slots.shape
    out = np.empty((n, temps * walkers, ndim), dtype=slots.dtype)
    rows = np.arange(n)[:, None]
    labels = np.asarray(replicas).reshape(n, temps * walkers)
    out[rows, labels] = slots.reshape(n, temps * walkers, ndim)
    return out


def swap_rates(extra: dict | None, steps: int) -> list[float]:
    """Each adjacent pair's share of accepted swaps over ``steps`` steps, from the
    tempering state a checkpoint stores (:meth:`.twin_backend.TwinBackend.extra`; empty
    without one)."""
    if not extra or steps <= 0:
        return []
    walkers = extra["cold_loglik"].shape[0]
    return [float(c) / (steps * walkers) for c in extra["swaps"]]


def sample_tempered(target: Target, backend, state: emcee.State, *, tempering: Tempering, schedule,
                    iterations: int, seed: int, executor: Executor | None = None,
                    hot_starts: list | None = None) -> Iterator[emcee.State]:
    """Yield the cold ensemble's state after each of ``iterations`` steps and swaps from
    ``state`` (the back end's last step, or the first walkers), storing each step, with
    the hot ensembles' states in its ``extra`` (see module docstring), in ``backend``.

    A new chain's hot ensembles start from ``hot_starts`` (walkers x ndim each, drawn as
    the first walkers are, and apart from them: an ensemble whose walkers coincide
    cannot move by differential evolution), each with a random state of its own drawn
    from ``seed``; a continued one takes them from the checkpoint (the state its seal
    vouches for). Ctrl-C comes out between steps, after the step it came in is stored."""
    betas = tempering.betas
    nwalkers, ndim = np.shape(state.coords)
    stored = backend.extra if backend.iteration > 0 else None
    replicas = np.arange(len(betas) * nwalkers).reshape(len(betas), nwalkers)  # each walker its own label
    if backend.iteration > 0 and stored is None:
        raise CheckpointError("the checkpoint holds no tempering state to continue from (it was damaged or "
                              "written untempered); run with --fresh to start over, or use another --out")
    if stored is not None:
        if len(stored["hot_coords"]) != len(betas) - 1:
            raise CheckpointError("the checkpoint's tempering state is of another ladder; run with --fresh to "
                                  "start over, or use another --out")
        hot = [emcee.State(np.array(c), log_prob=np.array(lp), blobs=np.array(bl),
                           random_state=_random_state(stored, k))
               for k, (c, lp, bl) in enumerate(zip(stored["hot_coords"], stored["hot_log_prob"], stored["hot_blobs"]))]
        swap_rng = np.random.RandomState()
        swap_rng.set_state(_random_state(stored, len(hot)))
        swaps = np.array(stored["swaps"], dtype=np.int64)
        if "replicas" in stored:  # one written before the labels were kept keeps the fresh ones above
            replicas = np.array(stored["replicas"], dtype=np.int64)
    else:
        if hot_starts is None or len(hot_starts) != len(betas) - 1:
            raise ValueError(f"a new tempered chain needs the first walkers of its {len(betas) - 1} hot ensembles")
        seeds = np.random.SeedSequence([seed, 0x7E3B]).generate_state(len(betas))
        hot = [emcee.State(np.array(start, dtype=float), random_state=np.random.RandomState(int(s)).get_state())
               for start, s in zip(hot_starts, seeds[1:])]
        swap_rng = np.random.RandomState(int(seeds[0]))
        swaps = np.zeros(len(betas) - 1, dtype=np.int64)
    fns = [functools.partial(TemperedTarget(target, float(beta)).batch, executor=executor) for beta in betas]
    if stored is not None:  # the stored step holds phi alone; its log-likelihood is in the seal
        blobs = np.column_stack([stored["cold_loglik"], state.blobs])
        cold = emcee.State(state.coords, log_prob=state.log_prob, blobs=blobs, random_state=state.random_state)
    else:
        cold = emcee.State(state.coords, random_state=state.random_state)
    states = [_evaluated(s, fn) for s, fn in zip([cold] + hot, fns)]
    keep_rows = backend.has_rows("hot_chain")  # a chain written before they were kept goes on without them
    until = backend.iteration + iterations
    while backend.iteration < until:
        step = backend.iteration
        end = min(until, schedule.end_of_stretch(step))
        samplers = [emcee.EnsembleSampler(nwalkers, ndim, fn, vectorize=True, blobs_dtype=float,
                                          moves=_moves(schedule, step, backend, k, tempering.adapt_hot and keep_rows))
                    for k, fn in enumerate(fns)]
        with interrupts_held():
            backend.grow(end - step, states[0].blobs[:, 1])
        for _ in range(end - step):
            with interrupts_held():
                before = states[0].coords.copy()
                states = [next(s.sample(st, iterations=1, store=False, skip_initial_state_check=True))
                          for s, st in zip(samplers, states)]
                accepted = np.any(states[0].coords != before, axis=1).astype(int)
                for k in range(len(betas) - 2, -1, -1):
                    swaps[k] += _swap(states[k], states[k + 1], betas[k], betas[k + 1], swap_rng,
                                      (replicas[k], replicas[k + 1]))
                cold = states[0]
                extra = _extra(states, swap_rng, swaps, replicas)
                saved = emcee.State(cold.coords.copy(), log_prob=cold.log_prob.copy(), blobs=cold.blobs[:, 1].copy(),
                                    random_state=cold.random_state)
                # single precision: what tau needs, half the checkpoint (the continued run
                # takes the hot ensembles from ``extra``, in full)
                rows = {"hot_chain": extra["hot_coords"].astype(np.float32),
                        "replicas": extra["replicas"].astype(np.int32)}
                backend.save_step(saved, accepted, extra=extra, rows=rows if keep_rows else None)
            yield saved
        with interrupts_held():
            backend.flush()


def _moves(schedule, step: int, backend, k: int, adapt_hot: bool) -> list:
    """The moves of the ``k``-th ensemble (0: the posterior's) from ``step``: the run's
    schedule for the posterior's, and for a hot one the ensemble moves alone, or with
    ``adapt_hot`` moves fitted to its own walkers (:meth:`.adaptation.Schedule.hot_moves_at`)."""
    if k == 0:
        return schedule.moves_at(step, backend)
    return schedule.hot_moves_at(step, backend, k - 1) if adapt_hot else schedule.base


def _evaluated(state: emcee.State, fn) -> emcee.State:
    """``state`` with its log probabilities and blobs under ``fn`` (computed where it has none)."""
    if state.log_prob is not None:
        return state
    got = fn(state.coords)
    return emcee.State(state.coords, log_prob=np.array([g[0] for g in got], dtype=float),
                       blobs=np.array([g[1:] for g in got], dtype=float), random_state=state.random_state)


def _swap(a: emcee.State, b: emcee.State, beta_a: float, beta_b: float, rng: np.random.RandomState,
          labels: tuple | None = None) -> int:
    """Offer each walker of ``a`` a swap with a walker of ``b`` (a random pairing); swap
    the accepted in place (positions, log-likelihoods, phi, tempered log probabilities,
    and the replicas' ``labels`` of ``a`` and ``b`` where given) and return how many
    were."""
    n = len(a.coords)
    pair = rng.permutation(n)
    la, lb = a.blobs[:, 0], b.blobs[pair, 0]
    gain = (beta_a - beta_b) * (lb - la)
    take = ~np.isnan(gain) & (np.log(rng.uniform(size=n)) < gain)
    for i in np.flatnonzero(take):
        j = pair[i]
        prior_i = a.log_prob[i] - beta_a * a.blobs[i, 0]
        prior_j = b.log_prob[j] - beta_b * b.blobs[j, 0]
        a.coords[i], b.coords[j] = b.coords[j].copy(), a.coords[i].copy()
        a.blobs[i], b.blobs[j] = b.blobs[j].copy(), a.blobs[i].copy()
        a.log_prob[i] = prior_j + beta_a * a.blobs[i, 0]
        b.log_prob[j] = prior_i + beta_b * b.blobs[j, 0]
        if labels is not None:
            labels[0][i], labels[1][j] = labels[1][j], labels[0][i]
    return int(take.sum())
