"""Where a tempered chain's hot ensembles start, measured on targets whose marginals are known.

Issue 39, item 4: on the likelihood's own draws the fits' intervals held about 0.90 at
94 % and 0.46 at 50 %. This study runs the fit's own sampler (its ensemble moves, fitted
proposals, parallel tempering, convergence rule and kept draws: ``sampler.sample``,
``tempering.sample_tempered``, ``convergence.Monitor``) on two 12-D targets whose
marginals are known exactly, and checks the kept draws against them:

- ``normal``: a correlated normal (condition number 1e4, scales from 1e-3 to 10);
- ``banana``: six independent bent ridges, y_odd = 0.1 x_odd + (y_even^2 - 1),
  y_even = x_even, x standard normal (a narrow ridge that bends, as the friction's and
  the nut's do in the records' posteriors).

Three samplers, each from walkers drawn as a fit draws them
(``optimize.laplace_ensemble`` about the target's mode), the same seeds for all:

- ``untempered``: the posterior's ensemble alone;
- ``tempered-posterior-spread``: 4 temperatures down to beta 0.1, every hot ensemble
  drawn at the posterior's own spread (the package's start before 634035c);
- ``tempered-own-spread``: the same ladder, each hot ensemble drawn at its own
  temperature's spread (``laplace_ensemble(beta=)``, the package's start now);
- ``tempered-own-spread+replica-rule``: the same, stopped only where the chain after
  its warm-up is also 50 times the replicas' largest tau (each walker followed through
  the swaps, ``tempering.replica_trajectories``), its draws kept after 2 of those tau
  (tried here first; the package's ``Convergence(replicas=True)`` since);
- ``tempered-own-spread+adapt-hot+replica-rule``: the same, each hot ensemble also
  proposing from moves fitted to its own walkers (``Tempering(adapt_hot=True)``).

``--samplers`` runs some of them alone (their rows to ``--out``).

Two more isolate the hot ensembles' part: the posterior's ensemble drawn from the target
itself (``exact:``), the hot ensembles drawn from it too (``exact:tempered-posterior-spread``)
or from their own tempered targets, exactly (``exact:tempered-own-spread``). A valid
kernel started in its equilibrium stays there, so what the first loses against the
second is what swaps with hot ensembles out of their equilibrium take away.

Each chain runs to the package's rule (``Convergence(max_steps=10000, tau_rtol=0.2)``)
and keeps its draws as a fit does (after the warm-up and 2 tau, thinned by tau / 2).
Reported per chain: the hot ensembles' largest autocorrelation time over the chain after
its warm-up and whether that stretch is 50 times as long (the rule's tau part applied to
the hot ensembles, which the package's rule does not read), the kept draws' sd over the
target's (median over coordinates), and
the target's mass inside the kept draws' 94 % and 50 % equal-tailed intervals (mean
over coordinates; 0.94 and 0.50 for draws of the target itself, a little less from few
draws). Rows to ``--out``/chains.csv, medians per target and sampler to summary.csv.

    python studies/tempering_starts.py [--seeds 8] [--out results/tempering-starts]
"""

from __future__ import annotations

import argparse
import csv
import math
import sys
import tempfile
import time
from pathlib import Path

import emcee
import numpy as np
from scipy.stats import norm

from bayes_inerter.inference.sampling.adaptation import Adaptation, Schedule
from bayes_inerter.inference.sampling.checkpoint import new_checkpoint
from bayes_inerter.inference.sampling.convergence import Convergence, Monitor, integrated_time
from bayes_inerter.inference.sampling.coordinates import Coordinates
from bayes_inerter.inference.sampling.optimize import laplace_ensemble
from bayes_inerter.inference.sampling.sampler import default_moves, default_walkers, sample
from bayes_inerter.inference.sampling.target import Target
from bayes_inerter.inference.sampling.tempering import Tempering, replica_trajectories, sample_tempered

D = 12
BOX = 60.0
BEND, ACROSS = 1.0, 0.1
SAMPLERS = ("untempered", "tempered-posterior-spread", "tempered-own-spread", "exact:tempered-posterior-spread",
            "exact:tempered-own-spread", "tempered-own-spread+replica-rule",
            "tempered-own-spread+adapt-hot+replica-rule")
TARGETS = ("normal", "banana")
REFERENCE_DRAWS = 400_000


class Known:
    """A target with known marginals, in the shape the sampler reads a model: a flat
    prior on a box (``bounds``, ``log_prior``) and ``log_prob`` (value, phi)."""

    def __init__(self, kind: str, rng: np.random.Generator):
        self.kind = kind
        self.mode = np.zeros(D)
        if kind == "normal":
            q, _ = np.linalg.qr(rng.normal(size=(D, D)))
            c = q @ np.diag(np.geomspace(1e-4, 1.0, D)) @ q.T
            s = np.geomspace(1e-3, 10.0, D) / np.sqrt(np.diag(c))
            self.cov = c * np.outer(s, s)
            self.prec = np.linalg.inv(self.cov)
        else:
            self.mode[1::2] = -BEND
        self.scale = np.sqrt(np.diag(self.cov)) if kind == "normal" else np.ones(D)

    def bounds(self):
        half = BOX * self.scale if self.kind == "normal" else np.full(D, BOX ** 2)
        return np.column_stack([-half, half])

    def log_prior(self, theta) -> float:
        lo, hi = self.bounds().T
        return 0.0 if np.all((theta >= lo) & (theta <= hi)) else -math.inf

    def log_prob(self, theta):
        theta = np.asarray(theta, dtype=float)
        if not math.isfinite(self.log_prior(theta)):
            return -math.inf, math.nan
        if self.kind == "normal":
            return -0.5 * theta @ self.prec @ theta, 0.0
        x = theta.copy()
        x[1::2] = (theta[1::2] - BEND * (theta[0::2] ** 2 - 1.0)) / ACROSS
        return -0.5 * x @ x, 0.0

    def exact(self, n: int, rng: np.random.Generator, beta: float = 1.0) -> np.ndarray:
        """``n`` independent draws of prior x target^beta (a draw outside the prior's
        box, a vanishing share, is drawn again)."""
        lo, hi = self.bounds().T
        out = np.empty((0, D))
        while len(out) < n:
            x = rng.normal(size=(n, D)) / math.sqrt(beta)
            if self.kind == "normal":
                y = x @ np.linalg.cholesky(self.cov).T
            else:
                y = x.copy()
                y[:, 1::2] = ACROSS * x[:, 1::2] + BEND * (x[:, 0::2] ** 2 - 1.0)
            out = np.vstack([out, y[np.all((y > lo) & (y < hi), axis=1)]])
        return out[:n]

    def mass(self, lo, hi) -> np.ndarray:
        """The target's mass in [lo, hi] on each coordinate."""
        if self.kind == "normal":
            return norm.cdf(hi / self.scale) - norm.cdf(lo / self.scale)
        ref = self._reference()
        return np.array([np.searchsorted(ref[:, i], hi[i]) - np.searchsorted(ref[:, i], lo[i])
                         for i in range(D)]) / len(ref)

    def sd(self) -> np.ndarray:
        return self.scale if self.kind == "normal" else self._reference().std(axis=0)

    def _reference(self) -> np.ndarray:
        if not hasattr(self, "_ref"):
            self._ref = np.sort(self.exact(REFERENCE_DRAWS, np.random.default_rng(7)), axis=0)
        return self._ref


def run_chain(model: Known, sampler: str, seed: int, conv: Convergence, work: Path) -> dict:
    """One chain of ``sampler`` on ``model`` to the rule; its kept draws against the target."""
    nw = default_walkers(D)
    lo, hi = model.bounds().T
    coords = Coordinates("unconstrained", lo, hi, np.zeros(D, dtype=bool))
    target = Target(model, coords)
    # the package's ladder: 4 down to beta 0.1; "+adapt-hot": its hot ensembles' own fitted moves
    ladder = None if sampler == "untempered" else Tempering(adapt_hot="+adapt-hot" in sampler)
    betas = (1.0,) if ladder is None else tuple(ladder.betas)
    rng = np.random.default_rng(seed)
    own = "own-spread" in sampler
    if sampler.startswith("exact:"):
        ensembles = [model.exact(nw, rng, beta if own else 1.0) for beta in betas]
    else:
        ensembles = [laplace_ensemble(model, model.mode, nw, rng, beta=beta if own else 1.0)[0] for beta in betas]
    state = emcee.State(ensembles[0], random_state=np.random.RandomState(seed).get_state())
    backend = new_checkpoint(work / f"{sampler}-{seed}.h5", write_seconds=60.0,
                             identity={"nwalkers": nw, "ndim": D, "model": {"parameters": [f"x{i}" for i in range(D)]}})
    schedule = Schedule(default_moves(model, coordinates=coords), Adaptation())
    if ladder is None:
        stepping = sample(target, backend, state, schedule=schedule, iterations=conv.max_steps)
    else:
        stepping = sample_tempered(target, backend, state, tempering=ladder, schedule=schedule,
                                   iterations=conv.max_steps, seed=seed, hot_starts=ensembles[1:])
    def replicas_after(warmup: int) -> np.ndarray:  # the replicas' trajectories after the warm-up
        return replica_trajectories(backend.get_chain()[warmup:], backend.get_rows("hot_chain", warmup),
                                    backend.get_rows("replicas", warmup))

    monitor, ok, t0 = Monitor(conv), False, time.perf_counter()
    replica_rule, replica_tau = sampler.endswith("+replica-rule"), 0.0
    for _ in stepping:
        n = backend.iteration
        if n % conv.check_every == 0:
            check, ok = monitor.check(backend.get_chain(), backend.get_log_prob())
            if ok and replica_rule:  # the rule's tau part read on the replicas too
                paths = replicas_after(check.warmup)
                replica_tau = float(np.max(integrated_time(paths)))
                ok = bool(np.isfinite(replica_tau) and len(paths) >= conv.n_tau * replica_tau)
            if ok or n >= conv.max_steps:
                break
    tau = check.tau
    burn = check.warmup + int(2 * max(np.max(tau), replica_tau if np.isfinite(replica_tau) else 0.0))
    draws = backend.get_chain(discard=burn, thin=max(1, int(0.5 * np.min(tau)))).reshape(-1, D)
    row = {"target": model.kind, "sampler": sampler, "seed": seed, "steps": n, "converged": ok,
           "tau_max": round(float(np.max(tau)), 1), "kept": len(draws),
           "sd_ratio": round(float(np.median(draws.std(axis=0) / model.sd())), 3),
           "seconds": round(time.perf_counter() - t0, 1)}
    if ladder is not None:  # the rule's tau part read on each hot ensemble's chain after the same warm-up
        chains = backend.get_rows("hot_chain", check.warmup)  # steps, hot ensembles, walkers, ndim
        taus = [float(np.max(integrated_time(chains[:, k]))) for k in range(chains.shape[1])]
        row["hot_tau_max"] = round(max(taus), 1)
        row["hot_rule_holds"] = bool(len(chains) >= conv.n_tau * max(taus))
        paths = replicas_after(check.warmup)
        row["replica_tau_max"] = round(float(np.max(integrated_time(paths))), 1)
        row["replica_rule_holds"] = bool(len(paths) >= conv.n_tau * row["replica_tau_max"])
    for level in (0.94, 0.5):
        q = np.quantile(draws, [(1 - level) / 2, (1 + level) / 2], axis=0)
        row[f"mass{round(level * 100)}"] = round(float(np.mean(model.mass(q[0], q[1]))), 3)
    return row


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--seeds", type=int, default=8)
    p.add_argument("--out", type=Path, default=Path("results/tempering-starts"))
    p.add_argument("--samplers", nargs="+", choices=SAMPLERS, default=list(SAMPLERS), metavar="SAMPLER",
                   help="the samplers to run (default: all): " + ", ".join(SAMPLERS))
    args = p.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    conv = Convergence(max_steps=10_000, tau_rtol=0.2)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        for kind in TARGETS:
            for seed in range(args.seeds):
                model = Known(kind, np.random.default_rng([99, seed]))
                for sampler in args.samplers:
                    rows.append(run_chain(model, sampler, seed, conv, Path(tmp)))
                    r = rows[-1]
                    print(f"{kind} {sampler} seed {seed}: {r['steps']} steps, sd ratio {r['sd_ratio']}, "
                          f"mass {r['mass94']} / {r['mass50']}", flush=True)
    with open(args.out / "chains.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(max(rows, key=len)))
        w.writeheader()
        w.writerows(rows)
    summary = []
    for kind in TARGETS:
        for sampler in args.samplers:
            got = [r for r in rows if r["target"] == kind and r["sampler"] == sampler]
            summary.append({"target": kind, "sampler": sampler, "chains": len(got),
                            "converged": sum(r["converged"] for r in got),
                            "hot_rule_holds": sum(r.get("hot_rule_holds", False) for r in got) if got[0].get(
                                "hot_tau_max") is not None else "",
                            "replica_rule_holds": sum(r.get("replica_rule_holds", False) for r in got) if got[0].get(
                                "replica_tau_max") is not None else "",
                            "replica_tau_max": float(np.median([r["replica_tau_max"] for r in got]))
                            if got[0].get("replica_tau_max") is not None else "",
                            **{k: float(np.median([r[k] for r in got])) for k in
                               ("steps", "sd_ratio", "mass94", "mass50")}})
    with open(args.out / "summary.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(summary[0]))
        w.writeheader()
        w.writerows(summary)
    for s in summary:
        print(f"{s['target']:7s} {s['sampler']:33s} converged {s['converged']}/{s['chains']} (hot ensembles "
              f"long enough: {s['hot_rule_holds']}, replicas: {s['replica_rule_holds']}, replica tau "
              f"{s['replica_tau_max']}), median steps "
              f"{s['steps']:.0f}, sd ratio {s['sd_ratio']:.3f}, mass {s['mass94']:.3f} / {s['mass50']:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
