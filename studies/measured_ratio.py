"""Seed 23's calibration records by the ratio each record itself shows (records.reactance).

results/capped-by-force-ratio reads the chains that stop at the cap by the truth's
inertial-to-dissipative force ratio; a study cannot select replicates by the truth
without spoiling the ranks. The same ratio read from the record
(``records.reactance.drive_impedance``: w M / C at the drive's fundamental) is a function
of the record alone, so the replicates above a level of it keep uniform ranks. For each
finished replicate of results/coverage-sbc-lf-exact-s23-untempered this regenerates its
record (``study_calibration.replicate_device``, the same seed sequence), reads its ratio,
and writes it beside the chain's outcome and intervals (measured.csv); then, for each level,
the replicates at or above it: how many converged, and how many of their 94 % and 50 %
intervals held (by_level.csv).

    python studies/measured_ratio.py --out results/capped-by-force-ratio
"""
from __future__ import annotations

import argparse
import csv
import json
import math
from pathlib import Path

from deviation_scale_probe import SEED23
from bayes_inerter.records.reactance import drive_impedance
from bayes_inerter.study.study_calibration import Config, replicate_device

ROOT = Path(__file__).resolve().parents[1]
FOLDER = ROOT / "results" / "coverage-sbc-lf-exact-s23-untempered"
#: The levels of the measured ratio read (fixed before the table was).
LEVELS = (-math.inf, 0.5, 1.0, 2.0)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--folder", type=Path, default=FOLDER, help="seed 23's untempered calibration folder")
    ap.add_argument("--out", type=Path, default=None, help="write measured.csv and by_level.csv here")
    a = ap.parse_args(argv)
    cs = Config(**SEED23).settings()
    rows = []
    with open(a.folder / "replicates.jsonl") as f:
        for line in f:
            r = json.loads(line)
            record = replicate_device(cs, r["replicate"]).records[0]
            held = {lvl: sum(r["hdi"][lvl].values()) for lvl in ("94", "50")}
            rows.append({"replicate": r["replicate"], "measured_ratio": round(drive_impedance(record).ratio, 4),
                         "converged": r["converged"], "steps": r["iterations"], "tau_max": round(r["tau_max"], 1),
                         "intervals": len(r["hdi"]["94"]), "held_94": held["94"], "held_50": held["50"]})
    rows.sort(key=lambda r: r["measured_ratio"])
    table = []
    for level in LEVELS:
        sel = [r for r in rows if r["measured_ratio"] >= level]
        n = sum(r["intervals"] for r in sel)
        table.append({"ratio_at_least": level, "replicates": len(sel), "converged": sum(r["converged"] for r in sel),
                      "intervals": n, "held_94": sum(r["held_94"] for r in sel),
                      "expected_94": round(0.94 * n, 1), "se_94": round(math.sqrt(n * 0.94 * 0.06), 1),
                      "held_50": sum(r["held_50"] for r in sel), "expected_50": round(0.5 * n, 1),
                      "se_50": round(math.sqrt(n * 0.25), 1)})
    for t in table:
        print(f"measured ratio >= {t['ratio_at_least']}: {t['converged']} of {t['replicates']} converged; "
              f"94 % held {t['held_94']} of {t['intervals']} (expected {t['expected_94']}, se {t['se_94']}), "
              f"50 % {t['held_50']} (expected {t['expected_50']}, se {t['se_50']})")
    if a.out is not None:
        for name, data in (("measured.csv", rows), ("by_level.csv", table)):
            with open(a.out / name, "w", newline="") as f:
                w = csv.DictWriter(f, fieldnames=list(data[0]))
                w.writeheader()
                w.writerows(data)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
