"""The reports of simulation-based calibration (``study.calibration``): one run's, and
the cases side by side."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .markdown import table as markdown_table  # a report's argument is called table

__all__ = ["calibration_report", "calibration_comparison", "study_calibration_report"]


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


def _off(row: dict, key: str, q: int) -> str:
    """'low'/'high' where the coverage lies more than 2 se from nominal, else ''."""
    got, se = row[f"{key}_{q}"], row[f"se_{q}"]
    return "" if abs(got - q / 100) <= 2 * se else ("low" if got < q / 100 else "high")


def _redrawn_because(cs) -> str:
    """Why a calibration's prior draws are drawn again: the simulator's refusals, and the
    selections ``cs`` asks (``StudyCalibration.domain``, ``min_ratio``)."""
    why = ["refused by the simulator"]
    if getattr(cs, "domain", False):
        why.append("outside the impedance coordinates' domain")
    if getattr(cs, "min_ratio", None) is not None:
        why.append(f"a record's force ratio below {cs.min_ratio:g}")
    return ", ".join(why[:-1]) + (" or " if len(why) > 1 else "") + why[-1]


def study_calibration_report(out: Path, cs, rows: list[dict], results: list[dict], versions: dict, *,
                             long_enough: int, levels, priors: dict) -> tuple[Path, Path]:
    """``out``/REPORT.md and ``out``/SECTION.md of a calibration in the study's
    configuration (``study.study_calibration``), written from its coverage rows and
    replicates, at the interval ``levels`` (fractions) and with the ``priors`` its devices
    were drawn from. Returns both paths."""
    n = len(results)
    failed = [r for r in results if "error" in r]
    ok = [r for r in results if "ranks" in r]
    levels = [round(100 * q) for q in levels]
    taus = [r["tau_max"] for r in ok if r.get("tau_max")]
    why: dict = {}
    for r in failed:  # one line per distinct error, the replicates it stopped beside it
        why.setdefault(r["error"], []).append(str(r["replicate"]))
    head = (f"{n} replicates: {cs.describe()}. {len(failed)} failed"
            + (" (" + "; ".join(f"{', '.join(ks)}: {e}" for e, ks in why.items()) + ")" if failed else "")
            + "; a failed replicate counts as a miss at every level. "
            + f"{long_enough} of {len(ok)} chains ran at least 50 times their longest autocorrelation time"
            + (f" (median longest tau {np.median(taus):.0f} steps, largest {max(taus):.0f})" if taus else "")
            + f"; {sum(r['redraws'] for r in ok)} prior draws were drawn again ({_redrawn_because(cs)}).")
    verdict = []
    if rows:
        by = {r["parameter"]: r for r in rows}
        b = by.get("b")
        if b:
            ran = [f"{sum(r['hdi'][str(q)]['b'] for r in ok)} of the {len(ok)} that ran at {q} %" for q in levels]
            verdict.append("b's highest-density intervals hold the truth in "
                           + " and ".join(f"{b[f'hdi_{q}']:.3f} of the replicates at {q} % (se {b[f'se_{q}']:.3f})"
                                          for q in levels) + f" ({' and '.join(ran)}).")
        for q in levels:
            off = [f"{r['parameter']} ({_off(r, 'hdi', q)}, {r[f'hdi_{q}']:.2f})" for r in rows if _off(r, "hdi", q)]
            verdict.append(f"At {q} %, " + (f"more than 2 se from nominal: {', '.join(off)}." if off else
                                           "every parameter lies within 2 se of nominal."))
        bad = [r["parameter"] for r in rows if r["rank_chi2_p"] < 0.01]
        verdict.append(f"Ranks not uniform (chi-square p < 0.01): {', '.join(bad)}." if bad else
                       "No rank histogram departs from uniform at p < 0.01.")
    cols = ["parameter", "replicates", "failed"] + [c for q in levels for c in (f"hdi_{q}", f"central_{q}", f"se_{q}")]
    cols.append("rank_chi2_p")
    fmt = {c: "{:.3f}" for c in cols[3:]}
    table = markdown_table(rows, cols, fmt) if rows else "(no replicate ran)"
    prior = "\n".join(f"- {name}: {p.describe()}" for name, p in priors.items())
    report = ["# Simulation-based calibration in the study's configuration", "",
              "**Question.** Do the intervals the study reports hold the truth as often as they say, where its "
              "numbers come from: 10 s generator records, "
              + ("each fitted alone as `bayes-inerter fit` fits it" if getattr(cs, "single", False) else
                 "the joint model") + ", the package's start and the 94 % interval?", "", head, "", " ".join(verdict), "",
              "Columns: `hdi_<q>` is the coverage of the highest-density interval the study reports, `central_<q>` "
              "of the equal-tailed one, `se_<q>` the binomial standard error at the nominal level.", "",
              table, "", "![coverage](coverage.png)", "", "![ranks](ranks.png)", "",
              "The prior each device is drawn from and fitted under:", "", prior, "",
              "Versions: " + ", ".join(f"{k} {v}" for k, v in versions.items()) + ".", "",
              f"Settings: `{cs!r}`", ""]
    section = ["## Calibration in the study's configuration", "",
               "Simulation-based calibration where the study's numbers come from (results/study-calibration): "
               "devices drawn from a wide physical prior, 10 s generator records, the joint model and the package's "
               "start, the 94 % and 50 % intervals checked directly. " + head, "", " ".join(verdict), "",
               markdown_table(rows, ["parameter"] + [f"hdi_{q}" for q in levels] + ["rank_chi2_p"],
                              {c: "{:.3f}" for c in [f"hdi_{q}" for q in levels] + ["rank_chi2_p"]})
               if rows else "", "", "![coverage](coverage.png)", ""]
    path, spath = Path(out) / "REPORT.md", Path(out) / "SECTION.md"
    path.write_text("\n".join(report))
    spath.write_text("\n".join(section))
    return path, spath
