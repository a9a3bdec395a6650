"""When a chain has converged: emcee's autocorrelation time, R-hat and bulk ESS after a
warm-up, checked at fixed steps (see :class:`Convergence` and docs/inference.md).

The rule (documented defaults, :class:`Convergence`): emcee's integrated
autocorrelation time tau (emcee's estimate, ``emcee.autocorr.integrated_time(tol=0)``,
computed by :func:`integrated_time` on the chain in theta, the reported parameters) per parameter, checked every ``check_every`` steps, on
the chain after its warm-up: its :func:`transient` (the steps before the walkers reach
equilibrium, none for a chain that starts there) or its first ``warmup`` share,
whichever is longer; converged when the chain after the warm-up is longer than
``n_tau`` times the largest tau (and than ``n_tau`` times the last check's, if that was
larger), tau grew by less than ``tau_rtol`` since the last check (a tau that still grows
with the chain is underestimated; so a run never stops at its first check, where tau has
nothing to be compared with, as in emcee's own recipe), and, after discarding 2 tau more, R-hat <
``max_rhat`` and bulk ESS >= ``min_ess`` (arviz, treating walkers as chains: they are
not independent, so R-hat here is a check that no walker is stuck apart from the
others, not a proof). Or stops at ``max_steps``. The draws kept for the posterior
(:func:`..summaries.results.posterior_sample`) are the same: after the warm-up and 2 tau more.

:class:`Monitor` applies the rule along one run: it remembers the last check's tau.

A tempered run (:mod:`.tempering`) is judged on its posterior's ensemble and, by
default (``Convergence.replicas``), on its replicas, each walker followed through the
swaps: each parameter's larger tau is the rule's (and the kept draws'):
the posterior's slots decorrelate at every accepted swap, so their tau alone called
chains converged that had not crossed their posterior (docs/inference.md, "Tempering
on bent ridges").
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import emcee
import numpy as np
import scipy.fft

__all__ = ["Convergence", "Check", "Monitor", "WARMUP", "TAU_RTOL", "GROWTH", "transient", "check_chain", "steps_for",
           "tau_settled", "is_converged", "why_not", "integrated_time"]

#: Share of a chain left out as warm-up before its convergence is judged and its draws
#: kept (:class:`Convergence`), unless its transient is longer.
WARMUP = 1 / 3

#: :class:`Convergence`'s default ``tau_rtol``. tau estimated from a chain a few hundred
#: steps long is itself noisy, so a 5 % test (emcee's recipe takes 1 % on far longer
#: chains) held tempered chains whose tau was 5 to 11 steps to 1,250 to 2,000 steps.
#: Replayed on the same six paper-like chains (``benchmarks/bench_tau_growth.py
#: --rtol``, results/performance/tau_rtol.csv), 0.2 stopped the five that stopped at all
#: 1.5 to 2 times sooner, b's 3, 50 and 97 % quantiles there within 0.15 % of b of the
#: whole chain's. The sixth (A1 at 0.5 Hz, largest tau 70 steps at 3,000) no tolerance
#: stopped; dropping the test stopped three chains at their second check, 500 steps.
#: 0.05 until this changed (CHANGELOG.md).
TAU_RTOL = 0.2

#: The ways :class:`Convergence` can judge tau's growth between two checks (its ``growth``).
GROWTH = ("each", "largest")


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
    #: how much any parameter's tau may have grown since the last check, as a share of
    #: it (:data:`TAU_RTOL`)
    tau_rtol: float = TAU_RTOL
    max_rhat: float = 1.05
    min_ess: float = 400.0
    check_every: int = 250
    max_steps: int = 20_000
    warmup: float = WARMUP
    #: how tau's growth since the last check is judged (:data:`GROWTH`): "each" (the
    #: default), every parameter's tau against its own last value; "largest", every
    #: parameter's growth against the largest last tau, the one the chain's length
    #: must exceed 50 times (a parameter whose tau is a fraction of the largest may
    #: wander by more than ``tau_rtol`` of itself without the chain being too short).
    growth: str = "each"
    #: whether a tempered run's tau is also read on its replicas (each walker followed
    #: through the swaps, :func:`.tempering.replica_trajectories`), the rule then taking
    #: each parameter's larger tau: an accepted swap decorrelates the posterior's slots
    #: without moving any replica, so their own tau measures the swaps, not the ladder's
    #: mixing (docs/inference.md, "Tempering on bent ridges"). No effect on an untempered
    #: run or one whose checkpoint keeps no replicas. False: the posterior's slots alone,
    #: the rule before (CHANGELOG.md).
    replicas: bool = True

    def __post_init__(self) -> None:
        if self.growth not in GROWTH:
            raise ValueError(f"convergence setting growth must be one of {', '.join(GROWTH)}, got {self.growth!r}")
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
class Check:
    """One convergence check: tau, R-hat and ESS after the warm-up (in theta), the
    warm-up's steps and the transient's among them."""

    tau: np.ndarray
    rhat: np.ndarray
    ess: np.ndarray
    warmup: int
    transient: int
    #: the replicas' own tau where it was read (``Convergence.replicas``); ``tau`` is then
    #: each parameter's larger of it and the posterior's slots'
    replica_tau: np.ndarray | None = None


def integrated_time(chain: np.ndarray, c: float = 5.0) -> np.ndarray:
    """emcee's integrated autocorrelation time of each parameter of ``chain`` (steps,
    walkers, ndim), ``emcee.autocorr.integrated_time(chain, c, tol=0)``: the walkers'
    normalised autocorrelation functions averaged, and summed up to Sokal's window.
    Computed with one real FFT per parameter over all walkers at once (each walker's
    series contiguous), zero-padded to the shortest fast length that keeps the
    correlation linear (2 n - 1), where emcee takes a complex FFT per walker and
    parameter padded to twice the next power of two: the same numbers to a few parts in
    1e15, in 0.35 to 0.4 times emcee's time on chains of 6,667 to 13,333 steps of 26
    walkers and 12 parameters (a convergence check of a long chain is mostly this)."""
    chain = np.asarray(chain, dtype=float)
    if chain.ndim != 3:
        raise ValueError(f"chain must be (steps, walkers, ndim), got shape {chain.shape}")
    n, _, ndim = chain.shape
    m = scipy.fft.next_fast_len(2 * n - 1, real=True)
    tau = np.empty(ndim)
    for j in range(ndim):
        x = np.ascontiguousarray(chain[:, :, j].T)  # (walkers, steps)
        x -= x.mean(axis=1, keepdims=True)
        f = scipy.fft.rfft(x, n=m, axis=1)
        acf = scipy.fft.irfft(f.real ** 2 + f.imag ** 2, n=m, axis=1)[:, :n]
        with np.errstate(invalid="ignore", divide="ignore"):  # a walker that never moved: NaN, as emcee's
            acf = acf / acf[:, :1]
        taus = 2.0 * np.cumsum(acf.mean(axis=0)) - 1.0
        tau[j] = taus[emcee.autocorr.auto_window(taus, c)]
    return tau


def check_chain(chain: np.ndarray, log_prob: np.ndarray, conv: Convergence, rhat_if=None,
                replicas: np.ndarray | None = None) -> Check:
    """tau, R-hat and bulk ESS of ``chain`` (steps, walkers, ndim) after its warm-up (its
    :func:`transient` from ``log_prob``, at most half the chain, or ``conv.warmup`` of
    it, whichever is longer).

    ``replicas`` (steps, replicas, ndim; a tempered run's replicas' trajectories in the
    same parameters, :func:`.tempering.replica_trajectories`), read where
    ``conv.replicas`` says so: their tau after the same warm-up, and each parameter's
    tau the larger of theirs and the chain's. R-hat and ESS stay the chain's.

    ``rhat_if(steps after the warm-up, tau)``: where it says no, R-hat (inf) and ESS
    (0) are not computed. arviz takes about half a second per thousand steps of a
    single-record chain, a tenth of the sampling between two checks of a long chain,
    and they decide nothing while the chain is still too short for its tau."""
    from .diagnostics import rhat_ess

    n = len(chain)
    skip = min(transient(log_prob), n // 2)
    warm = max(skip, int(conv.warmup * n))
    replica_tau = None
    with np.errstate(invalid="ignore", divide="ignore"):  # a parameter that never moved: tau NaN, handled below
        tau = integrated_time(chain[warm:])
        if replicas is not None and conv.replicas:
            if len(replicas) != n:
                raise ValueError(f"the replicas' trajectories hold {len(replicas)} steps, the chain {n}")
            replica_tau = integrated_time(replicas[warm:])
            tau = np.maximum(tau, replica_tau)  # NaN where either is
    if rhat_if is not None and not rhat_if(n - warm, tau):
        return Check(tau, np.full(len(tau), np.inf), np.zeros(len(tau)), warm, skip, replica_tau)
    burn = warm + (int(2 * np.nanmax(tau)) if np.all(np.isfinite(tau)) else (n - warm) // 2)
    rhat, ess = rhat_ess(chain[min(burn, n - 2):])
    return Check(tau, rhat, ess, warm, skip, replica_tau)



def steps_for(tau_max: float, conv: Convergence) -> int:
    """The chain length at which the chain after its warm-up share is ``conv.n_tau``
    times ``tau_max`` long (the rule's tau part, where the share is the longer warm-up)."""
    return math.ceil(conv.n_tau * tau_max / (1.0 - conv.warmup))


def tau_settled(iteration, tau, previous, conv: Convergence) -> bool:
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
        scale = previous if conv.growth == "each" else np.max(previous)
        if np.max((tau - previous) / scale) > conv.tau_rtol or iteration < conv.n_tau * np.max(previous):
            return False
    return True


def is_converged(iteration, tau, previous, rhat, ess, conv: Convergence) -> bool:
    """``iteration``: the chain's steps after its warm-up."""
    if not tau_settled(iteration, tau, previous, conv):
        return False
    return bool(np.nanmax(rhat) < conv.max_rhat and np.nanmin(ess) >= conv.min_ess)


def why_not(iteration, check: Check, conv: Convergence) -> str:
    tau, rhat, ess, skip = check.tau, check.rhat, check.ess, check.warmup
    parts = []
    if np.all(np.isfinite(tau)):
        need = conv.n_tau * np.max(tau)
        if iteration - skip < need:
            after = f" after a warm-up of {skip}" if skip else ""
            whose = ("the replicas' " if check.replica_tau is not None
                     and np.max(check.replica_tau) >= np.max(tau) else "")
            parts.append(f"chain of {iteration - skip} steps{after} is shorter than {conv.n_tau:g} {whose}tau = "
                         f"{need:.0f}")
    else:
        parts.append("autocorrelation time not estimable")
    if not np.nanmax(rhat) < conv.max_rhat:
        parts.append(f"max R-hat {np.nanmax(rhat):.3f} >= {conv.max_rhat}")
    if not np.nanmin(ess) >= conv.min_ess:
        parts.append(f"min bulk ESS {np.nanmin(ess):.0f} < {conv.min_ess:g}")
    return "not converged: " + ("; ".join(parts) if parts else "tau still growing (or not yet compared with an "
                                f"earlier check), or the chain shorter than {conv.n_tau:g} times the last check's tau")


class Monitor:
    """The convergence rule along one run: :meth:`check` the chain at a check step and
    remember its tau for the next (a continued run first takes the tau of the last check
    before its start from the stored chain, :meth:`resume`, so that it stops where an
    uninterrupted run would)."""

    def __init__(self, conv: Convergence):
        self.conv = conv
        self.previous: np.ndarray | None = None

    def resume(self, chain: np.ndarray, log_prob: np.ndarray, done: int, replicas: np.ndarray | None = None) -> None:
        """Take ``previous`` from the first steps of a stored ``chain`` (in theta; and of
        its ``replicas``' trajectories, :func:`check_chain`) up to the last check before
        step ``done``."""
        last = ((done - 1) // self.conv.check_every) * self.conv.check_every if done else 0
        if last > 0:
            self.previous = check_chain(chain[:last], log_prob[:last], self.conv, rhat_if=lambda *_: False,
                                        replicas=None if replicas is None else replicas[:last]).tau

    def check(self, chain: np.ndarray, log_prob: np.ndarray,
              replicas: np.ndarray | None = None) -> tuple[Check, bool]:
        """The check of ``chain`` (steps, walkers, ndim; theta; with its ``replicas``'
        trajectories where tempered, :func:`check_chain`) and whether it has converged;
        its tau becomes the next check's ``previous``. R-hat and ESS are computed only
        where tau says they could decide something, or at ``max_steps``."""
        n, previous, conv = len(chain), self.previous, self.conv
        last = n >= conv.max_steps  # its message names R-hat and ESS too
        # the first check cannot stop the run: a tau from a chain of one check's length
        # (a tempered cold chain's was 3.2 steps at 250) has not been seen to settle
        compared = previous is not None
        check = check_chain(chain, log_prob, conv,
                            rhat_if=lambda k, t: last or (compared and tau_settled(k, t, previous, conv)),
                            replicas=replicas)
        ok = compared and is_converged(n - check.warmup, check.tau, previous, check.rhat, check.ess, conv)
        self.previous = check.tau
        return check, ok
