"""Is a calibration replicate's posterior the density's, or the sampler's? (issue 39, item 4.)

On records drawn from the likelihood itself (results/coverage-sbc-likelihood-force-exact)
the fitted density is the one that drew the force, and yet the truths fall outside the
intervals more often than nominal. If the chain were not sampling that density, other
kernels would place the posterior elsewhere. This probe fits chosen replicates of a
calibration folder again, the same device and records (its settings), under kernels that
share as little as possible with the default:

- ``long``: the default kernel (the folder's moves, fitted proposals, coordinates and
  tempering) run a fixed ``--steps`` instead of to the rule, from its own start search;
- ``ensemble``: the ensemble moves alone (no fitted moves), a fixed ``--steps``;
- ``physical``: the same, walking theta itself (no impedance map, no logits);
- ``at-truth``: the ensemble moves in theta, every walker started near the truth (the
  drawn vector, :class:`ReplicateDevice`'s ``theta``; tau at its prior's floor), a fixed
  ``--steps``, the first half left out;
- ``metropolis``: another family altogether, one chain of adaptive random-walk
  Metropolis (Haario, Saksman and Tamminen 2001: a normal proposal of covariance
  2.38^2/d times the chain's own after a tenth's burn-in, with Roberts and Rosenthal's
  fixed small proposal in 5 % of the steps) in the fit's impedance coordinates, started
  at the truth (tau at e times its prior's floor, inside the range the chain walks),
  ``--iterations`` steps; the proposal adapts in the first half and is frozen in the
  second, which alone is kept (an exact Metropolis chain there), thinned to at most
  4,000 draws;
- ``tau-floor``: the default kernel and rule with tau's prior squeezed to its floor
  (1e-3 to 1.001e-3 N): the records carry no discrepancy, while the fits sample tau from
  a log-uniform prior from 1e-3 N, so this rules that mismatch in or out.

and beside them the folder's own replicate (``rule``: the default kernel to the rule).
Each row of ranks.csv: a replicate, a kernel, a ranked parameter, the share of the
kernel's draws below the truth, the draws' 3, 50 and 97 % quantiles, and whether the
94 % and 50 % highest-density intervals hold the truth.

    python studies/kernel_agreement.py --folder results/coverage-sbc-likelihood-force-exact
        --replicates 10 2 19 [--steps 8000] [--iterations 200000] [--seed 1] [--work runs/kernel-agreement]
        [--out results/kernel-agreement]

A rerun skips the (replicate, kernel) pairs already in ranks.csv.
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import sys
import time
from pathlib import Path

import numpy as np

from bayes_inerter.cli.study_script import config_from_folder
from bayes_inerter.inference import LogUniform, PosteriorModel, fit_record, run_sampler
from bayes_inerter.inference.sampling.convergence import integrated_time
from bayes_inerter.inference.sampling.coordinates import default_coordinates
from bayes_inerter.inference.sampling.target import Target
from bayes_inerter.inference.summaries.results import hdi
from bayes_inerter.study import stop_rule
from bayes_inerter.study.manifest import script_configuration, write_manifest
from bayes_inerter.study.replicate_store import load_replicates
from bayes_inerter.study.study_calibration import LEVELS, Config, replicate_device

from _table import write_table

KERNELS = ("rule", "long", "ensemble", "physical", "at-truth", "metropolis", "tau-floor")
#: The metropolis kernel's kept half is thinned to at most this many draws.
METROPOLIS_DRAWS = 4000
TAU_FLOOR = LogUniform(1e-3, 1.001e-3)


def _rows(k, kernel, draws: dict, truth: dict, steps: int, seconds: float) -> list[dict]:
    rows = []
    for name, t in truth.items():
        x = np.asarray(draws[name], dtype=float)
        row = {"replicate": k, "kernel": kernel, "steps": steps, "seconds": round(seconds, 1), "parameter": name,
               "truth": t, "rank_share": round(float(np.mean(x < t)), 4)}
        for q in (0.03, 0.5, 0.97):
            row[f"q{round(100 * q):02d}"] = float(np.quantile(x, q))
        for level in LEVELS:
            lo, hi = hdi(x, level)
            row[f"hdi{round(100 * level)}"] = bool(lo <= t <= hi)
        rows.append(row)
    return rows


def _rule_rows(rep: dict, k: int, truth: dict) -> list[dict]:
    """The folder's own replicate ``rep``: ranks among its L draws and its intervals' holds."""
    rows = []
    for name, t in truth.items():
        rows.append({"replicate": k, "kernel": "rule", "steps": rep["iterations"], "seconds": None, "parameter": name,
                     "truth": t, "rank_share": round(rep["ranks"][name] / (rep["L"] + 1), 4),
                     "q03": None, "q50": None, "q97": None,
                     **{f"hdi{round(100 * lv)}": rep["hdi"][f"{round(100 * lv)}"][name] for lv in LEVELS}})
    return rows


def _at_truth(cs, device, tau_above_floor: float = 1e-6) -> tuple:
    """The model of ``device``'s record and the truth as a start, tau ``tau_above_floor``
    above its prior's floor in its log (the records carry no discrepancy)."""
    model = PosteriorModel(device.records[0], priors=cs.priors(), likelihood=cs.likelihood)
    theta = np.array(device.theta)
    i = model.names.index("tau")
    theta[i] = model.bounds()[i][0] + tau_above_floor
    return model.with_reference(theta), theta


def metropolis(model, theta, iterations: int, rng: np.random.Generator) -> tuple[np.ndarray, dict]:
    """Adaptive random-walk Metropolis from ``theta`` in ``model``'s impedance coordinates
    (see module docstring): the second half's states, mapped back to theta (thinned to
    at most :data:`METROPOLIS_DRAWS`), and the chain's acceptance and slowest integrated
    autocorrelation time there (NaN where it never moved), with the kept states' count."""
    target = Target(model, default_coordinates(model, "impedance"))
    u = np.asarray(target.coords.to_u(theta), dtype=float).reshape(-1)
    lp = target(u)[0]
    if not np.isfinite(lp):
        raise ValueError("the truth lies outside the impedance coordinates' domain")
    d, half, burn = u.size, iterations // 2, iterations // 10
    fixed = np.eye(d) * 0.1 / np.sqrt(d)  # Roberts and Rosenthal's safeguard, a share of every step
    chol = fixed
    mean, cov, n = u.copy(), np.zeros((d, d)), 0
    kept, accepted = np.empty((iterations - half, d)), 0
    for t in range(iterations):
        if burn + 1000 <= t < half and t % 100 == 0:  # learnt from the states after the burn-in
            chol = np.linalg.cholesky(2.38 ** 2 / d * cov + 1e-6 * np.eye(d))
        step = fixed if rng.uniform() < 0.05 else chol  # a mixture of symmetric proposals: still symmetric
        proposal = u + step @ rng.normal(size=d)
        lp_new = target(proposal)[0]
        if np.log(rng.uniform()) < lp_new - lp:
            u, lp = proposal, lp_new
            accepted += t >= half
        if burn <= t < half:  # the running mean and covariance the proposal learns from
            n += 1
            delta = u - mean
            mean += delta / n
            cov += (np.outer(delta, u - mean) - cov) / n
        elif t >= half:
            kept[t - half] = u
    moved = np.ptp(kept, axis=0) > 0
    tau = float(np.max(integrated_time(kept[:, None, moved]))) if moved.all() else float("nan")
    thetas, _ = target.coords.transform(kept[:: -(-len(kept) // METROPOLIS_DRAWS)])
    return thetas, {"kept": len(kept), "acceptance": accepted / len(kept), "tau": tau}


def _fit(cs, device, kernel: str, steps: int, seed: int, out: Path,
         iterations: int = 200_000) -> tuple[dict, int, dict | None]:
    """(draws by ranked name, the chain's steps, the metropolis chain's mixing or None)."""
    record = device.records[0]
    if kernel == "metropolis":
        # tau at e times its floor: no discrepancy to speak of, yet not the wall
        model, theta = _at_truth(cs, device, tau_above_floor=1.0)
        thetas, info = metropolis(model, theta, iterations, np.random.default_rng(seed))
        tau = info["tau"]
        mixing = {"iterations": iterations, "kept": info["kept"], "acceptance": round(info["acceptance"], 4),
                  "tau_slowest": round(tau, 1) if np.isfinite(tau) else None,
                  "effective_draws": round(info["kept"] / tau) if np.isfinite(tau) else 0}
        values = [model.values(t) for t in thetas]
        return {n: np.array([v[n] for v in values]) for n in device.truth}, iterations, mixing
    if kernel == "at-truth":
        model, theta = _at_truth(cs, device)
        out.mkdir(parents=True, exist_ok=True)
        run = run_sampler(model, out / "chain.h5", steps=steps, seed=seed, fresh=True,
                          start=(theta, model.log_prob(theta)[0]), coordinates="physical", adaptation=None,
                          tempering=cs.tempering)
        chain = run.chain(discard=steps // 2)
        flat = chain.reshape(-1, chain.shape[-1])
        values = [model.values(t) for t in flat[:: max(1, len(flat) // 4000)]]
        return {n: np.array([v[n] for v in values]) for n in device.truth}, steps, None
    kw = dict(seed=seed, priors=cs.priors(), plots=False, likelihood=cs.likelihood, interval="posterior",
              tempering=cs.tempering)
    if kernel == "tau-floor":
        kw.update(priors={**cs.priors(), "tau": TAU_FLOOR}, convergence=stop_rule.convergence(cs.max_steps, cs.tau_rtol))
    elif kernel == "long":
        kw.update(steps=steps)
    else:
        kw.update(steps=steps, adaptation=None, coordinates="physical" if kernel == "physical" else "impedance")
    res = fit_record(record, out, **kw)
    post = res.idata.posterior
    return {n: np.asarray(post[n]).ravel() for n in device.truth}, int(res.iterations), None


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--folder", required=True, help="a single-record calibration folder (its settings.json)")
    ap.add_argument("--replicates", type=int, nargs="+", required=True)
    ap.add_argument("--kernels", nargs="+", default=list(KERNELS), choices=KERNELS)
    ap.add_argument("--steps", type=int, default=8000, help="steps of the fixed-length kernels")
    ap.add_argument("--iterations", type=int, default=200_000, help="steps of the metropolis kernel's chain")
    ap.add_argument("--seed", type=int, default=1, help="the refits' sampler seed")
    ap.add_argument("--work", default="runs/kernel-agreement")
    ap.add_argument("--out", default="results/kernel-agreement")
    args = ap.parse_args(argv)
    folder, out = Path(args.folder), Path(args.out)
    if not (folder / "settings.json").is_file():
        print(f"error: {folder} holds no calibration (no settings.json); give a folder of study_calibration.py",
              file=sys.stderr)
        return 2
    if args.iterations < 20000:
        print(f"error: --iterations must be at least 20000 (the proposal learns from the first half after a "
              f"tenth's burn-in), got {args.iterations}", file=sys.stderr)
        return 2
    if args.steps < 100:
        print(f"error: --steps must be at least 100, got {args.steps}", file=sys.stderr)
        return 2
    cs = config_from_folder(Config, folder).settings()
    if not cs.single:
        print("error: the probe refits single-record calibrations; this folder holds joint fits", file=sys.stderr)
        return 2
    cs = dataclasses.replace(cs, steps=None)
    out.mkdir(parents=True, exist_ok=True)
    write_manifest(out, script_configuration())
    table = out / "ranks.csv"
    rows = list(csv.DictReader(table.open())) if table.exists() else []
    done = {(int(r["replicate"]), r["kernel"]) for r in rows}
    todo = [(k, kern) for k in args.replicates for kern in args.kernels if (k, kern) not in done]
    stored = load_replicates(folder) if any(kern == "rule" for _, kern in todo) else {}
    devices = {}  # each replicate's device and records, drawn once for all its kernels
    for i, (k, kernel) in enumerate(todo, 1):
        if k not in devices:
            devices[k] = replicate_device(cs, k)
        device = devices[k]
        t0 = time.perf_counter()
        if kernel == "rule":
            got = _rule_rows(stored[k], k, device.truth)
        else:
            draws, steps, mixing = _fit(cs, device, kernel, args.steps, args.seed,
                                        Path(args.work) / f"{k:04d}-{kernel}", args.iterations)
            got = _rows(k, kernel, draws, device.truth, steps, time.perf_counter() - t0)
        rows += got
        write_table(table, rows)
        if kernel == "metropolis":  # the chain's own mixing, beside its ranks (written after them: a rerun redoes both)
            table_chains = out / "metropolis.csv"
            old = list(csv.DictReader(table_chains.open())) if table_chains.exists() else []
            write_table(table_chains, [r for r in old if int(r["replicate"]) != k]
                        + [{"replicate": k, "seed": args.seed, **mixing}])
        held = sum(str(r["hdi50"]) == "True" for r in got)
        print(f"[{i}/{len(todo)}] replicate {k}, {kernel}: 50 % intervals held {held} of {len(got)}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
