"""Sampling with emcee: HDF5 checkpoints, resume, and a convergence loop.

The chain is written to an HDF5 file (emcee's ``HDFBackend``) at every step, with the
sampler's random state, so a run that is killed can be continued: running again with the
same checkpoint adds only the missing steps, and the steps already taken are kept as
they are. A checkpoint written for another model, record or number of walkers is
refused with a one-line error rather than overwritten, and so is one damaged on disk:
every step is sealed into a running sha256 checksum stored with the chain, checked
before a run continues it.

Convergence (documented defaults, :class:`Convergence`): emcee's integrated
autocorrelation time tau (``get_autocorr_time(tol=0)``) per parameter, checked every
``check_every`` steps; converged when the chain is longer than ``n_tau`` times the
largest tau, tau moved less than ``tau_rtol`` since the last check, and, after
discarding 2 tau of burn-in, R-hat < ``max_rhat`` and bulk ESS >= ``min_ess`` (arviz,
treating walkers as chains: they are not independent, so R-hat here is a check that no
walker is stuck apart from the others, not a proof). Or stops at ``max_steps``.
"""

from __future__ import annotations

import hashlib
import multiprocessing
from dataclasses import dataclass

import emcee
import numpy as np

from .model import PosteriorModel
from .optimize import find_start, laplace_ensemble, sse

__all__ = ["Convergence", "CheckpointError", "SamplerRun", "run_sampler", "record_digest", "check_run_options"]

#: Stretch and differential-evolution moves: DE moves travel along the friction ridges.
DEFAULT_MOVES = [(emcee.moves.DEMove(), 0.6), (emcee.moves.DESnookerMove(), 0.1), (emcee.moves.StretchMove(), 0.3)]


def default_walkers(ndim: int) -> int:
    """Default walkers: twice the parameters plus two (24 for the two-port model's 11).
    A converged run costs walkers x 50 tau evaluations, so the default is near the
    fewest the moves need (2 ndim), with a margin; more walkers is an option."""
    return 2 * ndim + 2


class CheckpointError(ValueError):
    """A checkpoint that cannot be continued (corrupt, or made for another run)."""


@dataclass(frozen=True)
class Convergence:
    """When an open-ended run stops (see module docstring)."""

    n_tau: float = 50.0
    tau_rtol: float = 0.05
    max_rhat: float = 1.05
    min_ess: float = 400.0
    check_every: int = 500
    max_steps: int = 20_000

    def __post_init__(self) -> None:
        for name in ("n_tau", "tau_rtol", "max_rhat", "min_ess"):
            if not getattr(self, name) > 0:
                raise ValueError(f"convergence setting {name} must be positive, got {getattr(self, name)}")
        for name in ("check_every", "max_steps"):
            value = getattr(self, name)
            if not (isinstance(value, int) and value >= 1):
                raise ValueError(f"convergence setting {name} must be a positive whole number, got {value!r}")


@dataclass
class SamplerRun:
    """What a run produced: the sampler (chain in its backend) and convergence facts."""

    sampler: emcee.EnsembleSampler
    converged: bool
    tau: np.ndarray
    reason: str
    start_theta: np.ndarray | None = None

    @property
    def iteration(self) -> int:
        return self.sampler.iteration


def record_digest(model: PosteriorModel) -> str:
    """Identity of the data a checkpoint belongs to (record arrays and model settings);
    for a joint model (``model.parts``), of every record's part and the joint names."""
    h = hashlib.sha256()
    parts = getattr(model, "parts", None)
    for part in parts or [model]:
        rec = part.record
        for arr in (rec.time, rec.force, rec.accel):
            h.update(np.ascontiguousarray(arr, dtype=float).tobytes())
        h.update(repr((part.model, part.names, part.m_s, part.m_B, part.likelihood, sorted(
            (k, repr(v)) for k, v in part.all_priors.items()))).encode())
    if parts:
        h.update(repr(("joint", model.names)).encode())
    return h.hexdigest()[:16]


class _Backend(emcee.backends.HDFBackend):
    """emcee's HDF5 backend, opening the file without HDF5's advisory lock.

    With the lock, anyone reading ``chain.h5`` while a run writes it (h5py, a viewer)
    makes the run's next write fail with BlockingIOError and the run stop (seen here).
    A reader may then see a step half-written; the writer never fails. Same logic as
    ``HDFBackend.open`` (emcee 3.1) otherwise.
    """

    def open(self, mode="r"):
        import h5py

        if self.read_only and mode != "r":
            raise RuntimeError("the backend is read-only")
        f = h5py.File(self.filename, mode, locking=False)
        if not self.dtype_set and self.name in f:
            g = f[self.name]
            if "chain" in g:
                self.dtype = g["chain"].dtype
                self.dtype_set = True
        return f


# The log-probability for worker processes: a top-level function over a module global set
# before the pool forks, so that only the parameter vector is pickled per call.
_MODEL: PosteriorModel | None = None


def _log_prob(theta):
    return _MODEL.log_prob(theta)


def _sse(phys):
    return sse(_MODEL, phys)


def _open_backend(path, model: PosteriorModel, nwalkers: int, fresh: bool):
    """An HDF backend ready to sample into, and the steps it already holds."""
    import h5py

    digest = record_digest(model)
    if fresh and path.exists():
        path.unlink()  # the user asked to start over
    backend = _Backend(str(path), name="mcmc")
    if not path.exists():
        return backend, 0, digest
    try:
        with h5py.File(path, "r", locking=False) as f:
            if "mcmc" not in f:
                return backend, 0, digest
            attrs = dict(f["mcmc"].attrs)
        iteration = backend.iteration
        shape = backend.shape
    except Exception as exc:  # h5py raises OSError, KeyError, ValueError for damaged files
        raise CheckpointError(
            f"{path}: checkpoint is unreadable or truncated ({type(exc).__name__}); "
            "move it away to keep it, or run with --fresh to start over"
        ) from None
    if attrs.get("bayes_inerter_digest") != digest:
        raise CheckpointError(
            f"{path}: checkpoint belongs to another record, model or settings; "
            "use another output folder, or --fresh to start over"
        )
    if shape != (nwalkers, model.ndim):
        raise CheckpointError(
            f"{path}: checkpoint has {shape[0]} walkers and {shape[1]} parameters, this run "
            f"{nwalkers} and {model.ndim}; use the same --walkers, or --fresh"
        )
    try:
        intact = _checksum_holds(backend)
    except Exception:  # a damaged dataset fails here rather than at the first write
        intact = False
    if not intact:
        raise CheckpointError(
            f"{path}: checkpoint's steps do not match their checksum (damaged on disk); it is left "
            "as it is: move it away to keep it, or run with --fresh to start over"
        )
    return backend, iteration, digest


#: The checkpoint's running checksum: sha256 chained over every step's positions and
#: log probabilities (h_k = sha256(h_{k-1} + chain[k] + log_prob[k])), and the steps it covers.
_SUM, _SUMMED = "bayes_inerter_chain_sha256", "bayes_inerter_summed_steps"


def _step_hash(h: bytes, chain_row: np.ndarray, lp_row: np.ndarray) -> bytes:
    return hashlib.sha256(h + np.ascontiguousarray(chain_row).tobytes() + np.ascontiguousarray(lp_row).tobytes()).digest()


def _seal(backend) -> None:
    """Extend the checksum over the steps written since the last seal (after every step;
    a run killed between a step and its seal leaves at most that step unsummed)."""
    with backend.open("a") as f:
        g = f[backend.name]
        n, k = int(g.attrs["iteration"]), int(g.attrs.get(_SUMMED, 0))
        h = bytes.fromhex(g.attrs.get(_SUM, ""))
        for i in range(k, n):
            h = _step_hash(h, g["chain"][i], g["log_prob"][i])
        g.attrs[_SUM] = h.hex()
        g.attrs[_SUMMED] = n


def _checksum_holds(backend) -> bool:
    """Whether the summed steps still match their checksum (True for a checkpoint written
    before checksums existed)."""
    with backend.open("r") as f:
        g = f[backend.name]
        if _SUM not in g.attrs:
            return True
        k = int(g.attrs[_SUMMED])
        chain, lp = g["chain"][:k], g["log_prob"][:k]
        h = b""
        for i in range(k):
            h = _step_hash(h, chain[i], lp[i])
        return h.hex() == g.attrs[_SUM]


def _diagnostics(sampler, conv: Convergence):
    from .diagnostics import rhat_ess

    tau = sampler.get_autocorr_time(tol=0)
    burn = int(2 * np.nanmax(tau)) if np.all(np.isfinite(tau)) else sampler.iteration // 2
    rhat, ess = rhat_ess(sampler.get_chain(discard=min(burn, sampler.iteration - 2)))
    return tau, rhat, ess


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
    start=None,
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
    start : optional (theta, log prob) to start from instead of the optimiser; the
        walkers are drawn around it by ``optimize.laplace_ensemble``.
    """
    from pathlib import Path

    global _MODEL
    conv = convergence or Convergence()
    checkpoint = Path(checkpoint)
    nwalkers = check_run_options(model.ndim, nwalkers, steps)
    backend, done, digest = _open_backend(checkpoint, model, nwalkers, fresh)
    if done == 0:
        backend.reset(nwalkers, model.ndim)
        with backend.open("a") as f:
            f["mcmc"].attrs["bayes_inerter_digest"] = digest
            f["mcmc"].attrs["parameter_names"] = ",".join(model.names)
    _MODEL = model
    pool = multiprocessing.get_context("fork").Pool(processes) if processes > 1 else None
    try:
        sampler = emcee.EnsembleSampler(
            nwalkers, model.ndim, _log_prob, pool=pool, moves=moves or DEFAULT_MOVES,
            backend=backend, blobs_dtype=float,
        )
        start_theta = None
        if done == 0:
            rng = np.random.default_rng(seed)
            if start is None:
                sse_many = (lambda xs: pool.map(_sse, xs)) if pool is not None else None
                start = find_start(model, rng, sse_many=sse_many)
            start_theta = np.asarray(start[0], dtype=float)
            sampler.random_state = np.random.RandomState(seed).get_state()
            state, _ = laplace_ensemble(model, start_theta, nwalkers, rng)
        else:
            # continue from the checkpoint's last state, with its random state
            state = backend.get_last_sample()
        target = steps
        tau = np.full(model.ndim, np.nan)
        if steps is not None:
            n_more = steps - done
            if n_more > 0:
                for _ in sampler.sample(state, iterations=n_more, store=True):
                    _seal(backend)
                    if progress:
                        progress(sampler.iteration, target)
            tau, rhat, ess = _diagnostics(sampler, conv)
            ok = _is_converged(sampler.iteration, tau, None, rhat, ess, conv)
            reason = "converged" if ok else _why_not(sampler.iteration, tau, rhat, ess, conv)
            return SamplerRun(sampler, ok, tau, reason, start_theta)
        previous = None
        while True:
            chunk = min(conv.check_every, conv.max_steps - sampler.iteration)
            if chunk > 0:
                for _ in sampler.sample(state, iterations=chunk, store=True):
                    _seal(backend)
                    if progress:
                        progress(sampler.iteration, None)
                state = sampler.get_last_sample()
            tau, rhat, ess = _diagnostics(sampler, conv)
            if _is_converged(sampler.iteration, tau, previous, rhat, ess, conv):
                return SamplerRun(sampler, True, tau, "converged", start_theta)
            if sampler.iteration >= conv.max_steps:
                return SamplerRun(sampler, False, tau, _why_not(sampler.iteration, tau, rhat, ess, conv), start_theta)
            previous = tau
    finally:
        if pool is not None:
            pool.close()
            pool.join()
        _MODEL = None


def _is_converged(iteration, tau, previous, rhat, ess, conv: Convergence) -> bool:
    if not np.all(np.isfinite(tau)):
        return False
    if iteration < conv.n_tau * np.max(tau):
        return False
    if previous is not None and np.all(np.isfinite(previous)):
        if np.max(np.abs(tau - previous) / tau) > conv.tau_rtol:
            return False
    return bool(np.nanmax(rhat) < conv.max_rhat and np.nanmin(ess) >= conv.min_ess)


def _why_not(iteration, tau, rhat, ess, conv: Convergence) -> str:
    parts = []
    if np.all(np.isfinite(tau)):
        need = conv.n_tau * np.max(tau)
        if iteration < need:
            parts.append(f"chain of {iteration} steps is shorter than {conv.n_tau:g} tau = {need:.0f}")
    else:
        parts.append("autocorrelation time not estimable")
    if not np.nanmax(rhat) < conv.max_rhat:
        parts.append(f"max R-hat {np.nanmax(rhat):.3f} >= {conv.max_rhat}")
    if not np.nanmin(ess) >= conv.min_ess:
        parts.append(f"min bulk ESS {np.nanmin(ess):.0f} < {conv.min_ess:g}")
    return "not converged: " + ("; ".join(parts) if parts else "tau still changing")
