"""Does mirroring the viscous split as well as the Coulomb one find higher starts?

Issue 39, item 1: on the generator's noise-free B2 record at 1.5 Hz the start search
ended with the viscous friction's split c_share at 0.97, where Table I puts nearly all of
it on the rotation (c_share 2e-5), about 93 nats below the optimum polished from the
truth. The search polishes the mirror of its start in the Coulomb split f_share
(``optimize.MIRROR_SHARES``) and keeps it where higher; this script runs
``optimize.find_start`` on each record twice from the same seed, mirroring ``f_share``
alone (the default) and ``f_share`` and ``c_share``, and writes each start's log
posterior (the model without its reference point, as the search sees it), b's error
against the truth, c_share and the seconds of each search.

The records (``--set``), as results/start-continuation's: ``sbc`` (the single-record
calibration's devices of design seed ``--sbc-seed``), ``paper-like`` (design
laboratories 11 to 13, ``start_continuation.PAPER_LIKE``) and ``noise-free`` (records
``--noise-free`` of the paper's grid, every noise off, the plate mode damped
``--zeta-B``, inside the fit's prior, as results/noise-free-chains-v3's).

    python studies/start_mirrors.py [--set noise-free sbc paper-like] [--noise-free 1 4 7 8]
        [--zeta-B 0.02] [--out results/start-continuation/mirrors.csv]
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

from _table import append_row, read_rows
from start_continuation import records
from bayes_inerter.inference.sampling import optimize

ROOT = Path(__file__).resolve().parents[1]
VARIANTS = {"f_share": ("f_share",), "f_share+c_share": ("f_share", "c_share")}
FIELDS = ("set", "record", "freq_hz", "seed", "variant", "log_post", "b_error_pct", "c_share", "seconds")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--set", nargs="+", default=["noise-free", "sbc", "paper-like"],
                    choices=["sbc", "paper-like", "noise-free"])
    ap.add_argument("--sbc-seed", type=int, default=4)
    ap.add_argument("--sbc-replicates", type=int, default=12)
    ap.add_argument("--noise-free", type=int, nargs="+", default=[1, 4, 7, 8], metavar="K")
    ap.add_argument("--zeta-B", type=float, default=0.02, dest="zeta_b")
    ap.add_argument("--out", type=Path, default=ROOT / "results" / "start-continuation" / "mirrors.csv")
    args = ap.parse_args(argv)
    if not 0.0 < args.zeta_b < 1.0:
        print(f"error: --zeta-B is a damping ratio in (0, 1), got {args.zeta_b}", file=sys.stderr)
        return 2
    done = {(r["set"], r["record"], r["freq_hz"], r["seed"], r["variant"]) for r in read_rows(args.out)}
    for which in args.set:
        for label, freq, seed, model, b_true in records(which, args, zeta_b=args.zeta_b, seed_by_record=True):
            for variant, shares in VARIANTS.items():
                key = (which, label, str(float(freq)), str(seed), variant)
                if key in done:
                    continue
                t0 = time.perf_counter()
                theta, lp = optimize.find_start(model, np.random.default_rng(seed), mirrors=shares)
                values = dict(zip(model.names, model.to_values(theta)))
                append_row(args.out, {"set": which, "record": label, "freq_hz": float(freq), "seed": seed,
                                      "variant": variant, "log_post": round(float(lp), 2),
                                      "b_error_pct": round(100.0 * (values["b"] / b_true - 1.0), 3),
                                      "c_share": float(f"{values.get('c_share', math.nan):.4g}"),
                                      "seconds": round(time.perf_counter() - t0, 1)}, FIELDS)  # printed too
    return 0


if __name__ == "__main__":
    sys.exit(main())
