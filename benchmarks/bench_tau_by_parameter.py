"""Benchmark: which parameters set a paper-like fit's length (issue 40, item 1).

The convergence rule asks for at least 50 autocorrelation times of the slowest parameter
(``Convergence.n_tau``), so a fit's length is set by its slowest few. For each record
(paper-like, ``records.paper_like``, laboratory ``--seed``): one fit of a fixed
``--steps`` on one process, ``fit_record`` as ``bayes-inerter fit`` runs it, and every
parameter's autocorrelation time from its fit.json (emcee's estimate over the kept
draws; a chain shorter than 50 of them underestimates them, so read the ordering first).

Printed per record: the parameters by tau, the slowest over the median (a ratio within
one chain), and the steps the rule would need at that tau (50 tau) with the seconds
they would take at the run's own pace. One row per record goes to
results/performance/tau_by_parameter.csv.

    python benchmarks/bench_tau_by_parameter.py [--records A3:1 A3:0.5 B1:1.5] [--steps 4000] [--seed 11]

The machine is shared and noisy: the taus are the machine's business only through the
seed; the seconds are not a benchmark of speed.
"""

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

from _timing import record_row

from bayes_inerter.inference import Convergence, fit_record
from bayes_inerter.records.paper_like import paper_like_record


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--records", nargs="+", default=["A3:1", "A3:0.5", "B1:1.5"], help="SETTING:FREQ_HZ ...")
    ap.add_argument("--steps", type=int, default=4000)
    ap.add_argument("--seed", type=int, default=11, help="the paper-like laboratory's seed and the fit's")
    args = ap.parse_args()
    n_tau = Convergence().n_tau
    for spec in args.records:
        setting, freq = spec.split(":")
        freq = float(freq)
        record = paper_like_record(setting, freq, seed=args.seed)
        with tempfile.TemporaryDirectory() as tmp:
            t0 = time.perf_counter()
            fit_record(record, Path(tmp) / "fit", steps=args.steps, seed=args.seed, processes=1, plots=False)
            seconds = time.perf_counter() - t0
            info = json.loads((Path(tmp) / "fit" / "fit.json").read_text())
        tau = {k: float(v) for k, v in info["tau"].items()}
        order = sorted(tau, key=tau.get, reverse=True)
        slowest, median = tau[order[0]], float(np.median(list(tau.values())))
        need = int(np.ceil(n_tau * slowest))
        print(f"{setting} {freq:g} Hz paper-like (seed {args.seed}), {args.steps} steps in {seconds:.0f} s, one process")
        print("  tau (steps): " + ", ".join(f"{k} {tau[k]:.0f}" for k in order))
        print(f"  slowest / median: {slowest / median:.2f}; the rule's {n_tau:g} tau: {need} steps, "
              f"{need * seconds / args.steps:.0f} s at this run's pace")
        path = record_row("tau_by_parameter", {
            "setting": setting, "freq_hz": freq, "seed": args.seed, "steps": args.steps,
            "seconds": round(seconds, 1), "slowest": order[0], "second": order[1], "third": order[2],
            "tau_slowest": round(slowest, 1), "tau_median": round(median, 1),
            "ratio_slowest_median": round(slowest / median, 2), "steps_for_rule": need,
            "seconds_for_rule": round(need * seconds / args.steps, 1),
            "tau": " ".join(f"{k}={tau[k]:.0f}" for k in order)})
    print(f"rows written to {path}")


if __name__ == "__main__":
    main()
