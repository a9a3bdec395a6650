"""Benchmark: end-to-end time to a converged posterior for one 10 s record, and the share
of it spent in the simulator.

Run by hand: ``python benchmarks/bench_fit.py [--setting A3] [--freq 1.0] [--processes 2]``.

1. One log-probability evaluation and one simulation, timed side by side (medians).
2. A short single-process run (``--profile-steps``, default 200), with the simulator
   timed in-process: its share of the sampler's time.
3. The end-to-end run: ``fit_record`` without ``steps`` (start-up optimisation, Laplace
   start, emcee until the package's convergence criteria hold, posterior draws and
   outputs, plots included) on ``--processes`` worker processes; its wall time against
   the 2-minute target, with the steps, walkers and largest tau it needed.

The machine is shared and noisy: run it when it is otherwise idle, and read the ratios.
"""

import argparse
import tempfile
import time

import numpy as np

import bayes_inerter.inference.posterior.model as model_module
from _timing import median_time, record_row, supported_theta

from bayes_inerter import paper_parameters, simulate
from bayes_inerter.inference import Convergence, fit_record
from bayes_inerter.inference.posterior.model import PosteriorModel
from bayes_inerter.records import generate_record

TARGET_S = 120.0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--setting", default="A3")
    ap.add_argument("--freq", type=float, default=1.0)
    ap.add_argument("--processes", type=int, default=2)
    ap.add_argument("--profile-steps", type=int, default=200)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--max-steps", type=int, default=None,
                    help="stop the end-to-end chain here if not converged (default: the package's 20,000)")
    args = ap.parse_args()

    truth = paper_parameters(args.setting)
    rec = generate_record(truth, args.freq, rng=1, setting_name=args.setting)
    print(f"record {args.setting} {args.freq:g} Hz, {rec.time[-1]:g} s at {rec.fs:g} Hz")

    model = PosteriorModel(rec)
    theta = supported_theta(model, truth, 0.003, 0.1)
    params = model.parameters(theta)
    t_lp = median_time(lambda: model.log_prob(theta))
    t_sim = median_time(lambda: simulate(params, rec.time, rec.force, sampling="mean"))
    print(f"one log-probability: median {t_lp * 1e3:.2f} ms; one simulation: median {t_sim * 1e3:.2f} ms "
          f"({t_sim / t_lp:.0%} of it)")

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
    try:
        with tempfile.TemporaryDirectory() as d:
            short = fit_record(rec, d, steps=args.profile_steps, seed=args.seed, processes=1, plots=False)
    finally:
        model_module.simulate = original
    t_short = short.timings["sampling"]
    per_call = f"{spent['simulate'] / spent['calls'] * 1e3:.2f} ms a call" if spent["calls"] else "no call"
    print(f"{args.profile_steps} steps on 1 process: sampling {t_short:.1f} s (start-up included), "
          f"simulator() {spent['simulate']:.1f} s = {spent['simulate'] / t_short:.0%} of it "
          f"({spent['calls']} calls, {per_call}; the default likelihood simulates the drivetrain through "
          f"its own kernel, not simulate(), so its share shows as the log-probability's time above)")

    with tempfile.TemporaryDirectory() as d:
        t0 = time.perf_counter()
        conv = Convergence(max_steps=args.max_steps) if args.max_steps else None
        res = fit_record(rec, d, seed=args.seed, processes=args.processes, convergence=conv)
        wall = time.perf_counter() - t0
    b = res.row("b")
    verdict = (f"converged: {wall / TARGET_S:.2f} x the {TARGET_S:.0f} s target" if res.converged else
               f"NOT converged ({res.reason}): a converged posterior takes longer than this")
    print(f"end to end, {args.processes} processes: {wall:.0f} s wall; {verdict}; {res.iterations} steps x "
          f"{res.idata.posterior.sizes['chain']} walkers, largest tau {np.max(res.tau):.0f}")
    print(f"  split: sampling (with start-up) {res.timings['sampling']:.0f} s, posterior draws "
          f"{res.timings['posterior_draws']:.0f} s, outputs and plots "
          f"{res.timings['total'] - res.timings['sampling'] - res.timings['posterior_draws']:.0f} s")
    print(f"  b: {b['mean']:.1f} kg, 94 % HDI {b['hdi_3%']:.1f}-{b['hdi_97%']:.1f} (truth {truth.b:g})")
    path = record_row("fit", {
        "setting": args.setting, "freq_hz": args.freq, "seed": args.seed, "processes": args.processes,
        "log_prob_ms": round(t_lp * 1e3, 3), "simulation_ms": round(t_sim * 1e3, 3),
        "profile_steps": args.profile_steps, "profile_sampling_s": round(t_short, 2),
        "profile_simulator_share": round(spent["simulate"] / t_short, 4), "wall_s": round(wall, 1),
        "converged": bool(res.converged), "steps": res.iterations, "tau_max": round(float(np.max(res.tau)), 1),
        "b_mean": round(b["mean"], 2), "b_hdi_3": round(b["hdi_3%"], 2), "b_hdi_97": round(b["hdi_97%"], 2),
        "b_true": truth.b})
    print(f"wrote a row to {path}")


if __name__ == "__main__":
    main()
