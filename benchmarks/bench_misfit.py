"""Benchmark: sampling under misfit. Time to a converged posterior on one core for
records of a device richer than the fitted model, beside records of the model itself.

Run by hand from the project root: ``python benchmarks/bench_misfit.py [--setting A3]
[--freqs 0.5 1.0 1.5] [--seed 0] [--cap-seconds 360] [--max-steps N] [--tempering TEMPS
[--hottest-beta 0.1] [--growth each|largest]]``.

For each frequency, two 10 s records of the setting: the model's own (today's default,
``records.generator.paper_record``, grid seed ``--seed``) and a paper-like one
(``records.paper_like.paper_like_record``: full network, Stribeck friction, nut
backlash, calibration errors and coloured noise; laboratory seed ``--seed``). Each is
fitted by ``fit_record`` with the package's defaults (the posterior's ensemble alone;
rows whose sampler is "default" and dated 2026-12-03 or later were tempered, 4
temperatures, while that was ``fit``'s default), one process, until the convergence
rule holds (``steps=None``), without plots, into a temporary folder.

A run still going after ``--cap-seconds`` of wall time is stopped by its ``progress``
callback (the check comes after each step, so the start-up optimisation is not cut)
and its outputs are then written from the checkpoint by a second ``fit_record`` with
``steps`` set to the steps taken (nothing more is sampled): it counts as not converged,
with tau as that last check finds it. ``--max-steps`` caps the steps instead
(``Convergence.max_steps``; default the package's 20,000).

Printed per fit: converged or why not, steps, the largest tau and the parameters with
the largest three, sampling seconds (``FitResult.timings``: start-up optimisation
included; for a capped run the wall time until the cap), end-to-end wall seconds
(posterior draws and outputs included), b's posterior median (of the draws
posterior.nc keeps) and 94 % HDI against the true b, and whether it met the issue's
target: converged in under 120 s end to end. The 1-minute load average before and
after each fit is printed and kept; the machine is shared, so seconds are only
comparable within one run. One row per fit goes to
results/performance/misfit_default.csv, with its sampler (results/performance/misfit.csv
holds the rows of the ensemble sampler alone, the default before).

With ``--tempering TEMPS`` each record is fitted twice, side by side in the same run:
with the ensemble alone (``tempering=None``; its rows' ``sampler`` is "ensemble", and
"default" in the rows written while it was the package's default) and with parallel
tempering (``sampler.Tempering``, TEMPS
temperatures down to ``--hottest-beta``, its convergence rule judging tau's growth as
``--growth`` says, ``Convergence.growth``); the evaluations of the log posterior after the
start search (steps x walkers x temperatures), the swap rates and the ratio of the
tempered fit's wall time to the default's are printed, and the rows go to
results/performance/misfit_tempering.csv instead.

With ``--models M [M ...]`` each record is fitted under each of these models
(``fit_record(model=...)``; for example ``two-port two-port-rich``), side by side in the
same run with the ensemble sampler alone (as its rows were made before ``fit`` tempered
by default); the ratio of each fit's wall time to the first
model's is printed, and the rows, with their model, go to
results/performance/misfit_models.csv instead.
"""

import argparse
import dataclasses
import json
import os
import tempfile
import time
from pathlib import Path

import numpy as np
from _timing import record_row, supported_theta

from bayes_inerter import paper_parameters
from bayes_inerter.inference import Convergence, PosteriorModel, fit_record
from bayes_inerter.inference.sampling.convergence import GROWTH
from bayes_inerter.inference.sampling.sampler import Tempering
from bayes_inerter.records import GeneratorSettings
from bayes_inerter.records.generator import paper_record
from bayes_inerter.records.paper_like import PaperLike, paper_like_record

TARGET_S = 120.0


class _Capped(Exception):
    """Raised by the progress callback when a fit runs past its wall-time cap."""

    def __init__(self, steps: int, seconds: float):
        super().__init__(f"capped at {steps} steps, {seconds:.0f} s")
        self.steps, self.seconds = steps, seconds


def fit_capped(record, out: Path, *, seed: int, cap_s: float, convergence, tempering=None,
               model: str = "two-port") -> dict:
    """Fit ``record`` under ``model`` into ``out`` until converged or ``cap_s`` seconds
    (``tempering``: the sampler's ladder, None: none); what the row needs."""
    t0 = time.perf_counter()

    def progress(iteration, target):
        elapsed = time.perf_counter() - t0
        if elapsed > cap_s:
            raise _Capped(iteration, elapsed)

    capped = None
    try:
        res = fit_record(record, out, seed=seed, processes=1, plots=False, convergence=convergence,
                         progress=progress, tempering=tempering, model=model)
    except _Capped as stop:
        capped = stop
        # the checkpoint holds the steps taken: write the outputs from it, sampling nothing more
        res = fit_record(record, out, seed=seed, processes=1, plots=False, convergence=convergence,
                         steps=stop.steps, tempering=tempering, model=model)
    wall = time.perf_counter() - t0
    tau = json.loads((out / "fit.json").read_text())["tau"]
    b = res.row("b")
    converged = res.converged and capped is None
    return {
        "converged": converged,
        "reason": (res.reason.removeprefix("not converged: ") if capped is None else
                   f"stopped by the wall-time cap of {cap_s:g} s"),
        "steps": int(res.iterations),
        "walkers": int(res.idata.posterior.sizes["chain"]),
        "tau": tau,
        "sampling_s": capped.seconds if capped else res.timings["sampling"],
        "wall_s": wall,
        "b_median": float(np.median(res.idata.posterior["b"].values)),
        "b_3": b["hdi_3%"],
        "b_97": b["hdi_97%"],
        "met": converged and wall < TARGET_S,
        "evaluations": int(res.iterations) * int(res.idata.posterior.sizes["chain"])
        * (1 if tempering is None else tempering.temps),
        "swap_rates": [] if res.tempering is None else res.tempering["swap_rates"],
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--setting", default="A3")
    ap.add_argument("--freqs", type=float, nargs="+", default=[0.5, 1.0, 1.5])
    ap.add_argument("--seed", type=int, default=0,
                    help="the records' seed (grid seed of the model's records, laboratory seed of the paper-like "
                         "ones) and the fit's")
    ap.add_argument("--cap-seconds", type=float, default=360.0, help="wall-time cap per fit, s")
    ap.add_argument("--max-steps", type=int, default=None,
                    help="stop a chain here if not converged (default: the package's 20,000)")
    ap.add_argument("--truths", nargs="+", choices=("model", "paper-like"), default=["model", "paper-like"])
    ap.add_argument("--tempering", type=int, default=None, metavar="TEMPS",
                    help="also fit each record with parallel tempering of this many temperatures, side by side")
    ap.add_argument("--hottest-beta", type=float, default=0.1, help="the tempering ladder's hottest beta")
    ap.add_argument("--growth", choices=GROWTH, default=None,
                    help="the tempered fits' judgement of tau's growth (Convergence.growth; default: the package's)")
    ap.add_argument("--models", nargs="+", default=None, metavar="MODEL",
                    help="fit each record under each of these models, side by side (the ensemble sampler alone)")
    ap.add_argument("--no-row", action="store_true", help="print only; write no CSV row (trial runs)")
    args = ap.parse_args()
    if args.models and args.tempering:
        ap.error("--models and --tempering each compare fits side by side; give one of them")
    models = args.models or ["two-port"]
    conv = Convergence(max_steps=args.max_steps) if args.max_steps else None
    samplers = [("ensemble", None, conv)]  # the package's default sampler
    if args.tempering:
        ladder = Tempering(args.tempering, args.hottest_beta)
        hot_conv = conv
        if args.growth is not None:
            hot_conv = dataclasses.replace(conv or Convergence(), growth=args.growth)
        name = f"tempered {ladder.temps} to {ladder.beta_min:g}" + (f", growth {args.growth}" if args.growth else "")
        samplers.append((name, ladder, hot_conv))

    device = PaperLike(base=GeneratorSettings(duration=10.0))
    makers = {"model": lambda f: paper_record(args.setting, f, seed=args.seed),
              "paper-like": lambda f: paper_like_record(args.setting, f, seed=args.seed, device=device)}

    # compile the kernels before the first fit is timed
    warm = PosteriorModel(makers["model"](args.freqs[0]))
    supported_theta(warm, paper_parameters(args.setting), 0.003, 0.1)  # evaluates it

    print(f"{args.setting}, seed {args.seed}, one process, cap {args.cap_seconds:g} s a fit"
          + (f", at most {args.max_steps} steps" if args.max_steps else "") + f"; load {os.getloadavg()[0]:.2f}")
    results = []
    for freq in args.freqs:
        for truth in args.truths:
            rec = makers[truth](freq)
            b_true = rec.metadata["true_parameters"]["b"]
            for model, (sampler, ladder, rule) in [(m, s) for m in models for s in samplers]:
                load0 = os.getloadavg()[0]
                with tempfile.TemporaryDirectory() as d:
                    got = fit_capped(rec, Path(d) / "fit", seed=args.seed, cap_s=args.cap_seconds, convergence=rule,
                                     tempering=ladder, model=model)
                load1 = os.getloadavg()[0]
                slow = sorted(got["tau"].items(), key=lambda kv: -kv[1])
                got.update(truth=truth, freq=freq, b_true=b_true, load=(load0, load1), slow=slow, sampler=sampler,
                           model=model)
                results.append(got)
                print(f"  {truth} {freq:g} Hz, {model if args.models else sampler}: "
                      f"{'converged' if got['converged'] else 'NOT converged: ' + got['reason']}, "
                      f"{got['steps']} steps, {got['wall_s']:.0f} s; tau " +
                      ", ".join(f"{n} {t:.0f}" for n, t in slow[:3]) + f"; load {load0:.2f} -> {load1:.2f}", flush=True)
                if not args.no_row:
                    row = {
                        "setting": args.setting, "freq_hz": freq, "truth": truth, "seed": args.seed,
                        "processes": 1, "cap_s": args.cap_seconds, "converged": got["converged"],
                        "reason": got["reason"], "steps": got["steps"], "walkers": got["walkers"],
                        "max_tau": round(slow[0][1], 1), "slowest": slow[0][0], "second": slow[1][0],
                        "sampling_s": round(got["sampling_s"], 1), "wall_s": round(got["wall_s"], 1),
                        "b_3%": round(got["b_3"], 1), "b_50%": round(got["b_median"], 1),
                        "b_97%": round(got["b_97"], 1), "b_truth": round(b_true, 1),
                        "covers": got["b_3"] <= b_true <= got["b_97"], "under_120s": got["met"],
                        "load_before": round(load0, 2), "load_after": round(load1, 2)}
                    if not args.models:
                        row.update(sampler=sampler, evaluations=got["evaluations"],
                                   swap_rates=" ".join(f"{r:.3f}" for r in got["swap_rates"]))
                    if args.models:
                        row.update(model=model)
                    record_row(_csv_name(args), row)

    print()
    head = (f"{'record':>16} {'conv':>5} {'steps':>6} {'max tau':>8} {'slowest':>8} {'sampling s':>10} "
            f"{'wall s':>7} {'b median':>9} {'b 94% HDI':>17} {'b true':>7} {'<120 s':>6} {'load':>11}")
    print(head)
    print("-" * len(head))
    for r in results:
        name = (f"{r['truth']} {r['freq']:g} Hz" + (" PT" if args.tempering and r["sampler"] != "ensemble" else "")
                + (f" {r['model']}" if args.models else ""))
        print(f"{name:>16} {'yes' if r['converged'] else 'no':>5} {r['steps']:>6} {r['slow'][0][1]:>8.0f} "
              f"{r['slow'][0][0]:>8} {r['sampling_s']:>10.0f} {r['wall_s']:>7.0f} {r['b_median']:>9.1f} "
              f"{r['b_3']:>8.1f}-{r['b_97']:<8.1f} {r['b_true']:>7.1f} {'yes' if r['met'] else 'no':>6} "
              f"{r['load'][0]:>5.2f}-{r['load'][1]:<5.2f}")
    print(f"\ntarget: converged in under {TARGET_S:.0f} s end to end on one process; conv 'no' = stopped by the cap "
          f"or max steps, not by the convergence rule")
    if args.tempering:
        print("\ntempered against the ensemble alone, same record and seed: wall-time ratio, evaluations ratio")
        for plain, hot in zip(results[::2], results[1::2]):
            print(f"  {plain['truth']} {plain['freq']:g} Hz: {hot['wall_s'] / plain['wall_s']:.2f}, "
                  f"{hot['evaluations'] / plain['evaluations']:.2f}; swap rates "
                  + ", ".join(f"{r:.0%}" for r in hot["swap_rates"]))
    if args.models:
        print(f"\neach model against {models[0]}, same record and seed: wall-time ratio")
        for i in range(0, len(results), len(models)):
            first = results[i]
            print(f"  {first['truth']} {first['freq']:g} Hz: " + ", ".join(
                f"{r['model']} {r['wall_s'] / first['wall_s']:.2f}" for r in results[i + 1: i + len(models)]))
    if not args.no_row:
        print(f"wrote rows to results/performance/{_csv_name(args)}.csv")


def _csv_name(args) -> str:
    return "misfit_tempering" if args.tempering else "misfit_models" if args.models else "misfit_default"


if __name__ == "__main__":
    main()
