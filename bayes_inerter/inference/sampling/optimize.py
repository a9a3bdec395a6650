"""A robust quick optimum of the log posterior, to start the walkers from.

The landscape has many local optima (stick-slip makes it rough, and several parameters
are unidentified), so a local optimiser from a guess is not enough. Two stages:

1. differential evolution (scipy) over the physical parameters, within the prior's
   bounds in log space, once per objective of :data:`OBJECTIVES`: the sum of squared
   kept residuals (:func:`sse`) and that sum with the noise profiled out of the AR(1)
   likelihood (:func:`profiled_misfit`; the noise parameters do not move the
   least-squares optimum, but the AR(1) weighting does). Each population is seeded with
   a rigid-body guess (:func:`rigid_guess`: least squares of the force on acceleration,
   sign of velocity and velocity), which puts b and the frictions in the right basin;
   the best of the guess and the evolved point is kept;
2. for each evolved point, the noise parameters from its residual (sigma its sd, rho
   its lag-one correlation), then Nelder-Mead on the full log posterior, restarted from
   its own result while a pass still gains (:data:`NM_RESTARTS`, :data:`RESTART_GAIN`);
   the point with the highest log posterior is the start;
3. the rigid guess polished the same way (:data:`POLISH_RIGID_GUESS`), and the higher
   of the two;
4. that point with the Coulomb force's split mirrored (f_share to 1 - f_share),
   polished the same way (:func:`mirrored_modes`), and the higher of the two. Where the
   mirror ends in a mode of its own not far below, the sampler draws half its walkers
   there (``sampler``; :data:`MIRROR_NATS`).

Where the sampler draws its walkers around the search's optimum, it also looks along
the friction's ridge: that point with the viscous sum held at each factor of
:data:`HELD_MODES` times its own value, polished with it held and then freed
(:func:`held_modes`); each polish that ends in a mode of its own not far below (or
above) gets an equal share of the walkers.

Why two objectives: where the model is right the residual is nearly white and the two
agree; on a record of a richer device the residual is dominated by the model's error,
strongly correlated (rho near 0.98), and the plain least-squares optimum can lie in
another basin of the posterior than its mode. Measured on paper-like records
(``records.paper_like``, laboratory seed 0) and generated ones (grid seed 0), with 40
generations each and polished as above: the log posterior reached was (least squares,
profiled) 1688.5 and 1708.2 on A3 at 0.5 Hz, 1069.7 and 993.9 on A0 at 1 Hz, 1402.9
and 1573.0 on A0 at 0.5 Hz, 1928.7 and 1849.6 on B2 at 0.5 Hz, 2594.5 and 2736.8 on
the generated A3 at 0.5 Hz: neither objective is best everywhere, and the worse start
is tens to hundreds of nats down. A chain started from the least-squares point of A3
at 0.5 Hz, 40 nats below the best optimum found there, first reached a point 14 nats
higher than its start after 3,500 steps; started at that optimum, the chain converged
in 2,250 steps.

Then :func:`laplace_ensemble` draws the walkers from a normal approximation there.

Seeded: the same Generator gives the same optimum and the same walkers.
"""

from __future__ import annotations

import math
import warnings

import numpy as np
from scipy.optimize import differential_evolution, minimize

from ...records.conditioning import lowpass
from ...simulate import SimulationError
from ..posterior.model import PosteriorModel
from ..posterior import friction_law
from ..posterior.motion import predicted_force
from ..posterior.priors import RHO_BOUNDS

__all__ = ["find_start", "local_optimum", "laplace_ensemble", "laplace_covariance", "sse", "profiled_misfit",
           "rigid_guess", "velocity_estimate", "OBJECTIVES", "DE_POPSIZE", "DE_MAXITER", "NM_MAXITER",
           "NM_RESTARTS", "RESTART_GAIN", "NM_XATOL", "NM_FATOL", "POLISH_RIGID_GUESS", "mirrored_modes", "MIRROR_SHARES", "MIRROR_NATS",
           "held_modes", "held_walk", "polished", "HELD_MODES", "HELD_SEPARATION",
           "MIRROR_SEPARATION", "tau_continued", "TAU_CONTINUATION", "held_optimum", "whitened_optimum"]

DE_POPSIZE = 8  # population per parameter
#: Generations of each objective's differential evolution. Forty: on six records
#: (paper-like A3 and A0 at 0.5 Hz, A0 at 1 Hz, B2 at 0.5 Hz, A3 at 1 Hz; generated A3 at
#: 0.5 Hz; seed 0) twenty gave polished points at most 6.5 nats below forty's (1701.7
#: and 1708.2, 1572.6 and 1573.0, 1064.9 and 1069.7, 1954.4 and 1928.7, 1565.6 and
#: 1567.6, 2736.8 both), but on the full study's generated B2 record at 1 Hz twenty
#: ended at log posterior 2526.9 (c_n 1.8e5 N s/m) where forty reached 2753.5 (the
#: truth polished: 2753.8), and a joint chain of it and the 1.5 Hz record started there
#: met the convergence rule 1,600 nats below the truth, b 0.7 % low and outside its
#: interval. Read at call time (``find_start(maxiter=None)``),
#: so a caller may set it (the test suite runs twenty, for time).
DE_MAXITER = 40
NM_MAXITER = 800  # Nelder-Mead iterations a pass on the full posterior (read at call time)
#: Nelder-Mead's simplex collapses along this posterior's ridges and stops far short of
#: the optimum: on a generated A3 record at 1 Hz one pass from the evolved point ended
#: 167 nats below where three more passes, each from the last one's result with a fresh
#: simplex, got to (the third gained 0.2 nat). ``find_start`` restarts while a pass gains
#: more than RESTART_GAIN nats, at most NM_RESTARTS times.
NM_RESTARTS = 6
RESTART_GAIN = 0.5
#: A Nelder-Mead pass of :func:`local_optimum` ends where its simplex spans at most
#: NM_XATOL in every coordinate of theta and NM_FATOL nats (read at call time).
NM_XATOL = 1e-6
NM_FATOL = 1e-6

#: Polish the rigid guess as well as each evolved point, and keep the higher log
#: posterior (False: only the evolved points). The evolution often ends in another basin
#: than the posterior's mode: on a paper-like record (B1 at 1.5 Hz, laboratory 1016) it
#: put b at 3,288 kg with the nut's and the bearing's stiffnesses exchanged, 219 nats below
#: the rigid guess's polish (b 10,421 kg; true 10,468), and that chain never left the basin
#: in 20,000 steps. Polishing the rigid guess only where the evolved b lay more than a
#: factor 2 from it missed smaller slips: over the 27 paper-like records of laboratory 11
#: the rigid guess's polish was higher on 11 (by more than 5 nats on 6, up to 21 nats,
#: A5 at 1 Hz), at about 1 s each (docs/inference.md).
POLISH_RIGID_GUESS = True

#: Factors of the polished start's discrepancy sd (``tau``, sampled by the harmonic and
#: motion-in likelihoods) at which :func:`find_start` polishes it again with ``tau``
#: held, largest first, before a last polish with everything free, keeping the result
#: where its log posterior is higher (:func:`tau_continued`). With ``tau`` large every
#: harmonic weighs alike and the polish can cross between basins that a small ``tau``
#: (a record with little noise) makes narrow valleys. Measured side by side
#: (results/start-continuation): on ten noise-free generator records it raised the start
#: on six by 1.1 to 340 nats (A4 at 0.5 Hz: b -2.25 % to +0.03 %) and lowered none; on
#: twelve noisy records of the model's own physics (SBC design seed 4) and eight
#: paper-like ones (laboratories 11 to 13) it moved the start by 0 to 0.8 nats; it costs
#: about 2 s a search. () leaves the search as before.
TAU_CONTINUATION: tuple = (1000.0, 100.0, 10.0)

#: The shares :func:`mirrored_modes` mirrors (x to 1 - x; in the raw parametrisation the
#: two frictions exchanged). The Coulomb force's split between plate and rotation is
#: what a record tells least, and its posterior often holds a mode at either end: on a
#: replicate of the model's own physics (simulation-based calibration, seed 4, replicate
#: 9, 0.5 Hz, true f_share 0.954) the start search ended at f_share 0.0002; the mirror,
#: polished, lay 4.1 nats higher at 0.99996. The chain from the first alone converged
#: (tau 45) with every draw below the truth; with half its walkers started at the mirror
#: it converged in 8,250 steps with f_share spread over 0.04 to 0.99 (3 % to 97 %) and
#: 0.89 of the draws below the truth. () leaves the search and the walkers as before.
MIRROR_SHARES = ("f_share",)

#: A mirrored optimum counts as a mode of its own, and gets half the initial walkers,
#: where it lies within this many nats of the start and its share differs by more than
#: :data:`MIRROR_SEPARATION` (**assumption**: a mode 10 nats down may still hold mass,
#: its volume being unknown; walkers started in a mode that holds little leave it
#: through the fitted independence move, and R-hat over walkers keeps the chain going
#: until they have).
MIRROR_NATS = 10.0
MIRROR_SEPARATION = 0.2

#: The parameters whose ridge :func:`held_modes` searches, each held at these factors of
#: its own value before it is freed (**assumption**; {} leaves the walkers as before).
#: Where the Coulomb force is large against the inertial one, the Coulomb and viscous
#: sums trade along a ridge broken into separate optima (the friction's split, the nut's
#: stiffness and the viscous split move with them). On the model's own physics
#: (simulation-based calibration, results/coverage-sbc-v9, seed 16) f_0's truth lay
#: above every draw and c_f's below every draw on 13 of 150 replicates, all with f_0
#: above 2,000 N. On replicate 36 (0.5 Hz, f_0 4,531 N, c_f 189 N s/m) the chain,
#: converged, sampled an optimum with c_f near 1,000 N s/m; held at a tenth of the
#: start's c_f and freed, the polish ended at f_0 4,531 N, c_f 178 N s/m, 5 nats above
#: the start, with a straight path between the two optima 500 nats down. On replicate
#: 102 (f_0 5,488 N, c_f 208 N s/m, the start at c_f 8,166) a tenth found an optimum at
#: c_f 1,071 and the truth's (c_f 263, 0.7 nats lower) took 0.03: the ladder walks to
#: a thirtieth and to thirty times.
HELD_MODES: dict = {"c_f": (0.3, 0.1, 0.03, 3.0, 10.0, 30.0)}
#: A held optimum counts as a mode of its own where its held parameter differs from the
#: start's by more than this in log (a factor of 2), and it lies within
#: :data:`MIRROR_NATS` of the start.
HELD_SEPARATION = math.log(2.0)

_BAD = 1e30


def _with_noise(model: PosteriorModel, phys: np.ndarray) -> np.ndarray:
    """theta with the noise entries (sigma, rho) at the middle of their prior's bounds:
    they change neither the simulation nor the residual, only keep the prior finite."""
    mid = model.bounds()[len(phys):].mean(axis=1)
    return np.concatenate([phys, mid])


def _kept_residual(model: PosteriorModel, phys: np.ndarray) -> np.ndarray | None:
    """The kept residual at the physical part of theta, or None where there is none."""
    theta = _with_noise(model, phys)
    got = model.misfit(theta) if math.isfinite(model.log_prior(theta)) else None
    return None if got is None else got[0]


def sse(model: PosteriorModel, phys: np.ndarray) -> float:
    """Sum of squared kept residuals at the physical part of theta (a stage-1 objective)."""
    r = _kept_residual(model, phys)
    return _BAD if r is None else float(r @ r)


def profiled_misfit(model: PosteriorModel, phys: np.ndarray) -> float:
    """Minus twice the record's log-likelihood at the physical part of theta with the
    noise profiled out (a stage-1 objective), up to a constant: n log s2 - log(1 - rho^2),
    rho the residual's lag-one correlation (within the prior's bounds) and s2 the AR(1)
    innovation variance it leaves; n log(SSE / n) for the "iid" residual."""
    r = _kept_residual(model, phys)
    if r is None:
        return _BAD
    n = len(r)
    ss = float(r @ r)
    if not ss > 0.0:
        return -_BAD
    if model.likelihood.residual == "iid":
        return n * math.log(ss / n)
    rho = float(np.clip(np.dot(r[1:], r[:-1]) / ss, RHO_BOUNDS[0], RHO_BOUNDS[1]))
    e = r[1:] - rho * r[:-1]
    s2 = ((1.0 - rho * rho) * r[0] ** 2 + float(e @ e)) / n
    return n * math.log(s2) - math.log(1.0 - rho * rho)


def harmonic_misfit(model: PosteriorModel, phys: np.ndarray) -> float:
    """Minus the harmonic likelihoods' log-likelihood at the physical part of theta, the
    discrepancy's scale set to the harmonic residual's rms there (a stage-1 objective of
    the harmonic and motion-in likelihoods)."""
    theta = _with_discrepancy_estimate(model, phys)
    if not math.isfinite(model.log_prior(theta)):
        return _BAD
    got = model.log_likelihood(theta)
    return _BAD if got is None or not math.isfinite(got[0]) else -got[0]


#: The stage-1 objectives of :func:`find_start`, each evolved once (see module docstring).
OBJECTIVES = {"sse": sse, "profiled": profiled_misfit, "harmonic": harmonic_misfit}


def default_objectives(model: PosteriorModel) -> tuple[str, ...]:
    """The stage-1 objectives a model's start searches with: its own likelihood's."""
    return ("harmonic",) if model.harmonic is not None else ("sse", "profiled")


def velocity_estimate(model: PosteriorModel) -> np.ndarray:
    """Velocity of terminal 1 (m/s): the derivative of the low-passed displacement when
    the record has one, else the integral of the low-passed acceleration from rest (a
    record starts at rest) less its straight-line drift (an accelerometer offset)."""
    rec = model.record
    fs = model.fs
    if rec.disp is not None:
        return np.gradient(lowpass(rec.disp, fs, model.likelihood.cutoff), 1.0 / fs)
    v = np.concatenate([[0.0], np.cumsum(0.5 * (model.measured_lp[1:] + model.measured_lp[:-1])) / fs])
    t = rec.time - rec.time[0]
    slope, intercept = np.polyfit(t, v, 1)
    return v - (slope * t + intercept)


def rigid_guess(model: PosteriorModel) -> dict:
    """Total mass, Coulomb and viscous friction of one rigid body, by least squares.

    F = M a + f0 sgn(v) + c v on the low-passed signals (v from
    :func:`velocity_estimate`). Returns the free parameters' values (SI units):
    b = M - m_B - m_s, the Coulomb force split 95/5 between plate and rotation (a guess
    the sampler corrects), the viscous part given to the rotation.
    """
    fs = model.fs
    a = model.measured_lp
    f = lowpass(model.record.force, fs, model.likelihood.cutoff)
    v = velocity_estimate(model)
    w = model.window
    X = np.column_stack([a[w], np.tanh(v[w] / (0.02 * np.std(v[w]) + 1e-12)), v[w]])
    coef, *_ = np.linalg.lstsq(X, f[w], rcond=None)
    mass, f0, c = coef
    b = max(mass - model.m_B - model.m_s, 1.0)
    f0, c = max(abs(f0), 1.0), max(c, 1.0)
    guess = {"b": b, "f1_0": 0.95 * f0, "f2_0": 0.05 * f0, "c_f1": 0.01 * c, "c_f2": c}
    if model.model == "rigid":
        guess.update(f1_0=f0, c_f1=c)
    return {k: v for k, v in guess.items() if k in model.free}


def _initial_point(model: PosteriorModel) -> np.ndarray:
    """The rigid guess where it applies, the prior's centre elsewhere, within bounds."""
    n = model.n_phys
    bounds = model.bounds()[:n]
    guess = model.sampled_from_physical(rigid_guess(model))
    x = []
    for name, (lo, hi) in zip(model.names[:n], bounds):
        if name in guess:
            x.append(math.log(guess[name]) if model.all_priors[name].log_scale else guess[name])
        else:
            x.append(0.5 * (lo + hi))
    return np.clip(np.array(x), bounds[:, 0] + 1e-9, bounds[:, 1] - 1e-9)


def _swaps(model: PosteriorModel, x: np.ndarray) -> list[np.ndarray]:
    """x and its copies with the plate and rotation frictions exchanged (:func:`_mirror`
    of each share, and of both): the two sit on a ridge (MODEL.md section 7), and the
    optimiser often stops on the wrong side."""
    out = [x]
    for share in ("f_share", "c_share"):
        for y in list(out):
            z, _ = _mirror(model, y, share)
            if z is not None:
                out.append(z)
    return out


def find_start(model: PosteriorModel, rng: np.random.Generator, *, popsize=DE_POPSIZE, maxiter=None,
               objectives=None, many=None, continuation=None, mirrors=None, map=None):
    """Return (theta, log posterior) of a quick optimum (see module docstring).

    ``objectives``: names of :data:`OBJECTIVES` evolved in stage 1, each in turn with the
    same ``rng`` (None: :func:`default_objectives`). ``maxiter``: generations of each
    evolution (None: :data:`DE_MAXITER` as it is when called). ``many``: optional
    callable(name, list of physical parameter vectors) giving the objective ``name`` at
    each (for example on a process pool): differential evolution then evaluates each
    generation through it. The result does not depend on it. ``continuation``: the
    factors of :func:`tau_continued` (None: :data:`TAU_CONTINUATION` as it is when
    called; (): none). ``mirrors``: the shares whose mirrors the search polishes and
    keeps where higher (:func:`mirrored_modes`; None: :data:`MIRROR_SHARES` as it is
    when called). ``map``: callable(fn, items) giving ``fn(model, item)`` for each item in
    order (for example on worker processes holding the model): the polishes that do not
    depend on one another run through it. The result does not depend on it either.
    """
    maxiter = DE_MAXITER if maxiter is None else maxiter
    objectives = default_objectives(model) if objectives is None else tuple(objectives)
    unknown = [name for name in objectives if name not in OBJECTIVES]
    if unknown or not objectives:
        raise ValueError(f"start objectives must be some of {', '.join(OBJECTIVES)}, got {list(objectives)}")
    # every evolution first (they share ``rng``, in turn), then their polishes and the
    # rigid guess's, which depend on nothing but their point, at once where ``map`` runs them
    points = [_with_noise_estimate(model, _evolve(model, name, rng, popsize, maxiter, many)) for name in objectives]
    if POLISH_RIGID_GUESS:
        points.append(_with_noise_estimate(model, _initial_point(model)))
    best = None
    for theta, lp in _each(model, map, polished, points):
        if best is None or lp > best[1]:
            best = (theta, lp)
    continued = tau_continued(model, best[0], continuation)
    if continued is not None and continued[1] > best[1]:
        best = continued
    for theta, lp in mirrored_modes(model, best[0], best[1], nats=math.inf, shares=mirrors, map=map):
        if lp > best[1]:
            best = (theta, lp)
    return best


def polished(model: PosteriorModel, theta: np.ndarray) -> tuple:
    """(theta, log posterior) of :func:`local_optimum` with :data:`NM_RESTARTS` restarts
    from ``theta``: one of the start's polishes, as a function a worker can run."""
    got, lp = local_optimum(model, theta, restarts=NM_RESTARTS)
    return got, float(lp)


def _each(model, map, fn, items) -> list:
    """``fn(model, item)`` for each item, in order: here one after the other, or through
    ``map`` (callable(fn, items), for example on worker processes holding the model)."""
    items = list(items)
    if map is None:
        return [fn(model, item) for item in items]
    return list(map(fn, items))


def tau_continued(model: PosteriorModel, theta: np.ndarray, factors: tuple | None = None):
    """(theta, log posterior) of ``theta`` polished with the discrepancy's sd held at each
    of ``factors`` (None: :data:`TAU_CONTINUATION`) times its own in turn, then with
    everything free; None where the model samples no ``tau`` or there are no factors."""
    factors = TAU_CONTINUATION if factors is None else tuple(factors)
    names = list(model.names)
    if not factors or "tau" not in names:
        return None
    i = names.index("tau")
    lo, hi = model.bounds()[i]
    log_scale = model.all_priors["tau"].log_scale
    t = np.array(theta, dtype=float)
    own = t[i]
    for f in factors:
        level = float(np.clip(own + math.log(f) if log_scale else own * f, lo, hi))
        t = held_optimum(model, t, i, level)
    return local_optimum(model, t, restarts=NM_RESTARTS)


def held_optimum(model: PosteriorModel, theta: np.ndarray, i: int, value: float) -> np.ndarray:
    """``theta`` with entry ``i`` set to ``value`` and the others polished (Nelder-Mead
    with restarts as :func:`local_optimum`'s) with it held there."""
    base = np.array(theta, dtype=float)
    base[i] = value
    free = np.arange(len(base)) != i

    def at(x):
        t = base.copy()
        t[free] = x
        return t

    x, _ = local_optimum(model, base[free], restarts=NM_RESTARTS, log_prob=lambda x: model.log_prob(at(x)))
    return at(x)


def mirrored_modes(model: PosteriorModel, theta: np.ndarray, lp: float, *, nats: float | None = None,
                   shares: tuple | None = None, map=None) -> list:
    """The optima that ``theta``'s mirrors reach (``shares``, default :data:`MIRROR_SHARES`,
    each share x at 1 - x, polished by :func:`local_optimum` with restarts), as (theta,
    log posterior), those apart from ``theta`` by more than :data:`MIRROR_SEPARATION` in
    the share and within ``nats`` (default :data:`MIRROR_NATS`) of ``lp``; [] for a model
    without those shares. ``map``: as :func:`held_modes`' (the mirrors' polishes at once)."""
    nats = MIRROR_NATS if nats is None else nats
    shares = MIRROR_SHARES if shares is None else tuple(shares)
    unknown = [s for s in shares if s not in _RAW_PAIRS]
    if unknown:
        raise ValueError(f"mirrored shares must be some of {', '.join(_RAW_PAIRS)}, got {list(shares)}")
    mirrored = [_mirror(model, np.asarray(theta, dtype=float), share) for share in shares]
    mirrored = [(mirror, distance) for mirror, distance in mirrored if mirror is not None]
    out = []
    for (_, distance), (got, got_lp) in zip(mirrored, _each(model, map, polished, [m for m, _ in mirrored])):
        if math.isfinite(got_lp) and got_lp > lp - nats and distance(got) > MIRROR_SEPARATION:
            out.append((got, float(got_lp)))
    return out


def held_modes(model: PosteriorModel, theta: np.ndarray, lp: float, *, nats: float | None = None,
               holds: dict | None = None, map=None) -> list:
    """The optima reached from ``theta`` with a parameter held away from its value and
    then freed (``holds``, default :data:`HELD_MODES`: for each parameter, the factors it
    is held at, walked outwards from 1 in each direction, each held polish started from
    the one before; :func:`held_optimum`, then :func:`local_optimum` with restarts), as
    (theta, log posterior): those whose held parameter ended more than
    :data:`HELD_SEPARATION` in log from ``theta``'s, within ``nats`` (default
    :data:`MIRROR_NATS`) of ``lp``, and apart from one another. A parameter the model
    does not sample, or does not sample in log scale, is passed over.

    ``map``: callable(fn, walks) giving ``fn(model, walk)`` for each walk in order (for
    example on a process pool, each worker holding the model): the walks, one per
    parameter and direction, are independent, so they may run at once. The result does
    not depend on it (None: one after the other, here)."""
    nats = MIRROR_NATS if nats is None else nats
    holds = HELD_MODES if holds is None else dict(holds)
    names = list(model.names)
    theta = np.asarray(theta, dtype=float)
    walks = []
    for name, factors in holds.items():
        if name not in names or not model.all_priors[name].log_scale:
            continue
        i = names.index(name)
        lo, hi = model.bounds()[i]
        if not all(f > 0 for f in factors):
            raise ValueError(f"held factors must be positive, got {tuple(factors)} for {name}")
        for ladder in (sorted((f for f in factors if f < 1), reverse=True), sorted(f for f in factors if f > 1)):
            if ladder:
                walks.append((theta, i, tuple(ladder), float(lo), float(hi)))
    out = []
    for (_, i, _, _, _), points in zip(walks, _each(model, map, held_walk, walks)):
        for got, got_lp in points:
            apart = all(abs(float(got[i] - other[i])) > HELD_SEPARATION for other, _ in out)
            if (math.isfinite(got_lp) and got_lp > lp - nats and abs(float(got[i] - theta[i])) > HELD_SEPARATION
                    and apart):
                out.append((got, float(got_lp)))
    return out


def held_walk(model: PosteriorModel, walk: tuple) -> list:
    """One direction of :func:`held_modes`' ladder, ``walk`` = (theta, i, factors, lo,
    hi): entry ``i`` held at each factor in turn (walked outwards, each held polish
    started from the one before, clipped at the prior's bounds ``lo``, ``hi``), then
    freed; every freed optimum as (theta, log posterior), before any is kept."""
    theta, i, ladder, lo, hi = walk
    theta = np.asarray(theta, dtype=float)
    held = theta
    points = []
    for factor in ladder:
        level = float(np.clip(theta[i] + math.log(factor), lo, hi))
        if abs(level - held[i]) < 1e-12 and held is not theta:
            break  # clipped at the prior's bound: the rest of the ladder is the same point
        held = held_optimum(model, held, i, level)
        points.append(polished(model, held))
    return points


_RAW_PAIRS = {"f_share": ("f1_0", "f2_0"), "c_share": ("c_f1", "c_f2")}


def _mirror(model: PosteriorModel, theta: np.ndarray, share: str):
    """(theta with ``share`` mirrored, a function giving a point's distance from theta in
    that share), or (None, None) where the model has no such share."""
    names = list(model.names)
    if share in names:
        i = names.index(share)
        out = theta.copy()
        out[i] = 1.0 - theta[i]
        return out, lambda x: abs(float(x[i]) - float(theta[i]))
    a, b = _RAW_PAIRS.get(share, (None, None))
    if a in names and b in names:
        i, j = names.index(a), names.index(b)
        values = model.values

        def fraction(x):
            v = values(x)
            total = v[a] + v[b]
            return v[a] / total if total > 0 else 0.5

        out = theta.copy()
        out[i], out[j] = theta[j], theta[i]
        return out, lambda x: abs(fraction(x) - fraction(theta))
    return None, None


def _evolve(model: PosteriorModel, name: str, rng: np.random.Generator, popsize, maxiter, many) -> np.ndarray:
    """Stage 1 for one objective: the physical parameters differential evolution ends at
    (or the rigid guess, or either's friction swap, whichever the objective prefers)."""
    objective = OBJECTIVES[name]
    bounds = model.bounds()[: model.n_phys]
    # the noise entries are not optimised in stage 1: fix them mid-prior so the prior is finite
    x0 = _initial_point(model)
    workers = (lambda _func, xs: many(name, list(xs))) if many is not None else 1
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        de = differential_evolution(
            lambda x: objective(model, x), bounds, popsize=popsize, maxiter=maxiter,
            seed=rng, polish=False, init="sobol", tol=1e-8, updating="deferred",
            x0=x0, workers=workers,
        )
    return min(_swaps(model, de.x) + _swaps(model, x0), key=lambda x: objective(model, x))


def _with_noise_estimate(model: PosteriorModel, phys: np.ndarray) -> np.ndarray:
    """theta at ``phys`` with sigma the residual's sd and rho its lag-one correlation;
    for the harmonic likelihoods, tau the harmonic residual's rms, alpha 0 and gain 1."""
    if model.harmonic is not None:
        return _with_discrepancy_estimate(model, phys)
    _, _, sim = model.evaluate(_with_noise(model, phys))
    r = sim[model.grid] - model.observed
    sigma = max(float(np.std(r)), 1e-5)
    theta = list(phys) + [math.log(sigma)]
    if model.likelihood.residual == "ar1":
        rho = float(np.corrcoef(r[1:], r[:-1])[0, 1]) if np.std(r) > 0 else 0.0
        theta.append(float(np.clip(rho, RHO_BOUNDS[0] + 0.01, RHO_BOUNDS[1] - 0.01)))
    return np.array(theta)


def _with_discrepancy_estimate(model: PosteriorModel, phys: np.ndarray) -> np.ndarray:
    theta = _with_noise(model, phys)
    # a white discrepancy of the residual's size, the friction law's deviations at their fixed scale
    start = {"tau": 1e-4, "alpha": 0.0, "gain": 1.0, "delay": 0.0, "law": friction_law.SD}
    try:
        if model.motion is not None:
            r = model.harmonic.force - predicted_force(model.motion, model.field_vector(theta),
                                                       effects=model.effects(theta))[0]
        else:
            r = model.harmonic.accel - model.harmonic.mean_amplitudes(model.simulate_unfiltered(theta))
        if np.all(np.isfinite(r)):
            start["tau"] = float(np.sqrt(np.mean(np.abs(r) ** 2)))
    except (SimulationError, ValueError):
        pass
    for name, value in start.items():
        if name in model.names:
            prior = model.all_priors[name]
            lo, hi = prior.bounds
            t = math.log(value) if prior.log_scale else value
            margin = min(0.01, 0.25 * (hi - lo))  # a narrow box (a delay's, in s) keeps its middle half
            theta[model.names.index(name)] = float(np.clip(t, lo + margin, hi - margin))
    return theta


def local_optimum(model: PosteriorModel, theta: np.ndarray, *, maxiter: int | None = None, restarts: int = 0,
                  log_prob=None):
    """(theta, log posterior) of the optimum Nelder-Mead reaches from ``theta`` (or
    ``theta`` itself if it finds nothing better) in ``maxiter`` iterations a pass (None:
    :data:`NM_MAXITER` as it is when called). With ``restarts`` > 0 it starts again
    from its result, with a fresh simplex, while a pass gains more than
    :data:`RESTART_GAIN` nats, at most ``restarts`` more passes. ``log_prob``: the same
    function as ``model.log_prob`` computed elsewhere (``joint.pooled_log_prob``)."""
    log_prob = log_prob or model.log_prob
    maxiter = NM_MAXITER if maxiter is None else maxiter

    def neg(x):
        lp, _ = log_prob(x)
        return -lp if math.isfinite(lp) else _BAD

    best = np.asarray(theta, dtype=float)
    f_best = neg(best)
    for _ in range(restarts + 1):
        res = minimize(neg, best, method="Nelder-Mead",
                       options={"maxiter": maxiter, "xatol": NM_XATOL, "fatol": NM_FATOL})
        gain = f_best - res.fun
        if gain > 0:
            best, f_best = res.x, float(res.fun)
        if not gain > RESTART_GAIN:
            break
    return best, log_prob(best)[0]


#: Initial walkers whose log posterior falls more than this many sd of a chi-square's
#: half below the optimum's are drawn again (see :func:`laplace_ensemble`).
INIT_SD = 4.0


def _unit(model: PosteriorModel):
    """Map theta to the prior's unit box and back (the Hessian is taken there)."""
    bounds = model.bounds()
    lo, width = bounds[:, 0], bounds[:, 1] - bounds[:, 0]
    return (lambda theta: (theta - lo) / width), (lambda u: lo + u * width)


def _fd_steps(f, u0: np.ndarray, f0: float) -> np.ndarray:
    """Per coordinate, a step that lowers f by about one nat (halving from a quarter of
    the unit box; flat coordinates keep the quarter)."""
    steps = np.full(len(u0), 0.25)
    for i in range(len(u0)):
        h = 0.25
        for _ in range(40):
            drops = []
            for sgn in (1.0, -1.0):
                u = u0.copy()
                u[i] += sgn * h
                drops.append(f0 - f(u) if 0.0 <= u[i] <= 1.0 else np.inf)
            if min(drops) <= 2.0:
                break
            h *= 0.5
        steps[i] = h
    return steps


def _unit_objective(model, theta):
    """The log posterior on the prior's unit box (-inf outside), counting its calls."""
    to_u, from_u = _unit(model)
    n_evals = [0]

    def f(u):
        n_evals[0] += 1
        if np.any(u < 0.0) or np.any(u > 1.0):
            return -np.inf
        lp, _ = model.log_prob(from_u(u))
        return lp

    return f, to_u(np.asarray(theta, dtype=float)), from_u, n_evals


def _tempered(model, f, from_u, beta: float):
    """``f`` (the log posterior on the unit box) with its log-likelihood raised to the
    power ``beta``: log prior + beta x (f - log prior)."""
    def f_beta(u):
        lp = f(u)
        if not math.isfinite(lp):
            return lp
        prior = model.log_prior(from_u(u))
        return prior + beta * (lp - prior)
    return f_beta


def _hessian(f, u0: np.ndarray, f0: float) -> np.ndarray:
    """Central-difference Hessian of f at u0 with steps from :func:`_fd_steps`."""
    d = len(u0)
    h = _fd_steps(f, u0, f0)
    H = np.zeros((d, d))
    for i in range(d):
        e_i = np.zeros(d)
        e_i[i] = h[i]
        fp, fm = f(u0 + e_i), f(u0 - e_i)
        H[i, i] = (fp - 2 * f0 + fm) / h[i] ** 2 if np.isfinite(fp + fm) else 0.0
        for j in range(i):
            e_j = np.zeros(d)
            e_j[j] = h[j]
            quad = [f(u0 + e_i + e_j), f(u0 + e_i - e_j), f(u0 - e_i + e_j), f(u0 - e_i - e_j)]
            H[i, j] = H[j, i] = (quad[0] - quad[1] - quad[2] + quad[3]) / (4 * h[i] * h[j]) if np.all(np.isfinite(quad)) else 0.0
    return H


def whitened_optimum(model: PosteriorModel, theta: np.ndarray, *, rounds: int = 6, maxiter: int = 2000):
    """(theta, log posterior) of Nelder-Mead run in coordinates whitened by the Hessian.

    Each round takes the Hessian at the current point in the prior's unit box
    (:func:`_hessian`), maps every direction to one sd of its normal approximation (a
    direction the data leave flat or curved the wrong way to 0.3 of the box), and runs
    Nelder-Mead there from a simplex one sd wide, for ``maxiter`` iterations; rounds go
    on while one gains more than :data:`RESTART_GAIN` nats, at most ``rounds``. Plain
    Nelder-Mead's simplex collapses across a narrow curved ridge; whitened, the ridge
    is as wide as it is long near the point, and the simplex follows it.

    Not part of :func:`find_start`: on the generator's noise-free records it takes the
    start to the ridge's top but not b nearer the truth (results/noise-free-chains-v3).
    Returns ``theta`` itself where it finds nothing higher.
    """
    f, u, from_u, _ = _unit_objective(model, theta)
    f_u = f(u)
    if not math.isfinite(f_u):
        raise ValueError("the point has zero posterior density; there is nothing to polish from")
    d = len(u)
    for _ in range(rounds):
        root = _laplace_root(_hessian(f, u, f_u), curved=1.0, flat_var=0.09)

        def neg(z, u=u, root=root):
            value = f(u + root @ z)
            return -value if math.isfinite(value) else _BAD

        res = minimize(neg, np.zeros(d), method="Nelder-Mead",
                       options={"maxiter": maxiter, "xatol": 1e-4, "fatol": 1e-3,
                                "initial_simplex": np.vstack([np.zeros(d), np.eye(d)])})
        gain = -float(res.fun) - f_u
        if gain > 0:
            u, f_u = u + root @ res.x, -float(res.fun)
        if not gain > RESTART_GAIN:
            break
    return from_u(u), f_u


def _laplace_root(H: np.ndarray, curved: float = 12.0, flat_var: float = 1.0 / 12.0) -> np.ndarray:
    """A square root of the normal approximation's covariance in the unit box: the
    inverse of -H along the eigenvectors the data curve by more than ``curved`` (by
    default 12, the prior's precision: a uniform's variance is 1/12 of its box), and the
    variance ``flat_var`` (by default the prior's) along the rest."""
    lam, vec = np.linalg.eigh(-0.5 * (H + H.T))
    var = np.where(lam > curved, 1.0 / np.where(lam > curved, lam, 1.0), flat_var)
    return vec * np.sqrt(var)


def laplace_covariance(model: PosteriorModel, theta: np.ndarray) -> np.ndarray:
    """Covariance of theta in the normal (Laplace) approximation at ``theta``, with every
    direction the data leave flat given the prior's spread (see :func:`laplace_ensemble`)."""
    f, u0, _, _ = _unit_objective(model, theta)
    root = _laplace_root(_hessian(f, u0, f(u0)))
    width = np.diff(model.bounds(), axis=1)[:, 0]
    return (root @ root.T) * np.outer(width, width)


def laplace_ensemble(model: PosteriorModel, theta: np.ndarray, nwalkers: int, rng: np.random.Generator,
                     accept=None, beta: float = 1.0):
    """Initial walkers spread like the posterior near the optimum ``theta``.

    The Hessian of the log posterior at ``theta`` is taken by central differences in
    the prior's unit box, with a step per coordinate that lowers it by about one nat.
    Its inverse is the covariance of a normal approximation, where every direction the
    data leave flat (or curved the wrong way) gets the spread of the prior (variance
    1/12 of the box). Walkers are drawn from it, and a draw outside the prior or whose
    log posterior lies more than ``INIT_SD`` sd of chi-square(ndim)/2 below the
    optimum's is drawn again (the spread is halved after every 20 x nwalkers tries).

    Walkers started in a tiny ball must first expand across the directions the data do
    not fix (bearing damping, nut stiffness, the viscous split, spanning orders of
    magnitude), which lengthens the burn-in and inflates the autocorrelation estimate;
    walkers started like this begin near equilibrium. ``accept``: an optional test of a
    drawn theta (for example, that it lies in the sampler coordinates' domain); a draw
    it refuses is drawn again too.

    ``beta`` < 1: the same for the tempered posterior, log prior + ``beta`` x
    log-likelihood (a hot ensemble of parallel tempering, :mod:`.tempering`): its
    Hessian and its floor are that density's, so the walkers spread about
    1 / sqrt(beta) times wider where the data fix them, and as wide as the prior where
    they do not. Hot ensembles drawn at the posterior's own spread start far narrower
    than their equilibrium, and until they reach it their swaps carry the mode's draws
    down into the posterior's ensemble and its tails up (measured: docs/inference.md,
    "Tempering on bent ridges").
    Returns (nwalkers, ndim) and the number of log-posterior evaluations spent.
    """
    if not 0.0 < beta <= 1.0:
        raise ValueError(f"a tempered ensemble's beta must lie in (0, 1], got {beta}")
    f, u0, from_u, n_evals = _unit_objective(model, theta)
    if beta != 1.0:
        f = _tempered(model, f, from_u, beta)
    f0 = f(u0)
    if not math.isfinite(f0):
        raise ValueError("the start has zero posterior density (outside the prior, or the record cannot be "
                         "simulated there); no walkers can be drawn around it")
    d = len(u0)
    root = _laplace_root(_hessian(f, u0, f0))
    floor = f0 - (0.5 * d + INIT_SD * math.sqrt(0.5 * d))
    walkers, scale, tries = [], 1.0, 0
    while len(walkers) < nwalkers:
        u = u0 + scale * root @ rng.standard_normal(d)
        fu = f(u)
        if math.isfinite(fu) and fu >= floor and (accept is None or accept(from_u(u))):
            walkers.append(u)
        tries += 1
        if tries % (20 * nwalkers) == 0:
            scale *= 0.5
    return np.array([from_u(u) for u in walkers]), n_evals[0]
