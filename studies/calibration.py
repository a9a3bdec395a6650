"""Simulation-based calibration (Talts et al.): prior draws, records made from them,
posteriors fitted as a user's are, the rank of each truth. Writes
results/calibration/<truth>-<residual>/ (REPORT.md, coverage.csv, ranks.csv, ranks.png,
one JSON per replicate); running again reuses the replicates already there. Then
rewrites results/calibration/REPORT.md and coverage.png: every case there side by side.

    python studies/calibration.py [--replicates 100] [--truth model|generator]
        [--residual ar1|iid] [--friction coulomb|stribeck] [--backlash M] [--noise-corner HZ]
        [--steps 800]
        [--processes 2]
"""

import argparse
import os
import sys
from dataclasses import replace
from pathlib import Path

from _table import run_with_bar
from bayes_inerter.study.calibration import CalibrationSettings, compare_calibrations, run_calibration

RESULTS = Path(__file__).resolve().parents[1] / "results" / "calibration"

if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--replicates", type=int, default=100)
    ap.add_argument("--truth", choices=("model", "generator"), default="model")
    ap.add_argument("--residual", choices=("ar1", "iid"), default="ar1")
    ap.add_argument("--friction", choices=("coulomb", "stribeck", "smooth"), default="coulomb")
    ap.add_argument("--backlash", type=float, default=0.0)
    ap.add_argument("--noise-corner", type=float, default=None,
                    help="colour the generator's sensor noise with a low-pass at this frequency, Hz")
    ap.add_argument("--steps", type=int, default=CalibrationSettings.steps)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--processes", type=int, default=min(2, os.cpu_count() or 1))
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    try:
        base = CalibrationSettings()
        cs = replace(base, truth=args.truth, residual=args.residual, steps=args.steps, seed=args.seed,
                     generator=replace(base.generator, friction=args.friction, backlash=args.backlash,
                                       noise_corner=args.noise_corner))
        richer = "" if args.friction == "coulomb" and not args.backlash else f"-{args.friction}-bl{args.backlash:g}"
        richer += f"-colour{args.noise_corner:g}Hz" if args.noise_corner else ""
        out = Path(args.out) if args.out else RESULTS / f"{args.truth}{richer}-{args.residual}"
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(2)
    res = run_with_bar(lambda progress: run_calibration(cs, out, args.replicates, processes=args.processes, progress=progress),
                       args.replicates, "calibration")
    print(f"wrote {res['report']} ({res['replicates']} replicates, {len(res['failed'])} failed)")
    print(f"wrote {compare_calibrations(out.parent)} (every case in {out.parent}, side by side)")
    sys.exit(1 if res["failed"] else 0)
