"""The paper-like device's phi beside the paper's Table 2.

Run from the project root:

    python studies/paper_like_phi.py --out results/paper-like [--seed 0] [--processes 2]

Generates the 27 paper-like records of one laboratory (``records.paper_like``, seed
``--seed``), fits each with the paper's reduced model by least squares
(``inference.identify``: eq. 4 on the unfiltered record) and writes phi (eq. 5, as the
paper measured it) beside Table 2's: phi.csv (one row per record) and a summary line
(mean absolute difference in points; the orderings the paper shows: A0 at 0.5 Hz lowest,
phi rising with frequency). The effect sizes are PaperLike's defaults; the ones drawn
for the laboratory are in phi.csv.
"""

import argparse
import csv
import sys
import time
from pathlib import Path

import numpy as np

from bayes_inerter.device import FREQUENCIES_HZ, SETTINGS
from bayes_inerter.executor import make_executor
from bayes_inerter.inference.identify import identify
from bayes_inerter.inference.posterior.model import PosteriorModel
from bayes_inerter.records.paper_like import PaperLike, paper_like_record
from bayes_inerter.study.manifest import script_configuration, write_manifest


def one(job) -> dict:
    setting, freq, seed, device = job
    rec = paper_like_record(setting, freq, seed=seed, device=device)
    got = identify(PosteriorModel(rec), starts=2, seed=seed)
    gen = rec.metadata["generator"]
    paper = SETTINGS[setting].fit_paper[freq]
    return {"setting": setting, "freq_hz": freq, "phi_paper_pct": round(100 * paper, 1),
            "phi_pct": round(100 * got.phi, 1), "difference_pts": round(100 * (got.phi - paper), 1),
            "phi_filtered_pct": round(100 * got.phi_filtered, 1), "b_true": rec.metadata["true_parameters"]["b"],
            "b_least_squares": round(got.b, 1), "stribeck_ratio": round(gen["stribeck_ratio"], 4),
            "stribeck_velocity": gen["stribeck_velocity"], "backlash_um": round(1e6 * gen["backlash"], 2),
            "force_gain": round(gen["force_gain"], 5), "accel_gain": round(gen["accel_gain"], 5)}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="runs/paper-like")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--processes", type=int, default=2)
    ap.add_argument("--settings", nargs="+", default=list(SETTINGS))
    for name in ("ratio", "velocity", "backlash"):
        ap.add_argument(f"--{name}", type=float, nargs=2, metavar=("LOW", "HIGH"),
                        help=f"PaperLike's {name} range (default: its own)")
    args = ap.parse_args()
    sizes = {n: tuple(getattr(args, n)) for n in ("ratio", "velocity", "backlash") if getattr(args, n)}
    device = PaperLike(**sizes)
    jobs = [(s, f, args.seed, device) for s in args.settings for f in FREQUENCIES_HZ]
    t0 = time.perf_counter()
    rows = [None] * len(jobs)
    with make_executor(args.processes) as ex:
        for n, got in enumerate(ex.as_completed(one, jobs), 1):
            if not got.ok:
                sys.exit(f"error: {jobs[got.index][:2]}: {got.error}")
            rows[got.index] = got.value
            print(f"{n}/{len(jobs)} records ({time.perf_counter() - t0:.0f} s)", file=sys.stderr, flush=True)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    write_manifest(out, script_configuration())
    with open(out / "phi.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    diff = np.array([r["difference_pts"] for r in rows])
    by = {(r["setting"], r["freq_hz"]): r["phi_pct"] for r in rows}
    lowest = min(by, key=by.get)
    rising = sum(by[(s, 0.5)] < by[(s, 1.0)] < by[(s, 1.5)] for s in args.settings)
    print(f"mean |phi - Table 2| {np.mean(np.abs(diff)):.1f} points (mean signed {np.mean(diff):+.1f}); "
          f"lowest {lowest[0]} at {lowest[1]:g} Hz; phi rising with frequency in {rising} of "
          f"{len(args.settings)} settings")
    for f in FREQUENCIES_HZ:
        print(f"{f:g} Hz: " + " ".join(f"{s} {by[(s, f)]:.1f} ({SETTINGS[s].fit_paper[f] * 100:.1f})"
                                        for s in args.settings))


if __name__ == "__main__":
    main()
