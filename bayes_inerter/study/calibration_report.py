"""The reports of simulation-based calibration (``study.calibration``): one run's, and
the cases side by side."""

from __future__ import annotations

import math
from pathlib import Path

from .markdown import table as markdown_table  # a report's argument is called table

__all__ = ["calibration_report", "calibration_comparison"]


def calibration_report(out: Path, cs, table: list[dict], n_ok: int, failed: list[dict], versions: dict) -> Path:
    """``out``/REPORT.md of a simulation-based calibration run, written from its table."""
    lines = ["# Simulation-based calibration", "",
             f"{n_ok} replicates (truth: `{cs.truth}`; residual model `{cs.residual}`; setting {cs.setting} at "
             f"{cs.freq:g} Hz; {cs.steps} steps per chain; ranks among {cs.draws} posterior draws; seed {cs.seed})."
             + (f" {len(failed)} replicates failed: " + "; ".join(f"{r['replicate']}: {r['error']}" for r in failed)
                if failed else ""), ""]
    if table:
        def off(r, q):
            return abs(r[f"coverage_{q}"] - q / 100) > 2 * r[f"se_{q}"]

        bad = [r["parameter"] for r in table if off(r, 50) or off(r, 90)]
        nonuniform = [r["parameter"] for r in table if r["rank_chi2_p"] < 0.01]
        lines += ["A calibrated posterior holds the truth in its central 50 % and 90 % intervals 50 % and 90 % of "
                  "the time (binomial se beside each), and its ranks are uniform. "
                  + (f"Coverage more than 2 se from nominal: {', '.join(bad)}. " if bad else
                     "Every parameter's coverage lies within 2 se of nominal. ")
                  + (f"Ranks not uniform (chi-square p < 0.01): {', '.join(nonuniform)}." if nonuniform else
                     "No rank histogram departs from uniform at p < 0.01."), "",
                  markdown_table(table, ["parameter", "replicates", "coverage_50", "se_50", "coverage_90", "se_90",
                                        "rank_chi2_p"], {c: "{:.3f}" for c in ("coverage_50", "se_50", "coverage_90",
                                                                                "se_90", "rank_chi2_p")}), "",
                  "![ranks](ranks.png)", ""]
    lines += ["Versions: " + ", ".join(f"{k} {v}" for k, v in versions.items()) + ".", "",
              f"Settings: `{cs!r}`", ""]
    path = Path(out) / "REPORT.md"
    path.write_text("\n".join(lines))
    return path


def calibration_comparison(root: Path, cases: dict) -> Path:
    """``root``/REPORT.md comparing calibration cases: ``cases`` maps each case's folder
    name to its coverage rows (see ``calibration.compare_calibrations``)."""
    names = []
    for rows in cases.values():
        names += [r["parameter"] for r in rows if r["parameter"] not in names]
    lines = ["# Simulation-based calibration: the cases side by side", "",
             "Each cell: coverage of the central 90 % interval / of the 50 % interval over the case's "
             "replicates (the binomial se at the nominal level is in the header). Cases: the folder names "
             "say the truth (`model`: data from the likelihood's own model; `generator`: the realistic "
             "record generator, optionally with coloured sensor noise, Stribeck friction or backlash) "
             "and the residual model the likelihood used (`ar1` or `iid`). With the generator as truth "
             "only the physical parameters have a true value. Details and rank histograms: each "
             "case's own REPORT.md.", ""]
    header = ["parameter"]
    for name, rows in cases.items():
        n = int(rows[0]["replicates"])
        header.append(f"{name} (n = {n}, se {math.sqrt(0.09 / n):.3f} / {math.sqrt(0.25 / n):.3f})")
    lines += ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    for p in names:
        cells = [p]
        for rows in cases.values():
            by = {r["parameter"]: r for r in rows}
            cells.append(f"{by[p]['coverage_90']:.2f} / {by[p]['coverage_50']:.2f}" if p in by else "")
        lines.append("| " + " | ".join(cells) + " |")
    lines += ["", "![coverage](coverage.png)", ""]
    path = Path(root) / "REPORT.md"
    path.write_text("\n".join(lines))
    return path
