"""A study's REPORT.md: the tables and figures with a few sentences of what they say.

Every sentence is written from the numbers in the tables (nothing is typed in by hand),
so the report of a study that has not converged or that misses the truth says so.
"""

from __future__ import annotations

import dataclasses
import os
from pathlib import Path

from ..inference.sampling.sampler import Convergence
from .analysis import is_joint
from .least_squares import least_squares_section
from .markdown import table
from .report_text import (
    AMBIGUITY,
    calibration_text,
    combination_note,
    how_identified,
    outlying_text,
    records_sentence,
    regression_text,
    truth_sentence,
)

__all__ = ["write_report", "NOT_IDENTIFIED", "shown_path"]

#: Contraction below which a parameter is reported as not identified by the records.
NOT_IDENTIFIED = 0.5
#: Pareto k above which PSIS-LOO is flagged as unreliable (Vehtari et al. 2017).
PARETO_K = 0.7


def _joint_section(rows, info, calibration=None, truth_b=None, gains=None) -> list[str]:
    status = ("converged" if info["converged"] else
              f"**not converged** after {info['iterations']} steps ({info['reason']}): read it as indicative")
    text = ("One set of friction and deformation parameters for every record and one b per setting, as the paper "
            f"tuned them (`joint/`, `joint_inertance.csv`); the chain is {status}. ")
    if "covers_truth" in rows[0]:
        held = sum(r["covers_truth"] for r in rows)
        text += f"Its 94 % interval holds the generating b for {held} of {len(rows)} settings. "
    if "covers_truth_app" in rows[0]:
        held = sum(r["covers_truth_app"] for r in rows)
        text += (f"What the records fix more tightly is the inertance seen through the nut, "
                 f"b_app = b (1 + b k_n / c_n^2) (`device.apparent_inertance`): a stiffer nut with a smaller b "
                 f"looks the same at these frequencies. Its 94 % interval holds the generating b_app for {held} of "
                 f"{len(rows)} settings. ")
    text += ("The joint b's are correlated through the shared parameters (the frictions, the nut); the "
             "regression per flywheel above is taken draw by draw, which keeps that correlation.")
    if calibration is not None:
        text += " " + calibration_text(rows, calibration, truth_b, "b_joint_cal_", gains)
    cols = ("setting", "b_theory", "b_truth", "b_single_median", "b_joint_mean", "b_joint_hdi_3%", "b_joint_hdi_97%",
            "covers_truth", "b_app_truth", "b_app_joint_hdi_3%", "b_app_joint_hdi_97%", "covers_truth_app",
            "b_joint_cal_hdi_3%", "b_joint_cal_hdi_97%", "r_hat", "ess_bulk")
    one = ("b_theory", "b_truth", "b_single_median", "b_joint_mean", "b_joint_hdi_3%", "b_joint_hdi_97%",
           "b_app_truth", "b_app_joint_hdi_3%", "b_app_joint_hdi_97%", "b_joint_cal_hdi_3%", "b_joint_cal_hdi_97%")
    out = ["### Joint model: all records at once", "", text, "",
           table(rows, [c for c in cols if c in rows[0]],
                  {c: "{:.1f}" for c in one} | {"r_hat": "{:.3f}", "ess_bulk": "{:.0f}"}), "",
           "The joint posterior's corner plot is `joint/corner.png`, and its force-displacement and "
           "force-velocity loops over a steady period, two panels per record, `joint/loops.png` (the "
           "motion-in likelihood's fits); both are drawn where the joint chain ran.", ""]
    return out


#: The regression's columns in the report (``cal_*``: the sensors' calibration added).
REGRESSION_COLUMNS = ("term", "theory", "truth", "mean", "sd", "hdi_3%", "hdi_97%", "covers_theory", "covers_truth",
                      "cal_hdi_3%", "cal_hdi_97%", "covers_truth_cal")
REGRESSION_FORMATS = {c: "{:.1f}" for c in ("theory", "truth", "mean", "sd", "hdi_3%", "hdi_97%", "cal_hdi_3%",
                                            "cal_hdi_97%")}


def _regression_table(reg) -> str:
    """A regression per flywheel (``analysis.flywheel_regression``) as a table of the columns it has."""
    return table(reg, [c for c in REGRESSION_COLUMNS if c in reg[0]], REGRESSION_FORMATS)


def _answer_section(plan, inert, tables, truth_b) -> list[str]:
    """The report's first screen: one table of theory, paper and identified inertance
    with its interval per setting, how the interval was made, and the figure."""
    joint = is_joint(inert)
    how = how_identified(inert)
    rows = [{"setting": r["setting"], "theory (kg)": r["b_theory"], "paper (kg)": r["b_paper"],
             "identified (kg)": r["b_median"], "94 % interval (kg)": f"{r['b_hdi_3%']:.1f} to {r['b_hdi_97%']:.1f}",
             "against theory": f"{100 * (r['b_median'] / r['b_theory'] - 1):+.1f} %",
             **({"with sensor uncertainty (kg)": f"{r['b_cal_hdi_3%']:.1f} to {r['b_cal_hdi_97%']:.1f}"}
                if "b_cal_hdi_3%" in r else {}),
             **({"honest 94 % interval (kg)": _honest_cell(r)} if "b_honest_3%" in r else {})} for r in inert]
    cols = list(rows[0])
    lines = ["## Inertance per flywheel setting", "",
             table(rows, cols, {"theory (kg)": "{:.1f}", "paper (kg)": "{:.1f}", "identified (kg)": "{:.1f}"}), "",
             f"Identified: {how} Theory: the paper's geometry (`device.theoretical_inertance`). Paper: its Table 2, "
             "tuned by hand."
             + (" The column with sensor uncertainty adds the sensors' calibration uncertainty (below)."
                if "b_cal_hdi_3%" in inert[0]
                else "")
             + (HONEST_NOTE + _honest_truth(inert) if any("b_honest_3%" in r for r in inert) else "")
             + (f" The records were generated with known inertances: {truth_sentence(inert, truth_b)}."
                if truth_b else "")
             + (" **The joint chain is not converged: read these intervals as indicative.**"
                if joint and not all(r["converged"] for r in inert) else ""), "",
             "![theory against identification](theory_vs_identified.png)", ""]
    return lines


#: What the honest column is (``study.honest``), after the table.
HONEST_NOTE = (" The honest interval is what to quote for a real device: each record's posterior widened by the "
               "model discrepancy its harmonics show and the sensors' calibration, records the model reproduces "
               "less than half of left out (b not identified there), and the frequencies combined with the Birge "
               "ratio where they disagree (docs/inference.md, measured in results/model-error).")


def shown_path(path, out) -> str:
    """``path`` as a report in the folder ``out`` names it: relative to ``out``, with
    ``/``, so a committed report names no folder of the machine that made it (a path on
    another drive, where there is no relative one, by its name)."""
    try:
        rel = os.path.relpath(Path(path).resolve(), Path(out).resolve())
    except ValueError:
        return Path(path).name
    return rel.replace(os.sep, "/")


def _records_link(shown: str) -> str:
    """A link to the records' folder, its text the path itself: ``study.headline``
    moves both when it takes the section into another folder's report."""
    return f"[`{shown}`]({shown})"


def _honest_cell(row: dict) -> str:
    if not row["honest_identified"]:
        return f"not identified ({row['honest_records']} records)"
    return f"{row['b_honest_3%']:.1f} to {row['b_honest_97%']:.1f} ({row['honest_records']} records)"


def _honest_truth(inert) -> str:
    held = [r["covers_truth_honest"] for r in inert if "covers_truth_honest" in r]
    return f" It holds the generating b for {sum(held)} of {len(held)} settings." if held else ""


def _limitations_section(plan, tables, outcomes, truth_b) -> list[str]:
    """What the answer does not cover: where the records come from, what they do not
    identify, what the intervals were not tested against, unconverged or failed fits,
    and unreliable LOO."""
    contr, comp = tables.get("contraction", []), tables.get("models", [])
    done = [o for o in outcomes if o["status"] != "failed"]
    failed = [o for o in outcomes if o["status"] == "failed"]
    n_conv = sum(bool(o.get("converged")) for o in done)
    items = []
    if plan.records_dir and truth_b:
        items.append(f"The records ({_records_link(plan.records_dir)}) carry the parameters they were generated "
                     "with, so each interval is checked against a known b. A generated device is not the paper's "
                     "device: a richer one (paper-like: Stribeck friction, nut backlash, sensor errors) shows how "
                     "the intervals behave when the model is wrong in known ways, not in every way a real inerter "
                     "may be.")
    elif plan.records_dir:
        items.append(f"The records are the user's ({_records_link(plan.records_dir)}): no true inertance is "
                     "known, and no model fits a real device exactly; the posterior's intervals are the model's, "
                     "the honest ones add what the records show of the model's discrepancy and the sensors' "
                     "calibration.")
    else:
        items.append("The records were generated by this package from the model it fits (the paper's reduced "
                     "two-port network, Coulomb friction, its parameters): the fitted model is the true one. On "
                     "records of a device richer than the model (Stribeck friction, nut backlash, sensor errors), "
                     "which a real inerter is, the posterior's 94 % interval covers b for fewer than half and the "
                     "honest one for about 0.94 (`results/model-error`, approximate posteriors).")
    if contr:
        names = [k for k in contr[0] if k != "record"]
        weak = [n for n in names if min(r[n] for r in contr) < NOT_IDENTIFIED]
        if weak:
            items.append(f"Not identified by some record (posterior contraction below {NOT_IDENTIFIED}): "
                         f"{', '.join(weak)}; their intervals are the prior's, and b moves with some of them "
                         "(details below).")
    if plan.calibration.ratio_sd > 0:
        items.append("Every interval but those with sensor uncertainty and the honest ones takes the sensors' "
                     "sensitivities as exact.")
    conv = Convergence()
    if n_conv < len(done):
        items.append(f"**{len(done) - n_conv} of {len(done)} chains did not meet the convergence criteria** "
                     f"({conv.n_tau:g} autocorrelation times after a {100 * conv.warmup:.0f} % warm-up, R-hat < "
                     f"{conv.max_rhat:g}, ESS >= {conv.min_ess:g}): read their intervals as indicative.")
    else:
        items.append(f"All {len(done)} chains met the convergence criteria ({conv.n_tau:g} autocorrelation times "
                     f"after a {100 * conv.warmup:.0f} % warm-up, R-hat < {conv.max_rhat:g}, ESS >= {conv.min_ess:g}).")
    if failed:
        items.append("**Failed fits:** " + "; ".join(f"{o['key']}: {o.get('error', '')}" for o in failed))
    high_k = [f"{r['record']} ({r['model']}, k = {r['pareto_k_max']:.2f})" for r in comp
              if r.get("pareto_k_max") is not None and r["pareto_k_max"] > PARETO_K]
    if high_k:
        items.append(f"LOO is unreliable (Pareto k above {PARETO_K}) for " + ", ".join(high_k)
                     + ": their model comparison is approximate.")
    return ["## Limitations", "", *[f"- {t}" for t in items], ""]


def _records_section(plan, inert, recs, tables, truth_b, truth_app) -> list[str]:
    """Each record's own posterior of b (and b_app), how the per-setting values combine
    them, what the records cannot tell apart, and the sensors' calibration."""
    gains = None if plan.records_dir else (plan.generator.force_gain, plan.generator.accel_gain)
    app_cols = [c for c in ("b_app_hdi_3%", "b_app_hdi_97%") if recs and c in recs[0]]
    note = combination_note(inert, tables.get("joint"))
    return ["### Each record on its own", "",
            records_sentence(recs, truth_b, truth_app)
            + " Intervals here are each record's own posterior (mean and 94 % HDI), with its own friction "
              "and deformation parameters" + (": wider than the joint model's above." if is_joint(inert) else "."),
            "",
            table(recs, ["record", "b_mean", "b_hdi_3%", "b_hdi_97%", *app_cols, "b_r_hat", "iterations",
                          "converged"],
                   {c: "{:.1f}" for c in ("b_mean", "b_hdi_3%", "b_hdi_97%", *app_cols)}), "",
            *([note, ""] if note else []),
            AMBIGUITY if recs and app_cols else "", "",
            "### Sensor calibration", "", calibration_text(inert, plan.calibration, truth_b, "b_cal_", gains,
                                                              bool(tables.get("calibration_in_posterior"))), ""]


def _regression_section(reg, inert, product) -> list[str]:
    """The inertance added per flywheel (``analysis.flywheel_regression``), and beside the
    joint model's the same regression of the records' ``product``."""
    lines = ["### Inertance added per flywheel", "", regression_text(reg, is_joint(inert)), "",
             _regression_table(reg), "",
             "The records were generated with the paper's identified b per setting, not the geometry's: "
             "`truth` is what the regression gives on those values, `theory` the geometry."
             if "truth" in reg[0] else "", ""]
    if product:
        lines += ["The same regression of each setting's records combined one by one (`flywheels_product.csv`; "
                  "independent normals):", "",
                  _regression_table(product), ""]
    return lines


def _phi_section(phi) -> list[str]:
    """The fit accuracy phi per record beside the paper's Table 2."""
    return ["### Fit accuracy phi (the paper's Table 2, with uncertainty)", "",
            "phi (eq. 5) on the 30 Hz low-passed accelerations inside the likelihood's window, for every "
            "posterior draw; the paper's phi is on its unfiltered measured records, so the two are not the "
            "same measure: ours says how well the model explains what the filter keeps."
            + outlying_text(phi), "",
            table(phi, ["setting", "freq_hz", "phi_mean", "phi_hdi_3%", "phi_hdi_97%", "phi_paper"],
                   {c: "{:.4f}" for c in ("phi_mean", "phi_hdi_3%", "phi_hdi_97%", "phi_paper")}), "",
            "![phi heat map](phi_map.png)", ""]


def _contraction_section(contr) -> list[str]:
    """What the records identify: each parameter's posterior contraction per record."""
    names = [k for k in contr[0] if k != "record"]
    return ["### What the records identify", "",
            "Posterior contraction 1 - var(posterior) / var(prior) in the sampled scale: 1 is pinned down by "
            "the data, 0 is the prior unchanged.", "",
            table(contr, ["record"] + names, {n: "{:.2f}" for n in names}), "",
            "What other experiments (frequency, amplitude, accelerometer band and noise) would identify, and "
            "what a Stribeck hump or nut backlash does to b: `python studies/design.py`, written to "
            "`results/design/REPORT.md`.", ""]


def _closing_section(plan, versions: dict) -> list[str]:
    """Where the per-record figures come from, and the versions and plan of the run."""
    return ["### Per-record figures", "",
            "`bayes-inerter report DIR` draws each fit's corner plot, credible bands, traces and phi into its "
            "folder under `fits/<model>/<record>/` from its checkpoint (kept where the fit ran).", "",
            "### How this was made", "",
            "Versions: " + ", ".join(f"{k} {v}" for k, v in versions.items()) + ".", "",
            f"Plan: `{plan!r}`" + (" (`records_dir` relative to this folder)." if plan.records_dir else ""), ""]


def write_report(out: Path, plan, tables: dict, outcomes: list[dict], versions: dict, truth_b: dict | None,
                 truth_app: dict | None = None) -> Path:
    """Write ``out``/REPORT.md from the study's tables; return its path. ``truth_b`` and
    ``truth_app``: the generating b and b_app per setting, where the records were generated.

    The answer first (one table and one figure), then the limitations, then the details;
    each interval says how it was made. The records' folder (``plan.records_dir``) is
    named relative to ``out`` (:func:`shown_path`)."""
    if plan.records_dir:
        plan = dataclasses.replace(plan, records_dir=shown_path(plan.records_dir, out))
    inert, reg, phi, comp, contr, recs = (tables.get(k, []) for k in
                                          ("inertance", "regression", "phi", "models", "contraction", "records"))
    gains = None if plan.records_dir else (plan.generator.force_gain, plan.generator.accel_gain)
    source = (f"the records in {_records_link(plan.records_dir)}" if plan.records_dir else
              f"records generated at the paper's parameters (settings {', '.join(plan.settings)}; "
              f"{', '.join(f'{f:g}' for f in plan.frequencies)} Hz; noise seed {plan.seed})")
    chains = (f"each chain {plan.steps} steps" if plan.steps else "each chain run until converged")
    lines = [f"# Study `{plan.name}`: the inertance of each flywheel setting", "",
             f"Fitted: {source}; {len(outcomes)} posteriors ({chains}).", ""]
    if inert:
        lines += _answer_section(plan, inert, tables, truth_b)
    lines += _limitations_section(plan, tables, outcomes, truth_b)
    lines += ["## Details", ""]
    if inert:
        lines += _records_section(plan, inert, recs, tables, truth_b, truth_app)
    if reg:
        lines += _regression_section(reg, inert, tables.get("product_regression"))
    if tables.get("joint"):
        lines += _joint_section(tables["joint"], tables["joint_info"], None, truth_b, gains)
    if phi:
        lines += _phi_section(phi)
    if tables.get("least_squares"):
        lines += least_squares_section(tables["least_squares"])
    if comp:
        lines += _comparison_section(comp)
    if contr:
        lines += _contraction_section(contr)
    lines += _closing_section(plan, versions)
    path = Path(out) / "REPORT.md"
    path.write_text("\n".join(lines))
    return path


def _comparison_section(comp) -> list[str]:
    """Model comparison by LOO, each Pareto k above :data:`PARETO_K` flagged."""
    best = {}
    for r in comp:
        if r["record"] not in best or r["elpd_loo"] > best[r["record"]]["elpd_loo"]:
            best[r["record"]] = r
    sent = "; ".join(f"{rec}: {r['model']}" for rec, r in best.items())
    rows = [{**r, "loo_reliable": "yes" if r.get("pareto_k_max") is not None and r["pareto_k_max"] <= PARETO_K
             else "**no**"} for r in comp]
    return ["### Model comparison", "",
            f"Best model by LOO (expected log predictive density) per record: {sent}.", "",
            f"A Pareto k above {PARETO_K} (`pareto_k_max`; `loo_reliable` no) means LOO's importance sampling is "
            "unreliable for some observations of that fit; its elpd is then approximate.", "",
            table(rows, ["record", "model", "elpd_loo", "elpd_se", "p_loo", "pareto_k_max", "loo_reliable",
                          "phi_mean", "phi_paper_overall", "converged"],
                   {"elpd_loo": "{:.1f}", "elpd_se": "{:.1f}", "p_loo": "{:.1f}", "pareto_k_max": "{:.2f}",
                    "phi_mean": "{:.4f}"}), "",
            "![model comparison](model_comparison.png)", ""]


