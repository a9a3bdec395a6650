"""Paper-like coverage of b by the force ratio each record itself shows (records.reactance).

On the model's own physics the chains that stop at their cap are the records whose
friction outweighs their inertial force, and `fit` warns below a measured ratio of 1
(results/capped-by-force-ratio). Does the same ratio tell where b's interval misses on
records of a richer device, so that it could serve as a guard of identification (issue
39, item 5)? For each replicate of the paper-like coverage folders named, this
regenerates its record (``records.paper_like.paper_like_record``, the replicate's
laboratory seed and device family), reads its ratio, and writes it beside the
replicate's outcome (rows.csv); then, by folder, drive frequency and band of the
ratio, how many 94 % and 50 % intervals held (bins.csv). It fits nothing.

    python studies/paper_coverage_by_ratio.py [FOLDER ...] [--out results/capped-by-force-ratio/paper-coverage]
"""
from __future__ import annotations

import argparse
import math
from pathlib import Path

from _table import write_table
from bayes_inerter.records.paper_like import paper_like_record
from bayes_inerter.records.reactance import drive_impedance
from bayes_inerter.study.paper_like_coverage import FAMILIES
from bayes_inerter.study.replicate_store import finished

ROOT = Path(__file__).resolve().parents[1]
#: The folders read by default: the paper-like coverage of the tempered default and its
#: four held-out families.
FOLDERS = ("coverage-paper-like-v6", "coverage-breakaway-v3", "coverage-backlash-v3", "coverage-corner20-v3",
           "coverage-delays-v3")
#: The bands of the measured ratio (fixed before the table was read).
BANDS = ((-math.inf, 0.5), (0.5, 1.0), (1.0, 2.0), (2.0, math.inf))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folders", nargs="*", default=FOLDERS, help="paper-like coverage folders under results/")
    ap.add_argument("--out", type=Path, default=None, help="write rows.csv and bins.csv here")
    a = ap.parse_args(argv)
    rows = []
    for name in a.folders:
        folder = Path(name) if Path(name).is_dir() else ROOT / "results" / name
        for r in (r for r in finished(folder) if "error" not in r):  # packed and loose alike
            family = r.get("family", "default")
            record = paper_like_record(r["setting"], r["freq_hz"], seed=r["seed"], device=FAMILIES[family],
                                       duration=r.get("duration_s"))
            rows.append({"folder": folder.name, "replicate": r["replicate"], "setting": r["setting"],
                         "freq_hz": r["freq_hz"], "measured_ratio": round(drive_impedance(record).ratio, 4),
                         "converged": r["converged"], "identified": r["identified"], "covered94": r["covered94"],
                         "covered50": r["covered50"], "error_pct": round(100.0 * (r["b_median"] / r["b_true"] - 1), 3)})
    bins = []
    for folder in dict.fromkeys(r["folder"] for r in rows):
        for freq in (0.5, 1.0, 1.5, None):
            for lo, hi in BANDS:
                sel = [r for r in rows if r["folder"] == folder and (freq is None or r["freq_hz"] == freq)
                       and lo <= r["measured_ratio"] < hi and r["identified"]]
                if not sel:
                    continue
                errors = sorted(abs(r["error_pct"]) for r in sel)
                bins.append({"folder": folder, "freq_hz": "all" if freq is None else freq, "ratio_from": lo,
                             "ratio_below": hi, "identified": len(sel), "converged": sum(r["converged"] for r in sel),
                             "held94": sum(r["covered94"] for r in sel), "held50": sum(r["covered50"] for r in sel),
                             "median_abs_error_pct": round(errors[len(errors) // 2], 2)})
    for b in bins:
        if b["freq_hz"] == "all":
            print(f"{b['folder']}: measured ratio {b['ratio_from']:g} to {b['ratio_below']:g}: 94 % held "
                  f"{b['held94']} of {b['identified']}, 50 % {b['held50']} (median |error| {b['median_abs_error_pct']} %)")
    if a.out is not None:
        write_table(a.out / "rows.csv", rows)
        write_table(a.out / "bins.csv", bins)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
