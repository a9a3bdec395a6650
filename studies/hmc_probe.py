"""Would Hamiltonian moves with finite-difference gradients mix a hard single-record
posterior for fewer evaluations than the default ensemble? (Tried and dropped: the
answer, on the replicates measured, is in results/chain-geometry/README.md.)

The log posterior is a simulation, with no derivative of its own; its gradient here is
taken by forward differences (one evaluation per parameter, step ``--h`` in the
whitened coordinates below). A finite-difference gradient leaves the chain exact: the
leapfrog map with any force that depends on position alone keeps volume and is
reversible with the momentum flipped, and the Metropolis step uses the true log
posterior; the gradient's error costs acceptance, not correctness.

One chain, from a draw of the default sampler's chain of ``studies/chain_geometry.py``
(runs/chain-geometry, made by that script first), in that chain's coordinates whitened
by its draws' covariance after its first third (an identity mass matrix there): steps
``--eps`` (jittered by 10 % in log), ``--leapfrogs`` L/2 to L a trajectory.

Compared per effective draw of the slowest parameter (in theta): the ensemble's
evaluations per effective draw are its tau in steps (N W evaluations for N W / tau
draws, walkers counted independent, which flatters it), a single chain's are its tau
in iterations times its evaluations per iteration. Rows go to ``--out``/hmc.csv.

    python studies/hmc_probe.py [--seed 11] [--replicate 1] [--iterations 400] [--eps 0.08]
        [--leapfrogs 12] [--out results/chain-geometry] [--fits runs/chain-geometry]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from _table import git_commit, read_rows, sampled_model, write_rows
from bayes_inerter.inference import LikelihoodSettings, PosteriorModel
from bayes_inerter.inference.sampling.checkpoint import read_chain
from bayes_inerter.inference.sampling.convergence import integrated_time
from bayes_inerter.study.study_calibration import STUDY_SBC_PRIORS, StudyCalibration, replicate_device

ROOT = Path(__file__).resolve().parents[1]
FIELDS = ("seed", "replicate", "freq_hz", "commit", "sampler", "iterations", "eps", "leapfrogs", "acceptance",
          "evaluations_per_iteration", "tau_slowest", "slowest", "evaluations_per_effective_draw", "seconds")


class Whitened:
    """The log posterior in the default chain's coordinates, whitened: u = mu + L z."""

    def __init__(self, model, coords, draws: np.ndarray):
        self.model, self.coords = model, coords
        self.mu = draws.mean(axis=0)
        self.L = np.linalg.cholesky(np.cov(draws.T))
        self.evaluations = 0

    def __call__(self, z: np.ndarray) -> float:
        self.evaluations += 1
        theta, log_jac = self.coords.transform(np.atleast_2d(self.mu + self.L @ z))
        lp = float(self.model.log_prob(theta[0])[0]) + float(log_jac[0])
        return lp if np.isfinite(lp) else -np.inf

    def gradient(self, z: np.ndarray, fz: float, h: float) -> np.ndarray:
        g = np.empty(len(z))
        for i in range(len(z)):
            step = np.zeros(len(z))
            step[i] = h
            g[i] = (self(z + step) - fz) / h
        return g

    def theta(self, z: np.ndarray) -> np.ndarray:
        return self.coords.to_theta(self.mu + z @ self.L.T)


def hmc(f: Whitened, z: np.ndarray, iterations: int, eps: float, leapfrogs: int, h: float,
        rng: np.random.Generator) -> tuple[np.ndarray, float]:
    """(the chain of z, mean acceptance) of ``iterations`` Hamiltonian steps from ``z``."""
    d = len(z)
    fz = f(z)
    gz = f.gradient(z, fz, h)
    chain, accepted = [], []
    for _ in range(iterations):
        p = rng.standard_normal(d)
        h0 = fz - 0.5 * p @ p
        n = int(rng.integers(max(1, leapfrogs // 2), leapfrogs + 1))
        e = eps * np.exp(0.1 * rng.standard_normal())
        q, fq, gq = z.copy(), fz, gz.copy()
        p = p + 0.5 * e * gq
        a = 0.0
        for s in range(n):
            q = q + e * p
            fq = f(q)
            if not np.isfinite(fq):
                break
            gq = f.gradient(q, fq, h)
            p = p + (e if s < n - 1 else 0.5 * e) * gq
        else:
            a = float(min(1.0, np.exp(fq - 0.5 * p @ p - h0)))
        accepted.append(a)
        if rng.random() < a:
            z, fz, gz = q, fq, gq
        chain.append(z)
    return np.array(chain), float(np.mean(accepted))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seed", type=int, default=11)
    ap.add_argument("--replicate", type=int, default=1)
    ap.add_argument("--iterations", type=int, default=400)
    ap.add_argument("--eps", type=float, default=0.08)
    ap.add_argument("--leapfrogs", type=int, default=12)
    ap.add_argument("--h", type=float, default=1e-3, help="finite-difference step in the whitened coordinates")
    ap.add_argument("--out", default=str(ROOT / "results" / "chain-geometry"))
    ap.add_argument("--fits", default=str(ROOT / "runs" / "chain-geometry"))
    args = ap.parse_args(argv)
    first = Path(args.fits) / f"seed{args.seed}_{args.replicate}_default"
    if not (first / "chain.h5").is_file():
        print(f"error: no default chain in {first}; run studies/chain_geometry.py --seed {args.seed} "
              f"--replicate {args.replicate} first", file=sys.stderr)
        return 2
    cs = replace(StudyCalibration(), steps=None, seed=args.seed, single=True,
                 likelihood=LikelihoodSettings(residual="motion"), frequencies=(0.5, 1.0, 1.5))
    record = replicate_device(cs, args.replicate).records[0]
    model, coords = sampled_model(PosteriorModel(record, priors=STUDY_SBC_PRIORS,
                                                 likelihood=LikelihoodSettings(residual="motion")), first / "chain.h5")
    chain = read_chain(first / "chain.h5")
    draws = chain[len(chain) // 3:].reshape(-1, chain.shape[2])
    info = json.loads((first / "fit.json").read_text())
    names = list(model.names)
    base = {"seed": args.seed, "replicate": args.replicate, "commit": git_commit(ROOT),
            "freq_hz": record.metadata.get("drive_frequency_hz")}
    tau_e = {n: float(t) for n, t in info["tau"].items()}
    slow_e = max(tau_e, key=tau_e.get)
    rows = [{**base, "sampler": "default ensemble (its fit)", "iterations": len(chain), "acceptance": "",
             "evaluations_per_iteration": chain.shape[1], "tau_slowest": round(tau_e[slow_e], 1), "slowest": slow_e,
             "evaluations_per_effective_draw": round(tau_e[slow_e], 1), "seconds": ""}]
    f = Whitened(model, coords, draws)
    rng = np.random.default_rng([args.seed, args.replicate])
    z0 = np.linalg.solve(f.L, draws[rng.integers(len(draws))] - f.mu)
    t0 = time.perf_counter()
    zs, acceptance = hmc(f, z0, args.iterations, args.eps, args.leapfrogs, args.h, rng)
    seconds = time.perf_counter() - t0
    theta = f.theta(zs)[len(zs) // 5:]
    tau = dict(zip(names, map(float, integrated_time(theta[:, None, :]))))
    slow = max(tau, key=tau.get)
    per_iteration = f.evaluations / args.iterations
    rows.append({**base, "sampler": "Hamiltonian, forward-difference gradient", "iterations": args.iterations,
                 "eps": args.eps, "leapfrogs": args.leapfrogs, "acceptance": round(acceptance, 3),
                 "evaluations_per_iteration": round(per_iteration, 1), "tau_slowest": round(tau[slow], 1),
                 "slowest": slow, "evaluations_per_effective_draw": round(tau[slow] * per_iteration, 1),
                 "seconds": round(seconds, 1)})
    for r in rows:
        print(f"{r['sampler']}: tau {r['tau_slowest']} ({r['slowest']}), "
              f"{r['evaluations_per_effective_draw']} evaluations per effective draw")
    out = Path(args.out) / "hmc.csv"
    keep = [r for r in read_rows(out) if (r["seed"], r["replicate"]) != (str(args.seed), str(args.replicate))]
    write_rows(out, [{k: r.get(k, "") for k in FIELDS} for r in keep + rows])
    return 0


if __name__ == "__main__":
    sys.exit(main())
