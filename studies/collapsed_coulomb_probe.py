"""The plate's Coulomb force integrated out of a friction-dominated record's posterior.

Under ``fit``'s likelihood (the reference point's normaliser and deviations' scale) the
predicted force is linear in the plate's Coulomb force f1_0 = f_0 f_share, and the noise
does not depend on it, so the log posterior is quadratic in f1_0 with the rest held. On
friction-dominated records f1_0 is pinned to about 1e-4 of itself, and the pinned
combination turns with the other parameters: the thin, bent shape the ensemble crosses
slowly (results/capped-by-force-ratio). Integrating f1_0 out removes that direction:
the collapsed target over psi = (log f2_0, the rest) is

    log m(psi) = log p(psi, f1_0*) + log J + 1/2 log(2 pi / kappa),

with f1_0* and kappa from an exact quadratic in f1_0 (three evaluations, one Newton
refinement), J the Jacobian from (log f2_0, f1_0) to (log f_0, f_share). The prior and J
are not quadratic in f1_0, but over its conditional width they change by parts in 1e8.

Both targets are sampled by plain emcee with the package's ensemble moves
(``sampler.default_moves`` without the nut's ridge move; not its fitted ones), in theta,
not the impedance coordinates, 26 walkers from the last walkers of the users'-likelihood
chain of ``studies/deviation_scale_probe.py``, a fixed number of steps, the same seed;
tau is read on the last two thirds. Also printed: the local Hessian's largest eigenvalues, in coordinates whitened by each chain's covariance, at
three draws (a normal's would be 1).

    python studies/deviation_scale_probe.py --replicate 10 --steps 3000
    python studies/collapsed_coulomb_probe.py --replicate 10 --steps 3000 --out results/capped-by-force-ratio
"""
from __future__ import annotations

import dataclasses
import math
import time
from pathlib import Path

import emcee
import numpy as np

from _table import append_row, git_commit, sampled_model
from deviation_scale_probe import probe_arguments, seed23_replicate
from bayes_inerter.inference import PosteriorModel
from bayes_inerter.inference.sampling.checkpoint import read_chain
from bayes_inerter.inference.sampling.convergence import integrated_time
from bayes_inerter.inference.sampling.sampler import default_moves

ROOT = Path(__file__).resolve().parents[1]
FIELDS = ("replicate", "target", "steps", "walkers", "evaluations", "seconds", "acceptance", "tau_max",
          "tau_median", "evaluations_per_tau", "hessian_top", "commit")


class Targets:
    """The full posterior in theta and the collapsed one in psi, counting evaluations."""

    def __init__(self, model: PosteriorModel):
        self.model, self.evaluations = model, 0
        names = list(model.names)
        self.iF, self.iS = names.index("f_0"), names.index("f_share")
        self.rest = [i for i in range(len(names)) if i not in (self.iF, self.iS)]
        self.n = len(names)

    def full(self, theta) -> float:
        self.evaluations += 1
        v = self.model.log_prob(np.asarray(theta, dtype=float))[0]
        return v if math.isfinite(v) else -math.inf

    def psi_of(self, theta) -> np.ndarray:
        return np.r_[math.log(math.exp(theta[self.iF]) * (1.0 - theta[self.iS])), np.asarray(theta)[self.rest]]

    def joint(self, psi, f1: float) -> float:
        if not f1 > 0.0:
            return -math.inf
        f2 = math.exp(psi[0])
        total = f1 + f2
        theta = np.empty(self.n)
        theta[self.iF], theta[self.iS], theta[self.rest] = math.log(total), f1 / total, psi[1:]
        return self.full(theta) + math.log(f2) - 2.0 * math.log(total)

    def collapsed(self, psi) -> float:
        a = math.exp(psi[0])  # a start for f1_0; the quadratic is exact, so any positive one will do
        for _ in range(3):
            h = 1e-4 * a
            f = [self.joint(psi, a - h), self.joint(psi, a), self.joint(psi, a + h)]
            if not all(map(math.isfinite, f)):
                return -math.inf
            kappa = -(f[0] - 2.0 * f[1] + f[2]) / (h * h)
            if not kappa > 0.0:
                return -math.inf
            step = (f[2] - f[0]) / (2.0 * h) / kappa
            a += step
            if abs(step) < 1e-3 / math.sqrt(kappa):
                break
        top = self.joint(psi, a)
        return top + 0.5 * math.log(2.0 * math.pi / kappa) if math.isfinite(top) else -math.inf


def hessian_top(fn, draws: np.ndarray, rng: np.random.Generator, count: int = 3, h: float = 1e-3) -> list[float]:
    """The largest eigenvalue of -Hessian of ``fn`` at ``count`` of ``draws``, in coordinates
    whitened by the draws' covariance (central differences)."""
    L = np.linalg.cholesky(np.cov(draws.T))
    d = draws.shape[1]
    tops = []
    for _ in range(count):
        z0 = np.linalg.solve(L, draws[rng.integers(len(draws))])
        H = np.zeros((d, d))
        for i in range(d):
            for j in range(i, d):
                ei, ej = np.eye(d)[i] * h, np.eye(d)[j] * h
                f = [fn(L @ (z0 + a * ei + b * ej)) for a, b in ((1, 1), (1, -1), (-1, 1), (-1, -1))]
                H[i, j] = H[j, i] = (f[0] - f[1] - f[2] + f[3]) / (4.0 * h * h)
        tops.append(float(np.linalg.eigvalsh(-H)[-1]) if np.all(np.isfinite(H)) else math.nan)
    return tops


def main(argv=None) -> int:
    a = probe_arguments(__doc__, "collapsed_coulomb.csv").parse_args(argv)
    start = a.fits / f"s23_{a.replicate}_reference_3000" / "chain.h5"
    if a.steps < 300 or not start.exists():
        print(f"error: --steps must be at least 300, and {start} must exist: run "
              f"python studies/deviation_scale_probe.py --replicate {a.replicate} --steps 3000 first")
        return 2
    cs, device = seed23_replicate(a.replicate)
    likelihood = dataclasses.replace(cs.likelihood, normaliser="reference", deviation_scale="reference")
    model, coords = sampled_model(PosteriorModel(device.records[0], priors=cs.priors(), likelihood=likelihood), start)
    theta0 = np.asarray(coords.transform(read_chain(start)[-1])[0])
    t = Targets(model)
    commit = git_commit(ROOT)
    rows = []
    for name, fn, p0 in (("full (theta)", t.full, theta0),
                         ("f1_0 integrated out (psi)", t.collapsed, np.array([t.psi_of(x) for x in theta0]))):
        t.evaluations = 0
        sampler = emcee.EnsembleSampler(len(p0), p0.shape[1], fn, moves=default_moves(model, ridge_weight=0.0))
        state = emcee.State(p0, random_state=np.random.RandomState(a.replicate).get_state())
        t0 = time.perf_counter()
        sampler.run_mcmc(state, a.steps, progress=False)
        seconds = time.perf_counter() - t0
        evaluations = t.evaluations
        chain = sampler.get_chain()
        tau = integrated_time(chain[a.steps // 3:])
        top = hessian_top(fn, chain[a.steps // 3:].reshape(-1, chain.shape[-1]), np.random.default_rng(a.replicate))
        row = {"replicate": a.replicate, "target": name, "steps": a.steps, "walkers": len(p0),
               "evaluations": evaluations, "seconds": round(seconds, 1),
               "acceptance": round(float(sampler.acceptance_fraction.mean()), 3),
               "tau_max": round(float(np.nanmax(tau)), 1), "tau_median": round(float(np.nanmedian(tau)), 1),
               "evaluations_per_tau": round(evaluations / a.steps * float(np.nanmax(tau))),
               "hessian_top": " ".join(f"{x:.0f}" for x in top), "commit": commit}
        rows.append(row)
        print(f"replicate {a.replicate}, {name}: acceptance {row['acceptance']}, largest tau {row['tau_max']} steps, "
              f"{row['evaluations_per_tau']} evaluations per tau, {row['seconds']} s; "
              f"whitened Hessian's top eigenvalue {row['hessian_top']}", flush=True)
    if a.out is not None:
        for row in rows:
            append_row(a.out / "collapsed_coulomb.csv", row, FIELDS)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
