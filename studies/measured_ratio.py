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

``--paper-grid`` also reads the ratio of each of the 27 paper-like records of laboratory
0 (``records.paper_like.paper_like_grid``, the full study's headline records), and so how
many of them ``fit`` warns "friction-dominated" (paper_grid.csv).
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

from _table import write_table
from deviation_scale_probe import SEED23
from bayes_inerter.records.reactance import drive_impedance
from bayes_inerter.study.replicate_store import finished
from bayes_inerter.study.study_calibration import Config, replicate_device

ROOT = Path(__file__).resolve().parents[1]
FOLDER = ROOT / "results" / "coverage-sbc-lf-exact-s23-untempered"
#: The levels of the measured ratio read (fixed before the table was).
LEVELS = (-math.inf, 0.5, 1.0, 2.0)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--folder", type=Path, default=FOLDER, help="seed 23's untempered calibration folder")
    ap.add_argument("--out", type=Path, default=None, help="write measured.csv and by_level.csv here")
    ap.add_argument("--paper-grid", action="store_true", help="also the paper-like laboratory 0's 27 records")
    a = ap.parse_args(argv)
    cs = Config(**SEED23).settings()
    rows = []
    for r in finished(a.folder):
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
    grid = []
    if a.paper_grid:
        from bayes_inerter.inference.summaries.end_state import FRICTION_RATIO
        from bayes_inerter.records.paper_like import paper_like_grid

        for name, freq, record in paper_like_grid(seed=0):
            d = drive_impedance(record)
            grid.append({"setting": name, "freq_hz": freq, "mass": round(d.mass, 1), "damping": round(d.damping, 1),
                         "measured_ratio": round(d.ratio, 3), "warned": d.ratio < FRICTION_RATIO})
        for freq in sorted({g["freq_hz"] for g in grid}):
            sel = [g for g in grid if g["freq_hz"] == freq]
            print(f"paper-like laboratory 0 at {freq:g} Hz: {sum(g['warned'] for g in sel)} of {len(sel)} records "
                  f"below {FRICTION_RATIO:g} (" + ", ".join(f"{g['setting']} {g['measured_ratio']}" for g in sel) + ")")
    if a.out is not None:
        for name, data in (("measured.csv", rows), ("by_level.csv", table), ("paper_grid.csv", grid)):
            if data:
                write_table(a.out / name, data)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
