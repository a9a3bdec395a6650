"""Recovery study: fit generated records at known parameters and check the intervals.

For each record (several settings and frequencies, paper parameters, default
generator): b's 94 % interval against the truth, and every sampled quantity's posterior
contraction (1 - var post / var prior), which says what these experiments identify.
Writes results/recovery/recovery.csv, contraction.csv and one fit folder per record.
Runs each chain until converged (the package's default criteria) unless --steps is given.

    python studies/recovery.py [--steps N | --max-steps N] [--walkers N] [--processes 2]

Running it again continues each record's checkpoint.
"""

import argparse
import csv
from pathlib import Path

from bayes_inerter import paper_parameters
from bayes_inerter.inference import Convergence, fit_record
from bayes_inerter.records import generate_record
from bayes_inerter.study.manifest import script_configuration, write_manifest

OUT = Path(__file__).resolve().parents[1] / "results" / "recovery"
CASES = (("A1", 1.0), ("A2", 1.0), ("A0", 0.5), ("B2", 1.5))


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--steps", type=int, default=None, help="steps per chain (default: until converged)")
    ap.add_argument("--max-steps", type=int, default=None,
                    help="stop an open-ended chain here if not converged before (default: the package's 20,000)")
    ap.add_argument("--walkers", type=int, default=None, help="walkers (default: the package's)")
    ap.add_argument("--processes", type=int, default=2)
    args = ap.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    write_manifest(OUT, script_configuration())
    rows, shrink_rows = [], []
    for seed, (name, freq) in enumerate(CASES):
        truth = paper_parameters(name)
        rec = generate_record(truth, freq, rng=100 + seed, setting_name=name)
        conv = Convergence(max_steps=args.max_steps) if args.max_steps else None
        res = fit_record(rec, OUT / f"{name}_{freq:g}Hz", steps=args.steps, walkers=args.walkers,
                         seed=seed, processes=args.processes, convergence=conv)
        print(f"{name} {freq:g} Hz: {res.reason}, {res.iterations} steps, {res.timings['total']:.0f} s", flush=True)
        b = res.row("b")
        rows.append({
            "setting": name, "freq_hz": freq, "b_true": truth.b, "b_mean": b["mean"],
            "b_hdi_3%": b["hdi_3%"], "b_hdi_97%": b["hdi_97%"],
            "covered": b["hdi_3%"] <= truth.b <= b["hdi_97%"], "r_hat_b": b["r_hat"],
            "steps": res.iterations, "converged": res.converged, "tau_max": float(max(res.tau)),
            "minutes": res.timings["total"] / 60,
        })
        shrink_rows.append({"setting": name, "freq_hz": freq, **{k: round(v, 3) for k, v in res.contraction.items()}})
    for fname, table in (("recovery.csv", rows), ("contraction.csv", shrink_rows)):
        with open(OUT / fname, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(table[0]))
            w.writeheader()
            w.writerows(table)


if __name__ == "__main__":
    main()
