"""Simulation-based calibration in the configuration the study reports
(``bayes_inerter.study.study_calibration``): devices drawn from a wide physical prior,
10 s generator records at 0.5 and 1.5 Hz fitted with the joint model and the package's
start, the 94 % and 50 % intervals checked directly, failed replicates counted. Writes
results/study-calibration/ (REPORT.md, SECTION.md, coverage.csv, ranks.csv,
coverage.png, ranks.png, one JSON per replicate); running again reuses the replicates
already there. About a minute per replicate and process on a 2-core machine.

    python studies/study_calibration.py [--replicates 200] [--steps 600] [--processes 2]
        [--seed 0] [--out FOLDER] [--single] [--residual motion] [--converge] [--freqs 0.5 1.5]
        [--input-noise 0]

``--raise-cap`` raises a folder's cap to ``--max-steps`` before running: the replicates
whose chains stopped unconverged at its old cap move to ``capped-<old>/`` and are fitted
again (``study_calibration.raise_cap``; the others' chains are the same under any cap).

``--summarise`` writes coverage_so_far.csv from the replicates finished in ``--out``
(counts over every chain and over the converged ones), for a run still in chunks, and
rank_correlations.csv: the parameters whose truths' ranks move together; a single-record
calibration's coverage_by_frequency.csv: the same counts at each drive frequency.
``--single`` fits each replicate's one record alone (its frequency ``freqs[k % n]``),
``--residual`` chooses the likelihood, ``--input-noise N`` takes N draws of the
drivetrain's input noise (``LikelihoodSettings.input_noise``; 0 turns it off), ``--converge``
runs every chain to the convergence rule (at most ``--max-steps``) instead of
``--steps``. A folder keeps one
configuration (settings.json): its replicates are reused, so a run stopped by a
session's end continues where it stopped.
    python studies/study_calibration.py --inspect K [--steps N]

``--inspect K`` runs replicate K again (joint, or ``--single``) with its fit kept
(runs/study-calibration/<joint|single>_seed<S>_K_<steps>)
and prints the joint log posterior at the truth and at the posterior medians, and each
parameter's truth beside its interval: a chain far below the truth's log posterior is
in a wrong basin, one above it has a posterior that excludes the truth.
"""

import argparse
import json
import os
import sys
from dataclasses import replace
from pathlib import Path

from _table import run_with_bar
from bayes_inerter.inference.posterior.likelihood import LikelihoodSettings
from bayes_inerter.study.study_calibration import (StudyCalibration, finished_replicates, inspect_replicate,
                                                  rank_correlations, raise_cap, run_study_calibration,
                                                  write_coverage_so_far)

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "results" / "study-calibration"

if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--replicates", type=int, default=200)
    ap.add_argument("--steps", type=int, default=StudyCalibration.steps)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--processes", type=int, default=min(2, os.cpu_count() or 1))
    ap.add_argument("--out", default=str(RESULTS))
    ap.add_argument("--inspect", type=int, default=None, metavar="K", help="run replicate K again, its fit kept")
    ap.add_argument("--single", action="store_true", help="one record per replicate, fitted alone")
    ap.add_argument("--residual", default=None, help="the likelihood (LikelihoodSettings.residual)")
    ap.add_argument("--input-noise", type=int, default=None, metavar="N",
                    help="LikelihoodSettings.input_noise: N draws of the drivetrain's input noise "
                         "(0: off; default: the library's)")
    ap.add_argument("--converge", action="store_true", help="each chain to the convergence rule")
    ap.add_argument("--max-steps", type=int, default=StudyCalibration.max_steps)
    ap.add_argument("--freqs", nargs="+", type=float, default=None)
    ap.add_argument("--work", default=None, metavar="FOLDER",
                    help="where each replicate's fit runs until done, continued by the next run "
                         "(default: runs/study-calibration/<name of --out>)")
    ap.add_argument("--raise-cap", action="store_true",
                    help="raise --out's cap to --max-steps first: its capped replicates are fitted again")
    ap.add_argument("--summarise", action="store_true",
                    help="write --out's coverage_so_far.csv from the replicates finished there, run nothing")
    args = ap.parse_args()
    if args.summarise:
        rows = write_coverage_so_far(args.out)
        if not rows:
            print(f"error: {args.out} holds no finished replicate; run the study into it first", file=sys.stderr)
            sys.exit(2)
        for r in rows:
            print(f"{r['chains']:>9} {r['parameter']:>14}: of {r['intervals']:4d} the 94 % held {r['held_94']:4d} "
                  f"(expected {r['expected_94']}, se {r['se_94']}), the 50 % {r['held_50']:4d} "
                  f"(expected {r['expected_50']}, se {r['se_50']})")
        for pair in rank_correlations(finished_replicates(args.out)):
            print(f"ranks of {pair['parameter']} and {pair['with']} move together (r {pair['r']:+.2f}): "
                  "their counts are not independent tests")
        print(f"wrote {Path(args.out) / 'coverage_so_far.csv'} and rank_correlations.csv"
              + (" and coverage_by_frequency.csv" if (Path(args.out) / "coverage_by_frequency.csv").exists() else ""))
        sys.exit(0)
    try:
        if args.replicates < 1:
            raise ValueError(f"--replicates must be at least 1, got {args.replicates}")
        extra = {}
        if args.residual or args.input_noise is not None:
            extra["likelihood"] = LikelihoodSettings(
                **({"residual": args.residual} if args.residual else {}),
                **({"input_noise": args.input_noise} if args.input_noise is not None else {}))
        if args.freqs:
            extra["frequencies"] = tuple(args.freqs)
        cs = replace(StudyCalibration(), steps=None if args.converge else args.steps, seed=args.seed,
                     single=args.single, max_steps=args.max_steps, **extra)
    except ValueError as exc:
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(2)
    if args.raise_cap:
        try:
            moved = raise_cap(args.out, args.max_steps)
        except ValueError as exc:
            print(f"error: {exc}", file=sys.stderr)
            sys.exit(2)
        print(f"cap raised to {args.max_steps} steps; replicates to fit again: {moved or 'none'}", flush=True)
    if args.inspect is not None:
        kind = "single" if cs.single else "joint"
        got = inspect_replicate(cs, args.inspect, ROOT / "runs" / "study-calibration"
                                / f"{kind}_seed{cs.seed}_{args.inspect}_{cs.steps}")
        print(json.dumps(got, indent=1))
        sys.exit(0)
    # each replicate's fit in progress (its checkpoint, tens of MB) outside results/, continued by the next run
    work = Path(args.work) if args.work else ROOT / "runs" / "study-calibration" / Path(args.out).resolve().name
    res = run_with_bar(lambda progress: run_study_calibration(cs, args.out, args.replicates, processes=args.processes,
                                                              progress=progress, work=work),
                       args.replicates, "calibration", mininterval=10)
    print(f"wrote {res['report']} ({res['replicates']} replicates, {len(res['failed'])} failed)")
