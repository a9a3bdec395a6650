"""Benchmark: end-to-end time of a posterior for one 10 s record, and the share of it
spent in the simulator.

Run by hand: ``python benchmarks/bench_fit.py [--steps 300] [--processes 1]``. Runs a
fixed number of steps (single process, so the simulator's share can be timed in-process),
then prints the time per step and per log-probability evaluation, the simulator's share,
the autocorrelation time estimated from the run, and what 50 tau steps would cost at the
measured rate (a projection, labelled as such).
"""

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

import bayes_inerter.inference.model as model_module
from bayes_inerter import paper_parameters
from bayes_inerter.inference import fit_record
from bayes_inerter.records import generate_record


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--setting", default="A3")
    ap.add_argument("--freq", type=float, default=1.0)
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--walkers", type=int, default=24)
    args = ap.parse_args()

    rec = generate_record(paper_parameters(args.setting), args.freq, rng=1, setting_name=args.setting)
    spent = {"simulate": 0.0, "calls": 0}
    original = model_module.simulate

    def timed_simulate(*a, **k):
        t0 = time.perf_counter()
        try:
            return original(*a, **k)
        finally:
            spent["simulate"] += time.perf_counter() - t0
            spent["calls"] += 1

    model_module.simulate = timed_simulate
    with tempfile.TemporaryDirectory() as d:
        t0 = time.perf_counter()
        result = fit_record(rec, d, steps=args.steps, walkers=args.walkers, seed=0, processes=1, plots=False)
        total = time.perf_counter() - t0
    model_module.simulate = original
    t_sample = result.timings["sampling"]
    evals = args.steps * args.walkers
    print(f"record {args.setting} {args.freq} Hz, 10 s at 1 kHz; {args.walkers} walkers, {args.steps} steps, 1 process")
    print(f"total {total:.1f} s (sampling incl. start-up optimisation {t_sample:.1f} s, posterior draws "
          f"{result.timings['posterior_draws']:.1f} s)")
    print(f"simulator: {spent['calls']} calls, {spent['simulate']:.1f} s = {spent['simulate'] / total:.0%} of the total, "
          f"{spent['simulate'] / spent['calls'] * 1e3:.2f} ms a call")
    print(f"per step {t_sample / args.steps * 1e3:.0f} ms; per evaluation about {t_sample / (evals + 1) * 1e3:.2f} ms")
    from bayes_inerter.inference.model import PosteriorModel

    model = PosteriorModel(rec)
    theta = model.to_theta(paper_parameters(args.setting), 0.003, 0.1)
    model.log_prob(theta)
    times = []
    for _ in range(30):
        t1 = time.perf_counter()
        model.log_prob(theta)
        times.append(time.perf_counter() - t1)
    per_eval = float(np.median(times))
    print(f"one log-probability evaluation: median {per_eval * 1e3:.2f} ms (30 calls)")
    taus = []
    for f in sorted((Path(__file__).resolve().parents[1] / "results" / "recovery").glob("*/fit.json")):
        taus.append(max(json.loads(f.read_text())["tau"].values()))
    if taus:
        tau = max(taus)
        evals = 50 * tau * args.walkers
        print(f"largest autocorrelation time in results/recovery: {tau:.0f} steps; 50 tau x {args.walkers} walkers "
              f"= {evals:,.0f} evaluations = {evals * per_eval / 60:.0f} min on one process, "
              f"{evals * per_eval / 120:.0f} min on two (projection from the measured rates)")


if __name__ == "__main__":
    main()
