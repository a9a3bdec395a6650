"""Which of the motion-in likelihood's parts makes its posterior too narrow when its own
marginalised deviations are in the record? (results/coverage-sbc-v12; issue 39, item 4.)

A probe, not a calibration: for a few of SBC v12's devices (their true parameters, the
same records' settings), the device is recorded again N times with fresh sensor noise
and, in turn, no deviations, the reversals' only, the friction law's only and both
(``study_calibration.drawn_deviations(groups=...)``). Each record's model takes the truth
as its reference point (so that the deviations' prior sd and the normaliser are the
generator's), tau at its prior's floor (no discrepancy: the records have none) and the
channels' delay at the value that fits the noise-only records best. At that point theta0
the log-likelihood's score s (central differences in the sampler's coordinates) is
taken on every record, and its Hessian too (averaged: F).

If the likelihood's covariance is the generator's, Var(s) = F = -E[Hessian] (the
information identity). The posterior's curvature is F plus the prior's, and a linearised
estimate moves by Sigma s with Sigma = (F + P)^-1, so in the direction w = Sigma g of a
quantity g (a parameter, or log b - log gain) the ratio

    ratio = w' Var(s) w / w' F w

is how much the posterior's variance of g, from the data, falls short of the spread the
records really give: 1 when the likelihood is right, above 1 when its posterior is too
narrow. This is a sandwich (a local, Gaussian stand-in for the chain), read beside the
chains of results/coverage-sbc-v12, not in their place.

    python studies/deviation_sandwich.py [--replicates 2 5 11 0 1] [--draws 100] [--seed 29]
        [--normaliser full] [--out results/deviation-sandwich]

Writes ratios.csv (replicate, frequency, condition, quantity, ratio, its bootstrap 90 %
interval, the mean score's shift in sd) and prints one line per replicate and condition.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
from pathlib import Path

import numpy as np

from bayes_inerter.cli.study_script import config_from_folder
from bayes_inerter.inference.posterior.likelihood import NORMALISERS
from bayes_inerter.inference.posterior.model import PosteriorModel
from bayes_inerter.records import generate_record
from bayes_inerter.study.study_calibration import Config, drawn_deviations, replicate_device

from _table import write_table

ROOT = Path(__file__).resolve().parents[1]
V12 = ROOT / "results" / "coverage-sbc-v12"
CONDITIONS = ("none", "reversals", "law", "all")
TAU = 1e-3  # N: the floor of tau's prior; the records hold no discrepancy
#: the central differences' step in the sampler's coordinates (chosen where the score
#: agrees to 0.1 % between steps ten times apart and the curvature is not noise)
STEP = {"delay": 2e-7, "zeta_B": 1e-2, "k_B": 1e-2}
DEFAULT_STEP = 1e-3
#: the parameters whose posterior the sandwich's Sigma spans (see main)
IDENTIFIED = ("b", "f_0", "f_share", "c_f", "gain", "delay")
BOOT = 400


def record_again(cs, device, freq, condition, rng):
    """The device recorded again with fresh noise and the condition's deviations."""
    rec = generate_record(device.params, freq, settings=cs.generator, rng=rng, setting_name=cs.setting)
    rec = dataclasses.replace(rec, accel=rec.accel * device.truth.get("gain", 1.0))
    if condition != "none":
        rec = drawn_deviations(rec, device.params, cs.likelihood, rng, groups=condition)
    return rec


def score(f, theta, steps):
    g = np.empty(theta.size)
    for i, h in enumerate(steps):
        up, down = theta.copy(), theta.copy()
        up[i] += h
        down[i] -= h
        g[i] = (f(up) - f(down)) / (2.0 * h)
    return g


def hessian(f, theta, steps):
    n = theta.size
    H = np.empty((n, n))
    for i in range(n):
        for j in range(i, n):
            def at(a, b):
                t = theta.copy()
                t[i] += a * steps[i]
                t[j] += b * steps[j]
                return f(t)
            H[i, j] = H[j, i] = (at(1, 1) - at(1, -1) - at(-1, 1) + at(-1, -1)) / (4.0 * steps[i] * steps[j])
    return H


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--replicates", type=int, nargs="+", default=[2, 5, 11, 0, 1])
    ap.add_argument("--draws", type=int, default=100)
    ap.add_argument("--seed", type=int, default=29)
    ap.add_argument("--normaliser", choices=NORMALISERS, default=None,
                    help="the likelihood's normaliser (LikelihoodSettings.normaliser; default: v12's)")
    ap.add_argument("--out", default=str(ROOT / "results" / "deviation-sandwich"))
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    cs = config_from_folder(Config, V12).settings()
    if args.normaliser:
        cs = dataclasses.replace(cs, likelihood=dataclasses.replace(cs.likelihood, normaliser=args.normaliser))
    rows = []
    for k in args.replicates:
        device = replicate_device(cs, k)
        freq = cs.frequencies[k % len(cs.frequencies)]
        names = None
        records = {}
        for ci, cond in enumerate(CONDITIONS):
            records[cond] = [record_again(cs, device, freq, cond, np.random.default_rng([args.seed, k, ci, r]))
                             for r in range(args.draws)]
        base = PosteriorModel(records["none"][0], priors=cs.priors(), likelihood=cs.likelihood)
        names = base.names
        value = {**device.truth, "tau": TAU, "delay": 0.0}
        theta0 = np.array([math.log(value[n]) if base.all_priors[n].log_scale else value[n] for n in names])
        free = [i for i, n in enumerate(names) if n != "tau"]
        steps = np.array([STEP.get(names[i], DEFAULT_STEP) for i in free])
        # the channels' delay: the value that fits the noise-only records best
        di = names.index("delay")
        grid = np.linspace(-2e-4, 2e-4, 81)
        first = [PosteriorModel(r, priors=cs.priors(), likelihood=cs.likelihood).with_reference(theta0)
                 for r in records["none"][:10]]

        def total(d):
            t = theta0.copy()
            t[di] = d
            return sum(m.log_likelihood(t)[0] for m in first)
        theta0[di] = grid[int(np.argmax([total(d) for d in grid]))]

        # the prior's curvature; where it is flat (a uniform prior), the curvature of a
        # normal of the prior's own variance stands in, so that a direction the records
        # do not inform keeps its prior's width
        P = -hessian(lambda t: base.log_prior(_full(theta0, free, t)), theta0[free], steps)
        prior_rng = np.random.default_rng([args.seed, k, 98])
        for j, i in enumerate(free):
            spread = float(np.var(base.all_priors[names[i]].sample(prior_rng, 2000)))
            P[j, j] = max(P[j, j], 1.0 / spread)
        for cond in CONDITIONS:
            models = [PosteriorModel(r, priors=cs.priors(), likelihood=cs.likelihood).with_reference(theta0)
                      for r in records[cond]]

            def loglik_of(m):
                return lambda t: m.log_likelihood(_full(theta0, free, t))[0]
            S = np.array([score(loglik_of(m), theta0[free], steps) for m in models])
            F = -np.mean([hessian(loglik_of(m), theta0[free], steps) for m in models], axis=0)
            # the posterior's curvature on the parameters the records identify (the others
            # held at the truth: at the truth the log-likelihood is not concave in the
            # nut's and the bearing's, and their prior is flat); each parameter's own
            # ratio is the information identity along its axis, all parameters free
            ident = [j for j, i in enumerate(free) if names[i] in IDENTIFIED]
            Sigma = np.zeros_like(F)
            block = (F + P)[np.ix_(ident, ident)]
            concave = bool(np.linalg.eigvalsh(block)[0] > 0.0)
            Sigma[np.ix_(ident, ident)] = np.linalg.inv(block) if concave else np.nan
            quantities = {names[i]: np.eye(len(free))[j] for j, i in enumerate(free)}
            quantities["b/gain"] = quantities["b"] - quantities["gain"]
            rng = np.random.default_rng([args.seed, k, 99])
            line = []
            for q, g in quantities.items():
                w = Sigma @ g if q in IDENTIFIED or q == "b/gain" else g
                proj = S @ w
                model_var = float(w @ F @ w)
                if not model_var > 0.0:  # the log posterior is not concave there: no Gaussian stand-in
                    rows.append({"replicate": k, "frequency": freq, "normaliser": cs.likelihood.normaliser,
                                 "condition": cond, "quantity": q, "ratio": "not concave", "ratio_q05": "",
                                 "ratio_q95": "", "mean_shift_sd": "", "posterior_sd": "",
                                 "delay": f"{theta0[di]:.3g}", "draws": len(models)})
                    continue
                ratio = float(np.var(proj, ddof=1)) / model_var
                boot = [np.var(proj[rng.integers(0, proj.size, proj.size)], ddof=1) / model_var for _ in range(BOOT)]
                shift = float(np.mean(proj)) / math.sqrt(float(np.var(proj, ddof=1)))
                rows.append({"replicate": k, "frequency": freq, "normaliser": cs.likelihood.normaliser, "condition": cond, "quantity": q,
                             "ratio": f"{ratio:.3f}", "ratio_q05": f"{np.quantile(boot, 0.05):.3f}",
                             "ratio_q95": f"{np.quantile(boot, 0.95):.3f}", "mean_shift_sd": f"{shift:+.3f}",
                             "posterior_sd": (f"{math.sqrt(float(g @ Sigma @ g)):.4g}"
                                              if q in IDENTIFIED or q == "b/gain" else ""),
                             "delay": f"{theta0[di]:.3g}", "draws": len(models)})
                if q in ("b/gain", "f_0", "c_f", "k_B"):
                    line.append(f"{q} {ratio:.2f}")
            print(f"replicate {k} ({freq:g} Hz) {cond:9s}: " + ", ".join(line)
                  + ("" if concave else " (not concave at the truth)"), flush=True)
            write_table(out / "ratios.csv", rows)
    return 0


def _full(theta0, free, t):
    full = theta0.copy()
    full[free] = t
    return full


if __name__ == "__main__":
    sys.exit(main())
