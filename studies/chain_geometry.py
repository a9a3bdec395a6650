"""Why a single record's chain mixes slowly: the posterior's geometry, measured on a chain.

Issue 40, item 1 (and the capped chains of issue 39, item 4's coverage): one replicate
of the single-record calibration (``study.study_calibration.replicate_device``: the
device drawn from the study's priors and its record) is fitted by ``fit_record`` for a
fixed number of steps with the default sampler (26 walkers for 12 parameters) and again
with ``--walkers`` walkers for as many evaluations (and with ``--transport``, a third
time with the independence move after the triangular map below,
``Adaptation(transport=True)``; with ``--slice``, ensemble slice sampling, below); then,
on the first chain's draws after its first third:

- the share of walker steps that moved, and each parameter's autocorrelation time;
- **midpoints**: for ``--pairs`` pairs of draws, how far the log posterior at their
  midpoint in the sampler's coordinates lies below the lower of the two (a posterior
  that is one convex hump, a normal's, puts the midpoint above both);
- **bent ridges**: each sampler coordinate's sd given the others, fitted linearly and
  with their squares and products, beside its own sd;
- **independence proposals** at equilibrium (``benchmarks/bench_proposal.py``'s
  measure): the t in normal scores that the adaptation fits, and the same t after the
  triangular map of ``inference.sampling.transport`` (each coordinate's quadratic regression on
  the less identified ones taken away), each evaluated on ``--pairs`` proposals paired
  with as many draws.

**Ensemble slice sampling** (``--slice``; Karamanis and Beutler 2021, the package
``zeus-mcmc``, which the package does not need and this option alone imports): from the
first chain's last walkers, zeus's differential slice move (or, with ``--slice global``,
that move in 0.8 of the steps and its Gaussian-mixture global move in 0.2) runs in the
same sampler coordinates, blocks of 100 steps until it has made as many evaluations of
the log posterior as the first chain (its steps times its walkers). A slice step takes
several evaluations a walker, so the row compares the largest autocorrelation time
times the walkers times the evaluations a walker step took, on the draws after its
first third. zeus draws from numpy's global random state, which is seeded with the
replicate's seed before it runs. Its start is the first chain's equilibrium, which
favours it.

Rows go to ``--out``/geometry.csv (one per statistic and variant; another replicate's
rows, and this one's of variants not run now, are kept); the fits stay in
``--fits`` (runs/chain-geometry, not committed), and a second run reuses them.

    python studies/chain_geometry.py [--seed 11] [--replicate 1] [--steps 3000] [--walkers 52]
        [--transport] [--slice {differential,global}] [--pairs 300] [--out results/chain-geometry] [--fits runs/chain-geometry]
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
from bayes_inerter.inference import LikelihoodSettings, PosteriorModel, fit_record
from bayes_inerter.inference.sampling.adaptation import Adaptation
from bayes_inerter.inference.sampling.checkpoint import read_chain
from bayes_inerter.inference.sampling.convergence import integrated_time
from bayes_inerter.inference.sampling.moves import IndependenceMove
from bayes_inerter.inference.sampling.transport import TriangularScores, quadratic_features
from bayes_inerter.study.study_calibration import STUDY_SBC_PRIORS, StudyCalibration, replicate_device

ROOT = Path(__file__).resolve().parents[1]
FIELDS = ("seed", "replicate", "freq_hz", "commit", "variant", "statistic", "value", "value2", "steps", "walkers",
          "moved", "seconds", "tau")


def fit(record, out: Path, steps: int, walkers: int | None, seed: int, adaptation: Adaptation = Adaptation()) -> dict:
    """A fixed-step fit into ``out`` (kept if there), with its seconds."""
    if not (out / "fit.json").exists():
        t0 = time.perf_counter()
        fit_record(record, out, steps=steps, walkers=walkers, seed=seed, priors=STUDY_SBC_PRIORS, plots=False,
                   likelihood=LikelihoodSettings(residual="motion"), interval="posterior", adaptation=adaptation)
        (out / "seconds.txt").write_text(f"{time.perf_counter() - t0:.1f}\n")
    info = json.loads((out / "fit.json").read_text())
    chain = read_chain(out / "chain.h5")
    kept = chain[len(chain) // 3:]
    moved = float(np.mean(np.any(np.diff(kept, axis=0) != 0, axis=2)))
    tau = {n: float(t) for n, t in info["tau"].items()}
    return {"walkers": chain.shape[1], "steps": len(chain), "moved": moved, "tau": tau,
            "tau_max": max(tau.values()), "evaluations_per_tau": max(tau.values()) * chain.shape[1],
            "seconds": float((out / "seconds.txt").read_text())}


def posterior_in(model, coords):
    """The log posterior of ``model`` at rows of points in the sampler ``coords``
    (the Jacobian included; -inf outside)."""

    def log_post(u):
        theta, log_jac = coords.transform(np.atleast_2d(u))
        out = np.array([model.log_prob(t)[0] for t in theta], dtype=float) + log_jac
        return np.where(np.isfinite(out), out, -np.inf)

    return log_post


def slice_chain(log_post, start: np.ndarray, evaluations: int, kind: str, seed: int, out: Path) -> dict:
    """Ensemble slice sampling from the walkers ``start`` until ``evaluations`` log
    posteriors are made (see module docstring); the chain kept in ``out`` (reused)."""
    try:
        import zeus
    except ImportError:
        raise SystemExit("error: --slice needs the package zeus-mcmc; install it with pip install zeus-mcmc") from None
    calls = [0]

    def counted(u):
        calls[0] += 1
        return log_post(np.atleast_2d(u))[0]

    if not (out / "chain.npy").exists():
        out.mkdir(parents=True, exist_ok=True)
        np.random.seed(seed)  # zeus draws from numpy's global state
        moves = (zeus.moves.DifferentialMove() if kind == "differential"
                 else [(zeus.moves.DifferentialMove(), 0.8), (zeus.moves.GlobalMove(), 0.2)])
        sampler = zeus.EnsembleSampler(start.shape[0], start.shape[1], counted, moves=moves, verbose=False)
        t0 = time.perf_counter()
        state = start
        while calls[0] < evaluations:
            sampler.run_mcmc(state, 100, progress=False)
            state = sampler.get_last_sample()
        np.save(out / "chain.npy", sampler.get_chain())
        (out / "calls.txt").write_text(f"{calls[0]} {time.perf_counter() - t0:.1f}\n")
    chain = np.load(out / "chain.npy")
    n_calls, seconds = (out / "calls.txt").read_text().split()
    kept = chain[len(chain) // 3:]
    per_step = int(n_calls) / (chain.shape[0] * chain.shape[1])
    tau = [float(t) for t in integrated_time(kept)]
    moved = float(np.mean(np.any(np.diff(kept, axis=0) != 0, axis=2)))
    return {"walkers": chain.shape[1], "steps": len(chain), "moved": moved, "tau": tau, "tau_max": max(tau),
            "evaluations_per_tau": max(tau) * chain.shape[1] * per_step, "seconds": float(seconds),
            "per_step": per_step}


def geometry(model, coords, chain: np.ndarray, pairs: int, rng: np.random.Generator) -> list[dict]:
    """The midpoint, bent-ridge and independence-proposal rows of one chain."""
    d = chain.shape[2]
    fit_draws = chain[len(chain) // 3:].reshape(-1, d)
    stationary = chain[len(chain) // 2:].reshape(-1, d)

    log_post = posterior_in(model, coords)
    rows = []
    a = stationary[rng.integers(len(stationary), size=pairs)]
    b = stationary[rng.integers(len(stationary), size=pairs)]
    drop = np.minimum(log_post(a), log_post(b)) - log_post(0.5 * (a + b))
    rows += [{"statistic": "midpoint drop, median (nats)", "value": float(np.median(drop))},
             {"statistic": "midpoint drop over 10 nats (share)", "value": float(np.mean(drop > 10.0))}]
    names = list(model.names)
    for i in range(d):
        others = np.delete(fit_draws, i, axis=1)
        others = (others - others.mean(axis=0)) / others.std(axis=0)
        lin = np.column_stack([np.ones(len(others)), others])
        y = fit_draws[:, i]
        r_lin = y - lin @ np.linalg.lstsq(lin, y, rcond=None)[0]
        quad = quadratic_features(others)
        r_quad = y - quad @ np.linalg.lstsq(quad, y, rcond=None)[0]
        rows.append({"statistic": f"sd over sd given the rest, linear / quadratic: {names[i]}",
                     "value": float(np.std(y) / np.std(r_lin)), "value2": float(np.std(y) / np.std(r_quad))})
    x = stationary[rng.choice(len(stationary), pairs, replace=False)]
    lp_x = log_post(x)
    draws_rng = np.random.RandomState(int(rng.integers(2**31)))
    t_scores = IndependenceMove.fit(fit_draws, knots=200)
    t_map = IndependenceMove.fit_in(fit_draws, TriangularScores.fit(fit_draws))
    variants = {
        "t in normal scores (the adaptation's)": t_scores,
        "t after the triangular quadratic map": t_map,
    }
    for name, move in variants.items():
        y = move.draw(pairs, draws_rng)
        w_y, w_x = log_post(y) - move.log_density(y), lp_x - move.log_density(x)
        with np.errstate(invalid="ignore"):  # a proposal outside the domain: never accepted
            accept = np.where(np.isfinite(w_y), np.minimum(1.0, np.exp(np.clip(w_y - w_x, -700.0, 50.0))), 0.0)
        rows.append({"statistic": f"independence acceptance at equilibrium: {name}", "value": float(np.mean(accept))})
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seed", type=int, default=11, help="the single-record calibration's seed")
    ap.add_argument("--replicate", type=int, default=1)
    ap.add_argument("--steps", type=int, default=3000, help="steps of the default sampler's chain")
    ap.add_argument("--walkers", type=int, default=52,
                    help="walkers of the second chain, for as many evaluations (0: no second chain)")
    ap.add_argument("--transport", action="store_true",
                    help="a third chain, its independence move after the triangular map (Adaptation(transport=True))")
    ap.add_argument("--slice", choices=("differential", "global"),
                    help="a chain of ensemble slice sampling (zeus-mcmc) from the first chain's last walkers")
    ap.add_argument("--pairs", type=int, default=300)
    ap.add_argument("--out", default=str(ROOT / "results" / "chain-geometry"))
    ap.add_argument("--fits", default=str(ROOT / "runs" / "chain-geometry"))
    args = ap.parse_args(argv)
    if args.steps < 300 or args.walkers == 1 or args.walkers < 0 or args.pairs < 10:
        print("error: --steps must be at least 300, --walkers 0 or at least 2 and --pairs at least 10", file=sys.stderr)
        return 2
    out = Path(args.out)
    cs = replace(StudyCalibration(), steps=None, seed=args.seed, single=True,
                 likelihood=LikelihoodSettings(residual="motion"), frequencies=(0.5, 1.0, 1.5))
    device = replicate_device(cs, args.replicate)
    record = device.records[0]
    commit = git_commit(ROOT)
    base = {"seed": args.seed, "replicate": args.replicate, "freq_hz": record.metadata.get("drive_frequency_hz"),
            "commit": commit}
    rows = []
    fits = Path(args.fits)
    first = fits / f"seed{args.seed}_{args.replicate}_default"
    runs = {"default": fit(record, first, args.steps, None, args.replicate)}
    print(f"default sampler: {runs['default']['walkers']} walkers, tau {runs['default']['tau_max']:.0f} steps, "
          f"{runs['default']['moved']:.3f} of walker steps moved", flush=True)
    if args.walkers:
        steps2 = max(300, args.steps * runs["default"]["walkers"] // args.walkers)
        runs[f"{args.walkers} walkers"] = fit(record, fits / f"seed{args.seed}_{args.replicate}_w{args.walkers}",
                                              steps2, args.walkers, args.replicate)
    if args.transport:
        runs["transport map"] = fit(record, fits / f"seed{args.seed}_{args.replicate}_transport", args.steps, None,
                                    args.replicate, Adaptation(transport=True))
    model, coords = sampled_model(PosteriorModel(record, priors=STUDY_SBC_PRIORS,
                                                 likelihood=LikelihoodSettings(residual="motion")), first / "chain.h5")
    chain = read_chain(first / "chain.h5")
    if args.slice:
        r = slice_chain(posterior_in(model, coords), chain[-1], chain.shape[0] * chain.shape[1], args.slice,
                        args.seed * 1000 + args.replicate, fits / f"seed{args.seed}_{args.replicate}_slice_{args.slice}")
        print(f"ensemble slice ({args.slice}): tau {r['tau_max']:.0f} steps, {r['per_step']:.2f} evaluations a "
              f"walker step", flush=True)
        runs[f"ensemble slice, {args.slice} (zeus)"] = {**r, "tau": dict(zip(model.names, r["tau"]))}
    for name, r in runs.items():
        statistic = ("largest tau (steps) x walkers x evaluations per walker step" if "slice" in name
                     else "largest tau (steps) x walkers")
        rows.append({**base, "variant": name, "statistic": statistic,
                     "value": r["evaluations_per_tau"], "value2": r["tau_max"], "steps": r["steps"],
                     "walkers": r["walkers"], "moved": round(r["moved"], 4), "seconds": r["seconds"],
                     "tau": " ".join(f"{k}={v:.0f}" for k, v in sorted(r["tau"].items(), key=lambda kv: -kv[1]))})
    for row in geometry(model, coords, chain, args.pairs, np.random.default_rng(args.seed)):
        rows.append({**base, "variant": "default", **row})
    made = {row["variant"] for row in rows}  # other replicates' rows kept, and this one's other variants
    others = [r for r in read_rows(out / "geometry.csv")
              if (r["seed"], r["replicate"]) != (str(args.seed), str(args.replicate)) or r["variant"] not in made]
    write_rows(out / "geometry.csv", [{k: row.get(k, "") for k in FIELDS} for row in others + rows])
    return 0


if __name__ == "__main__":
    sys.exit(main())
