"""Do SBC v12's misses come from chains stopped too early? (results/coverage-sbc-v12;
issue 39, item 4.)

SBC v12's chains met the convergence rule after 500 to 5,000 steps (median 1,000), with
a largest autocorrelation time of about 5 steps; b / gain's 94 % interval missed the
truth on 23 of 150 replicates and the 50 % held on 52. This probe fits chosen
replicates again, the same device, records, start and seed as v12 (its manifest's
settings), with a fixed chain of ``--steps`` steps in place of the rule, and writes each
replicate's JSON as the calibration writes it (ranks and intervals) beside v12's:

    python studies/sbc_long_chains.py --replicates 11 29 35 2 5 8 [--steps 4000]
        [--rule] [--mirror-shares f_share c_share] [--tempering 8 --hottest-beta 0.01]
        [--work runs/sbc-long-chains] [--out results/sbc-long-chains]

``--rule`` keeps v12's convergence rule in place of the fixed length (to change only the
start's mirrored shares, ``optimize.MIRROR_SHARES``, or the tempering ladder).

A rerun skips the replicates already written. ``pairs.csv``: per replicate, v12's and
the long chain's b / gain rank, 94 % and 50 % holds, and iterations.
"""

from __future__ import annotations

import argparse
import dataclasses
import sys
from pathlib import Path

from bayes_inerter.cli.study_script import config_from_folder
from bayes_inerter.inference.sampling import optimize
from bayes_inerter.inference.sampling.tempering import Tempering
from bayes_inerter.study.manifest import script_configuration, write_manifest
from bayes_inerter.study.replicate_store import load_replicates, write_replicate
from bayes_inerter.study.study_calibration import IDENTIFIED, Config, study_replicate

from _table import write_table

ROOT = Path(__file__).resolve().parents[1]
V12 = ROOT / "results" / "coverage-sbc-v12"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--replicates", type=int, nargs="+", required=True)
    ap.add_argument("--steps", type=int, default=4000)
    ap.add_argument("--rule", action="store_true", help="v12's convergence rule, not --steps")
    ap.add_argument("--mirror-shares", nargs="+", default=None, help="optimize.MIRROR_SHARES for the start")
    ap.add_argument("--tempering", type=int, default=None, help="temperatures (default: v12's)")
    ap.add_argument("--hottest-beta", type=float, default=None, help="the hottest beta (with --tempering)")
    ap.add_argument("--work", default="runs/sbc-long-chains")
    ap.add_argument("--out", default="results/sbc-long-chains")
    args = ap.parse_args(argv)
    if args.steps < 20:
        print(f"error: --steps must be at least 20, got {args.steps}", file=sys.stderr)
        return 2
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    cs = config_from_folder(Config, V12).settings()
    if not args.rule:
        cs = dataclasses.replace(cs, steps=args.steps)
    if args.tempering is not None:
        cs = dataclasses.replace(cs, tempering=Tempering.of(args.tempering, args.hottest_beta))
    if args.mirror_shares:
        optimize.MIRROR_SHARES = tuple(args.mirror_shares)  # read at each start search
    write_manifest(out, script_configuration())
    v12 = load_replicates(V12)
    done = load_replicates(out)  # packed or loose: a rerun fits only the missing ones
    for i, k in enumerate(args.replicates, 1):
        if k not in done:
            done[k] = study_replicate(cs, k, Path(args.work) / f"{k:04d}")
            write_replicate(out, k, done[k])
        print(f"[{i}/{len(args.replicates)}] replicate {k} done", flush=True)
    rows = []
    for k in args.replicates:
        long_ = done[k]
        short = v12[k]
        a, b = short["identified"][IDENTIFIED], long_["identified"][IDENTIFIED]
        rows.append({"replicate": k, "frequency": cs.frequencies[k % len(cs.frequencies)],
                     "v12_iterations": short["iterations"], "v12_rank": a["rank"], "v12_held94": a["hdi"]["94"],
                     "v12_held50": a["hdi"]["50"], "long_iterations": long_["iterations"], "long_rank": b["rank"],
                     "long_held94": b["hdi"]["94"], "long_held50": b["hdi"]["50"],
                     "long_tau_max": round(long_["tau_max"], 1) if long_["tau_max"] else None})
    write_table(out / "pairs.csv", rows)
    for r in rows:
        print(f"replicate {r['replicate']} ({r['frequency']:g} Hz): rank {r['v12_rank']} -> {r['long_rank']}, "
              f"94 % {r['v12_held94']} -> {r['long_held94']}, 50 % {r['v12_held50']} -> {r['long_held50']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
