"""A study's REPORT.md: the tables and figures with a few sentences of what they say.

Every sentence is written from the numbers in the tables (nothing is typed in by hand),
so the report of a study that has not converged or that misses the truth says so.
"""

from __future__ import annotations

import math
from pathlib import Path

from scipy import stats

from ..inference.sampler import Convergence
from .analysis import is_joint

__all__ = ["write_report", "design_report", "calibration_report", "calibration_comparison", "NOT_IDENTIFIED"]

#: Contraction below which a parameter is reported as not identified by the records.
NOT_IDENTIFIED = 0.5
#: Pareto k above which PSIS-LOO is flagged as unreliable (Vehtari et al. 2017).
PARETO_K = 0.7


def _table(rows: list[dict], columns: list[str], fmt: dict | None = None) -> str:
    fmt = fmt or {}
    lines = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    for r in rows:
        cells = []
        for c in columns:
            v = r.get(c)
            if isinstance(v, float):
                cells.append(fmt.get(c, "{:.4g}").format(v))
            else:
                cells.append("" if v is None else str(v))
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _interval_list(rows, prefix: str = "b_") -> str:
    """'A0 752 kg (751-753; +58.5 % against theory); ...' from ``<prefix>median`` and its interval."""
    return "; ".join(f"{r['setting']} {r[f'{prefix}median']:.0f} kg ({r[f'{prefix}hdi_3%']:.0f}-"
                     f"{r[f'{prefix}hdi_97%']:.0f}; {100 * (r[f'{prefix}median'] / r['b_theory'] - 1):+.1f} % "
                     "against theory)" for r in rows)


def _truth_sentence(rows, truth_b: dict | None, prefix: str = "b_") -> str:
    """'the 94 % interval holds the true value for n of m settings (and misses it for ...)'."""
    known, missed = _coverage(rows, truth_b, prefix)
    missed = [r["setting"] for r in missed]
    return (f"the 94 % interval holds the true value for {len(known) - len(missed)} of {len(known)} settings"
            + (f" and misses it for {', '.join(missed)}" if missed else ""))


def _discrepancy_text(rows) -> str:
    """What the chi-square of each setting's per-record means says (``analysis.inertance_table``)."""
    text = ""
    scaled = [f"{r['setting']} ({r['scale']:.2f})" for r in rows if r.get("scale", 1.0) > 1.0]
    if scaled:
        text += (" Where a setting's records at different frequencies disagree on b by more than their intervals "
                 "allow (chi-square of the per-record means above its degrees of freedom), the combined sd is "
                 "widened by the Birge ratio sqrt(chi2 / (records - 1)): " + ", ".join(scaled) + ".")
    gross = [r["setting"] for r in rows
             if r.get("records", 1) > 1 and stats.chi2.sf(r["chi2"], r["records"] - 1) < 0.01]
    if gross:
        text += (f" For {', '.join(gross)} the disagreement is beyond chance (p < 1 %): rather than intervals too "
                 "narrow by a common factor, which is what the widening assumes, it may mean that the identified "
                 "b changes with the drive frequency.")
    return text


def _outlying_text(rows, name: str = "phi") -> str:
    """Rows whose posterior mean of ``name`` lies outside its own 94 % HDI: a small share
    of the draws lies far from the rest (a walker or two in another mode, say), which the
    interval leaves out and the mean does not; empty where there are none."""
    odd = [r for r in rows if not r[f"{name}_hdi_3%"] <= r[f"{name}_mean"] <= r[f"{name}_hdi_97%"]]
    if not odd:
        return ""
    where = ", ".join(f"{r['setting']} at {r['freq_hz']:g} Hz" for r in odd)
    return (f" For {where} the mean of {name} lies outside its 94 % interval: a small share of that chain's draws "
            "lies far from the rest (fits much worse), which the interval leaves out and the mean does not; "
            "read that record's posterior as holding a second, minor mode that its convergence checks did not catch.")


def _combination_note(inert, joint_rows) -> str:
    """Where the per-setting b's above come from: the joint model (and then what each
    setting's records, fitted one by one and combined, give beside it), or the product of
    each setting's records (nothing to say where every setting has one record)."""
    if is_joint(inert):
        text = ("These are the joint model's b's (below): one set of friction and deformation parameters for every "
                "record and one b per setting, as the paper tuned them. Fitted one record at a time and combined per "
                "setting as independent normals (the product of their posteriors: the `b_product_*` columns of "
                "`inertance.csv`, green in the figure), the same records give " + _interval_list(inert, "b_product_")
                + ".")
        if joint_rows and "b_truth" in joint_rows[0]:
            truth = {r["setting"]: r["b_truth"] for r in joint_rows}
            text += f" For those, {_truth_sentence(inert, truth, 'b_product_')}."
        text += (" Each record on its own leaves open where the viscous friction acts and how stiff the nut is, and "
                 "b moves with them (below); the joint model shares them across all records, which is the paper's "
                 "model and uses every record for them." + _discrepancy_text(inert))
        return text
    if all(r.get("records", 1) <= 1 for r in inert):
        return ""
    return ("These combine each setting's records as independent normals (the product of their posteriors): "
            "each record has its own frictions and deformations, so what every record leaves open and each "
            "moves b by (where the viscous friction acts, the nut's stiffness) is counted once per record. "
            "The study's joint model (`--no-joint` left it out, or it has too few records) shares them.")


def _calibration_text(rows, calibration, truth_b: dict | None, prefix: str, gains=None) -> str:
    """What the sensors' calibration adds to b (``<prefix>hdi_*`` columns). ``gains``: the
    (load cell, accelerometer) sensitivity errors the records were generated with (None
    for a user's records); with errors and ``truth_b``, how often the widened intervals
    hold the generating b."""
    if not rows or f"{prefix}hdi_3%" not in rows[0]:
        return ""
    u = calibration.ratio_sd
    if u == 0:
        return ("The sensors' sensitivities are taken as exact (`--sensor-uncertainty 0 0`): no calibration "
                "uncertainty is added to b.")
    text = (f"These intervals take the sensors' sensitivities as exact. With the load cell's sensitivity known "
            f"to {100 * calibration.force:.2g} % and the accelerometer's to {100 * calibration.accel:.2g} % (standard "
            f"uncertainties, an **assumption**: `--sensor-uncertainty`), a record reads the same whether b or the "
            f"sensitivities' ratio is off (`records.sensitivity`), so b carries a further {100 * u:.2g} % of "
            f"b plus the moving mass that no record can reduce: the 94 % intervals widen to those of the first "
            f"table's last column.")
    if truth_b and gains is not None:
        if tuple(gains) == (1.0, 1.0):
            text += (" The records were generated with exact sensitivities, so the records-alone intervals are the "
                     "ones to hold against the generating b; these say how wide a real measurement's interval is.")
        else:
            known, missed = _coverage(rows, truth_b, prefix)
            text += (f" The records were generated with a load cell reading {gains[0]:g} and an accelerometer "
                     f"{gains[1]:g} times the truth: these intervals hold the generating b for "
                     f"{len(known) - len(missed)} of {len(known)} settings.")
    return text


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
        text += " " + _calibration_text(rows, calibration, truth_b, "b_joint_cal_", gains)
    cols = ("setting", "b_theory", "b_truth", "b_single_median", "b_joint_mean", "b_joint_hdi_3%", "b_joint_hdi_97%",
            "covers_truth", "b_app_truth", "b_app_joint_hdi_3%", "b_app_joint_hdi_97%", "covers_truth_app",
            "b_joint_cal_hdi_3%", "b_joint_cal_hdi_97%", "r_hat", "ess_bulk")
    one = ("b_theory", "b_truth", "b_single_median", "b_joint_mean", "b_joint_hdi_3%", "b_joint_hdi_97%",
           "b_app_truth", "b_app_joint_hdi_3%", "b_app_joint_hdi_97%", "b_joint_cal_hdi_3%", "b_joint_cal_hdi_97%")
    out = ["### Joint model: all records at once", "", text, "",
           _table(rows, [c for c in cols if c in rows[0]],
                  {c: "{:.1f}" for c in one} | {"r_hat": "{:.3f}", "ess_bulk": "{:.0f}"}), "",
           "The joint posterior's corner plot is `joint/corner.png`, drawn where the joint chain ran.", ""]
    return out


#: The regression's columns in the report (``cal_*``: the sensors' calibration added).
REGRESSION_COLUMNS = ("term", "theory", "truth", "mean", "sd", "hdi_3%", "hdi_97%", "covers_theory", "covers_truth",
                      "cal_hdi_3%", "cal_hdi_97%", "covers_truth_cal")
REGRESSION_FORMATS = {c: "{:.1f}" for c in ("theory", "truth", "mean", "sd", "hdi_3%", "hdi_97%", "cal_hdi_3%",
                                            "cal_hdi_97%")}


def _regression_table(reg) -> str:
    """A regression per flywheel (``analysis.flywheel_regression``) as a table of the columns it has."""
    return _table(reg, [c for c in REGRESSION_COLUMNS if c in reg[0]], REGRESSION_FORMATS)


def _regression_text(reg, joint: bool) -> str:
    """The regression per flywheel in a sentence per term (``analysis.flywheel_regression``)."""
    sent = "; ".join(f"{r['term']}: {r['mean']:.1f} kg ({r['hdi_3%']:.1f}-{r['hdi_97%']:.1f}), geometry "
                     f"{r['theory']:.1f} kg, {'inside' if r['covers_theory'] else 'outside'} the interval"
                     + (f"; the generating values give {r['truth']:.1f} kg, "
                        f"{'inside' if r['covers_truth'] else 'outside'} it" if "truth" in r else "")
                     for r in reg)
    how = ("of the joint model's b's on the numbers of small and big flywheels, every posterior draw regressed "
           "(`flywheels.csv`; the b's correlation through the shared parameters kept)" if joint else
           "of the per-setting posteriors on the numbers of small and big flywheels (`flywheels.csv`; independent "
           "normals)")
    return f"A weighted least-squares regression {how}: {sent}."


def _coverage(rows, truth_b: dict | None, prefix: str = "b_"):
    """(rows whose setting has a generating b, those of them whose 94 % interval,
    ``<prefix>hdi_3%`` to ``<prefix>hdi_97%``, misses it)."""
    known = [r for r in rows if truth_b and r["setting"] in truth_b]
    missed = [r for r in known if not r[f"{prefix}hdi_3%"] <= truth_b[r["setting"]] <= r[f"{prefix}hdi_97%"]]
    return known, missed


def _record_coverage(recs, truth, prefix: str = "b_", label: str = "b") -> str:
    """'the 94 % intervals hold the generating <label> for n of m records (missed: ...)',
    or "" where no record has a generating value or an interval of it."""
    known, missed = _coverage([r for r in recs if f"{prefix}hdi_3%" in r], truth, prefix)
    if not known:
        return ""
    missed = [r["record"] for r in missed]
    return (f"the 94 % intervals hold the generating {label} for {len(known) - len(missed)} of {len(known)} records"
            + (f" (missed: {', '.join(missed)})" if missed else ""))


def _records_sentence(recs, truth_b, truth_app) -> str:
    """The per-record table's lead: how often b's and b_app's intervals hold their
    generating values, where the records were generated."""
    said = [t for t in (_record_coverage(recs, truth_b), _record_coverage(
        recs, truth_app, "b_app_", "b_app = b (1 + b k_n / c_n^2), the inertance seen through the nut,")) if t]
    return "Per record (`inertance_records.csv`)" + (": " + "; ".join(said) + "." if said else ":")


#: What the records cannot tell apart (``studies/ambiguity.py`` measures it on the paper's grid).
_AMBIGUITY = (
    "What a record fixes is the driving-point impedance at its drive frequency, not b itself: to first order "
    "b (1 - 2 c_f2 / c_n + b k_n / c_n^2). Where the viscous friction acts (plate or rotation) and how stiff the "
    "nut is are not identified, and they move b at the same data: by 0.15 % between all the viscous friction on "
    "the rotation and all on the plate, and by 0.13 % (A0) to 3.4 % (B2 at 1.5 Hz) as the nut stiffness goes "
    "from 1e3 to 1e7 N/m (on the paper's devices: `results/sensitivity/ambiguity.csv`). b's posterior spreads "
    "along both; b_app, which takes in the nut's stiffness but not the viscous split, along the split only. "
    "A generating value at the edge of what the prior allows for them (the paper's viscous friction is all on "
    "the rotation, where b is largest) lies at the top of b's posterior, and may fall just outside its interval.")


def _how_identified(inert) -> str:
    """How the per-setting intervals were made, in a sentence or two."""
    if is_joint(inert):
        return ("the joint model of all records (one set of friction and deformation parameters, one b per setting; "
                "`joint/`): posterior median and 94 % highest-density interval.")
    if all(r.get("records", 1) <= 1 for r in inert):
        return "each setting's one record: posterior median and 94 % highest-density interval."
    return ("each setting's records fitted one by one and combined as independent normals (the product of their "
            "posteriors): median and 94 % interval." + _discrepancy_text(inert))


def _answer_section(plan, inert, tables, truth_b) -> list[str]:
    """The report's first screen: one table of theory, paper and identified inertance
    with its interval per setting, how the interval was made, and the figure."""
    joint = is_joint(inert)
    how = _how_identified(inert)
    rows = [{"setting": r["setting"], "theory (kg)": r["b_theory"], "paper (kg)": r["b_paper"],
             "identified (kg)": r["b_median"], "94 % interval (kg)": f"{r['b_hdi_3%']:.1f} to {r['b_hdi_97%']:.1f}",
             "against theory": f"{100 * (r['b_median'] / r['b_theory'] - 1):+.1f} %",
             **({"with sensor uncertainty (kg)": f"{r['b_cal_hdi_3%']:.1f} to {r['b_cal_hdi_97%']:.1f}"}
                if "b_cal_hdi_3%" in r else {})} for r in inert]
    cols = list(rows[0])
    lines = ["## Inertance per flywheel setting", "",
             _table(rows, cols, {"theory (kg)": "{:.1f}", "paper (kg)": "{:.1f}", "identified (kg)": "{:.1f}"}), "",
             f"Identified: {how} Theory: the paper's geometry (`device.theoretical_inertance`). Paper: its Table 2, "
             "tuned by hand."
             + (" The last column adds the sensors' calibration uncertainty (below)." if "b_cal_hdi_3%" in inert[0]
                else "")
             + (f" The records were generated with known inertances: {_truth_sentence(inert, truth_b)}."
                if truth_b else "")
             + (" **The joint chain is not converged: read these intervals as indicative.**"
                if joint and not all(r["converged"] for r in inert) else ""), "",
             "![theory against identification](theory_vs_identified.png)", ""]
    return lines


def _limitations_section(plan, tables, outcomes, truth_b) -> list[str]:
    """What the answer does not cover: where the records come from, what they do not
    identify, what the intervals were not tested against, unconverged or failed fits,
    and unreliable LOO."""
    contr, comp = tables.get("contraction", []), tables.get("models", [])
    done = [o for o in outcomes if o["status"] != "failed"]
    failed = [o for o in outcomes if o["status"] == "failed"]
    n_conv = sum(bool(o.get("converged")) for o in done)
    items = []
    if plan.records_dir:
        items.append(f"The records are the user's (`{plan.records_dir}`): no true inertance is known, and no model "
                     "fits a real device exactly; the intervals are the model's.")
    else:
        items.append("The records were generated by this package from the model it fits (the paper's reduced "
                     "two-port network, Coulomb friction, its parameters): the fitted model is the true one. The "
                     "intervals have not been tested here against a device richer than the model (Stribeck "
                     "friction, nut backlash, sensor errors), which a real inerter is.")
    if contr:
        names = [k for k in contr[0] if k != "record"]
        weak = [n for n in names if min(r[n] for r in contr) < NOT_IDENTIFIED]
        if weak:
            items.append(f"Not identified by some record (posterior contraction below {NOT_IDENTIFIED}): "
                         f"{', '.join(weak)}; their intervals are the prior's, and b moves with some of them "
                         "(details below).")
    if plan.calibration.ratio_sd > 0:
        items.append("Every interval but the last column's takes the sensors' sensitivities as exact.")
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


def write_report(out: Path, plan, tables: dict, outcomes: list[dict], versions: dict, truth_b: dict | None,
                 truth_app: dict | None = None) -> Path:
    """Write ``out``/REPORT.md from the study's tables; return its path. ``truth_b`` and
    ``truth_app``: the generating b and b_app per setting, where the records were generated.

    The answer first (one table and one figure), then the limitations, then the details;
    each interval says how it was made."""
    inert, reg, phi, comp, contr, recs = (tables.get(k, []) for k in
                                          ("inertance", "regression", "phi", "models", "contraction", "records"))
    gains = None if plan.records_dir else (plan.generator.force_gain, plan.generator.accel_gain)
    source = (f"the records in `{plan.records_dir}`" if plan.records_dir else
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
        app_cols = [c for c in ("b_app_hdi_3%", "b_app_hdi_97%") if recs and c in recs[0]]
        note = _combination_note(inert, tables.get("joint"))
        lines += ["### Each record on its own", "",
                  _records_sentence(recs, truth_b, truth_app)
                  + " Intervals here are each record's own posterior (median and 94 % HDI), with its own friction "
                    "and deformation parameters: wider than the per-setting ones above.", "",
                  _table(recs, ["record", "b_mean", "b_hdi_3%", "b_hdi_97%", *app_cols, "b_r_hat", "iterations",
                                "converged"],
                         {c: "{:.1f}" for c in ("b_mean", "b_hdi_3%", "b_hdi_97%", *app_cols)}), "",
                  *([note, ""] if note else []),
                  _AMBIGUITY if recs and app_cols else "", "",
                  "### Sensor calibration", "", _calibration_text(inert, plan.calibration, truth_b, "b_cal_", gains), ""]
    if reg:
        lines += ["### Inertance added per flywheel", "", _regression_text(reg, is_joint(inert)), "",
                  _regression_table(reg), "",
                  "The records were generated with the paper's identified b per setting, not the geometry's: "
                  "`truth` is what the regression gives on those values, `theory` the geometry."
                  if "truth" in reg[0] else "", ""]
        product = tables.get("product_regression")
        if product:
            lines += ["The same regression of each setting's records combined one by one (`flywheels_product.csv`; "
                      "independent normals):", "",
                      _regression_table(product), ""]
    if tables.get("joint"):
        lines += _joint_section(tables["joint"], tables["joint_info"], None, truth_b, gains)
    if phi:
        lines += ["### Fit accuracy phi (the paper's Table 2, with uncertainty)", "",
                  "phi (eq. 5) on the 30 Hz low-passed accelerations inside the likelihood's window, for every "
                  "posterior draw; the paper's phi is on its unfiltered measured records, so the two are not the "
                  "same measure: ours says how well the model explains what the filter keeps."
                  + _outlying_text(phi), "",
                  _table(phi, ["setting", "freq_hz", "phi_mean", "phi_hdi_3%", "phi_hdi_97%", "phi_paper"],
                         {c: "{:.4f}" for c in ("phi_mean", "phi_hdi_3%", "phi_hdi_97%", "phi_paper")}), "",
                  "![phi heat map](phi_map.png)", ""]
    if comp:
        lines += _comparison_section(comp)
    if contr:
        names = [k for k in contr[0] if k != "record"]
        lines += ["### What the records identify", "",
                  "Posterior contraction 1 - var(posterior) / var(prior) in the sampled scale: 1 is pinned down by "
                  "the data, 0 is the prior unchanged.", "",
                  _table(contr, ["record"] + names, {n: "{:.2f}" for n in names}), "",
                  "What other experiments (frequency, amplitude, accelerometer band and noise) would identify, and "
                  "what a Stribeck hump or nut backlash does to b: `python studies/design.py`, written to "
                  "`results/design/REPORT.md`.", ""]
    lines += ["### Per-record figures", "",
              "`bayes-inerter report DIR` draws each fit's corner plot, credible bands, traces and phi into its "
              "folder under `fits/<model>/<record>/` from its checkpoint (kept where the fit ran).", "",
              "### How this was made", "",
              "Versions: " + ", ".join(f"{k} {v}" for k, v in versions.items()) + ".", "",
              f"Plan: `{plan!r}`", ""]
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
            _table(rows, ["record", "model", "elpd_loo", "elpd_se", "p_loo", "pareto_k_max", "loo_reliable",
                          "phi_mean", "phi_paper_overall", "converged"],
                   {"elpd_loo": "{:.1f}", "elpd_se": "{:.1f}", "p_loo": "{:.1f}", "pareto_k_max": "{:.2f}",
                    "phi_mean": "{:.4f}"}), "",
            "![model comparison](model_comparison.png)", ""]


def design_report(out: Path, rows: list[dict], shifts: list[dict], names: list[str], versions: dict,
                  seed: int) -> Path:
    """``out``/REPORT.md of the design study (``study.design``), written from its tables."""
    base_label = rows[0]["design"]
    settings = list(dict.fromkeys(r["setting"] for r in rows))
    lines = ["# What the experiments identify, and what a richer device does to b", "",
             "Laplace (normal) approximations at the generating parameters, no sampling: exact for a posterior "
             "that is normal in the sampled scale, optimistic where it is not. Records generated at the paper's "
             f"parameters, noise seed {seed}.", "",
             "Read the contractions with care: they come out near 0 or 1, because the normal approximation either "
             "sees curvature in a direction or gives it the prior's spread. A posterior pressed against a prior "
             "bound (the Coulomb share lies at 0.996 of its [0, 1] range) or flat up to a one-sided cliff (the nut "
             "stiffness) is beyond it: such entries flip between neighbouring designs and are noise. The robust "
             "findings are the patterns that hold across settings; the sampled contraction of the full study "
             "(`results/full/contraction.csv`) is the measure for the paper's own design.", "",
             "## Design sensitivity", ""]
    for s in settings:
        sub = [r for r in rows if r["setting"] == s]
        base = next(r for r in sub if r["design"] == base_label)
        weak = [n for n in names if base[n] < NOT_IDENTIFIED]
        parts = []
        for n in weak:
            best = max(sub, key=lambda r: r[n])
            parts.append(f"{n} {base[n]:.2f} -> {best[n]:.2f} with '{best['design']}'"
                         if best[n] > base[n] + 0.05 else f"{n} {base[n]:.2f}, no design here does better")
        lines.append(f"- **{s}**: under '{base_label}' not identified (contraction below {NOT_IDENTIFIED}): "
                     + ("; ".join(parts) if parts else "none") + f". Relative sd of b: {100 * base['b_rel_sd']:.2f} %.")
    lines += ["", "![design](design.png)", "",
              _table(rows, ["design", "setting", "force_peak", "b_rel_sd"] + names,
                     {"force_peak": "{:.0f}", "b_rel_sd": "{:.4f}"} | {n: "{:.2f}" for n in names}), "",
              "`force_peak` (N) is what the actuator must deliver; `b_rel_sd` the sd of log b.", "",
              "## Fitting the two-port model to a richer device", ""]
    ref = {(r["setting"], r["freq_hz"]): r for r in shifts if r["truth"] == "model's own"}
    for r in shifts:
        if r["truth"] == "model's own":
            continue
        own = ref.get((r["setting"], r["freq_hz"]))
        lines.append(f"- {r['setting']} {r['freq_hz']:g} Hz, truth with {r['truth']}: b {r['b_optimum']:.1f} kg "
                     f"against {r['b_true']:.1f} ({r['shift_pct']:+.2f} %, {r['shift_sd']:+.1f} sd)"
                     + (f"; on the model's own device the same fit is {own['shift_pct']:+.2f} % "
                        f"({own['shift_sd']:+.1f} sd)." if own else "."))
    lines += ["", "The optimum of the model's log posterior that Nelder-Mead reaches from the device's parameters, and "
              "its Laplace sd; a shift of several sd means the interval would miss the device's b.", "",
              _table(shifts, ["setting", "freq_hz", "truth", "b_true", "b_optimum", "b_sd", "shift_pct", "shift_sd",
                              "phi"], {"b_true": "{:.1f}", "b_optimum": "{:.1f}", "b_sd": "{:.1f}",
                                       "shift_pct": "{:+.2f}", "shift_sd": "{:+.1f}", "phi": "{:.4f}"}), "",
              "Versions: " + ", ".join(f"{k} {v}" for k, v in versions.items()) + ".", ""]
    path = Path(out) / "REPORT.md"
    path.write_text("\n".join(lines))
    return path


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
                  _table(table, ["parameter", "replicates", "coverage_50", "se_50", "coverage_90", "se_90",
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
