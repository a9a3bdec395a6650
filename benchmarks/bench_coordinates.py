"""Benchmark: the sampler coordinates side by side (issue 40, item 1).

For each record (paper-like, ``records.paper_like``, laboratory ``--seed``): one fit of
a fixed ``--steps`` on one process in each of ``--coordinates`` (default: the impedance
coordinates, today's default, and the series ones, which walk k_n and k_B as their
series stiffness and ratio), ``fit_record`` as ``bayes-inerter fit --coordinates KIND``
runs it, the same seed, start search and moves. The coordinates change how fast a
chain mixes, not the posterior, so what to read is each parameter's autocorrelation
time (from fit.json) and the steps the convergence rule would need at the slowest
(``Convergence.n_tau`` of them), as ratios within one record; b's posterior median and
94 % interval are printed beside as the check that both chains sample one posterior.

One row per record and coordinates goes to results/performance/coordinates.csv.

    python benchmarks/bench_coordinates.py [--records A3:1 A3:0.5 B1:1.5] [--steps 4000] [--seed 11]
        [--coordinates impedance series]

The machine is shared and noisy: taus do not depend on it; the seconds are not a
benchmark of speed.
"""

import argparse
import json
import tempfile
import time
from pathlib import Path

import numpy as np

from _timing import record_row

from bayes_inerter.inference import Convergence, fit_record
from bayes_inerter.inference.sampling.coordinates import COORDINATES
from bayes_inerter.records.paper_like import paper_like_record


def one_fit(record, kind: str, steps: int, seed: int) -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        t0 = time.perf_counter()
        res = fit_record(record, Path(tmp) / "fit", steps=steps, seed=seed, processes=1, plots=False,
                         coordinates=kind)
        seconds = time.perf_counter() - t0
        info = json.loads((Path(tmp) / "fit" / "fit.json").read_text())
    b = res.row("b")
    return {"tau": {k: float(v) for k, v in info["tau"].items()}, "seconds": seconds,
            "coordinates": info["coordinates"], "b_median": float(np.median(res.idata.posterior["b"].values)),
            "b_3": b["hdi_3%"], "b_97": b["hdi_97%"]}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--records", nargs="+", default=["A3:1", "A3:0.5", "B1:1.5"], help="SETTING:FREQ_HZ ...")
    ap.add_argument("--steps", type=int, default=4000)
    ap.add_argument("--seed", type=int, default=11, help="the paper-like laboratory's seed and the fits'")
    ap.add_argument("--coordinates", nargs="+", choices=COORDINATES, default=["impedance", "series"])
    args = ap.parse_args()
    n_tau = Convergence().n_tau
    path = None
    for spec in args.records:
        setting, freq = spec.split(":")
        freq = float(freq)
        record = paper_like_record(setting, freq, seed=args.seed)
        b_true = record.metadata["true_parameters"]["b"]
        got = {kind: one_fit(record, kind, args.steps, args.seed) for kind in args.coordinates}
        base = got[args.coordinates[0]]
        names = sorted(base["tau"], key=base["tau"].get, reverse=True)
        print(f"{setting} {freq:g} Hz paper-like (seed {args.seed}), {args.steps} steps each, one process; "
              f"true b {b_true:.1f} kg")
        print("  tau (steps)  " + "".join(f"{k:>12}" for k in args.coordinates))
        for n in names:
            print(f"  {n:<12} " + "".join(f"{got[k]['tau'][n]:12.0f}" for k in args.coordinates))
        for kind in args.coordinates:
            g = got[kind]
            slowest = max(g["tau"].values())
            need = int(np.ceil(n_tau * slowest))
            ratio = slowest / max(base["tau"].values())
            print(f"  {kind}: slowest tau {slowest:.0f} ({ratio:.2f} of {args.coordinates[0]}'s), the rule's "
                  f"{need} steps; b {g['b_median']:.1f} kg, 94 % {g['b_3']:.1f} to {g['b_97']:.1f}; "
                  f"{g['seconds']:.0f} s")
            order = sorted(g["tau"], key=g["tau"].get, reverse=True)
            path = record_row("coordinates", {
                "setting": setting, "freq_hz": freq, "seed": args.seed, "steps": args.steps, "coordinates": kind,
                "seconds": round(g["seconds"], 1), "tau_slowest": round(slowest, 1), "slowest": order[0],
                "ratio_to_first": round(ratio, 2), "steps_for_rule": need,
                "tau_k_n": round(g["tau"].get("k_n", float("nan")), 1),
                "tau_k_B": round(g["tau"].get("k_B", float("nan")), 1),
                "b_median": round(g["b_median"], 1), "b_3%": round(g["b_3"], 1), "b_97%": round(g["b_97"], 1),
                "b_true": round(b_true, 1),
                "tau": " ".join(f"{k}={g['tau'][k]:.0f}" for k in order)})
    if path is not None:
        print(f"rows written to {path}")


if __name__ == "__main__":
    main()
