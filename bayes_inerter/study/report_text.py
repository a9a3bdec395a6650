"""The sentences of a study's REPORT.md, each written from the numbers in its tables
(``analysis``): what the intervals hold, how they were made, what they leave out."""

from __future__ import annotations

from scipy import stats

from .analysis import is_joint

__all__ = ["coverage", "interval_list", "truth_sentence", "discrepancy_text", "outlying_text", "how_identified",
           "combination_note", "calibration_text", "regression_text", "record_coverage", "records_sentence",
           "AMBIGUITY"]


def coverage(rows, truth_b: dict | None, prefix: str = "b_"):
    """(rows whose setting has a generating b, those of them whose 94 % interval,
    ``<prefix>hdi_3%`` to ``<prefix>hdi_97%``, misses it)."""
    known = [r for r in rows if truth_b and r["setting"] in truth_b]
    missed = [r for r in known if not r[f"{prefix}hdi_3%"] <= truth_b[r["setting"]] <= r[f"{prefix}hdi_97%"]]
    return known, missed


def interval_list(rows, prefix: str = "b_") -> str:
    """'A0 752 kg (751-753; +58.5 % against theory); ...' from ``<prefix>median`` and its interval."""
    return "; ".join(f"{r['setting']} {r[f'{prefix}median']:.0f} kg ({r[f'{prefix}hdi_3%']:.0f}-"
                     f"{r[f'{prefix}hdi_97%']:.0f}; {100 * (r[f'{prefix}median'] / r['b_theory'] - 1):+.1f} % "
                     "against theory)" for r in rows)


def truth_sentence(rows, truth_b: dict | None, prefix: str = "b_") -> str:
    """'the 94 % interval holds the true value for n of m settings (and misses it for ...)'."""
    known, missed = coverage(rows, truth_b, prefix)
    missed = [r["setting"] for r in missed]
    return (f"the 94 % interval holds the true value for {len(known) - len(missed)} of {len(known)} settings"
            + (f" and misses it for {', '.join(missed)}" if missed else ""))


def discrepancy_text(rows) -> str:
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


def outlying_text(rows, name: str = "phi") -> str:
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


def how_identified(inert) -> str:
    """How the per-setting intervals were made, in a sentence or two."""
    if is_joint(inert):
        return ("the joint model of all records (one set of friction and deformation parameters, one b per setting; "
                "`joint/`): posterior median and 94 % highest-density interval.")
    if all(r.get("records", 1) <= 1 for r in inert):
        return "each setting's one record: posterior mean and its normal 94 % interval (mean +- 1.88 sd)."
    return ("each setting's records fitted one by one and combined as independent normals (the product of their "
            "posteriors): median and 94 % interval." + discrepancy_text(inert))


def combination_note(inert, joint_rows) -> str:
    """Where the per-setting b's above come from: the joint model (and then what each
    setting's records, fitted one by one and combined, give beside it), or the product of
    each setting's records (nothing to say where every setting has one record)."""
    if is_joint(inert):
        text = ("These are the joint model's b's (below): one set of friction and deformation parameters for every "
                "record and one b per setting, as the paper tuned them. Fitted one record at a time and combined per "
                "setting as independent normals (the product of their posteriors: the `b_product_*` columns of "
                "`inertance.csv`, green in the figure), the same records give " + interval_list(inert, "b_product_")
                + ".")
        if joint_rows and "b_truth" in joint_rows[0]:
            truth = {r["setting"]: r["b_truth"] for r in joint_rows}
            text += f" For those, {truth_sentence(inert, truth, 'b_product_')}."
        text += (" Each record on its own leaves open where the viscous friction acts and how stiff the nut is, and "
                 "b moves with them (below); the joint model shares them across all records, which is the paper's "
                 "model and uses every record for them." + discrepancy_text(inert))
        return text
    if all(r.get("records", 1) <= 1 for r in inert):
        return ""
    return ("These combine each setting's records as independent normals (the product of their posteriors): "
            "each record has its own frictions and deformations, so what every record leaves open and each "
            "moves b by (where the viscous friction acts, the nut's stiffness) is counted once per record. "
            "The study's joint model (`--no-joint` left it out, or it has too few records) shares them.")


def calibration_text(rows, calibration, truth_b: dict | None, prefix: str, gains=None,
                     in_posterior: bool = False) -> str:
    """What the sensors' calibration adds to b (``<prefix>hdi_*`` columns). ``gains``: the
    (load cell, accelerometer) sensitivity errors the records were generated with (None
    for a user's records); with errors and ``truth_b``, how often the widened intervals
    hold the generating b. ``in_posterior``: the fits sampled the sensors' relative gain
    (``analysis.added_calibration``), so nothing was added."""
    u = calibration.ratio_sd
    if in_posterior and u > 0:
        return (f"Each record's posterior samples the sensors' relative gain under a prior of the calibration's "
                f"{100 * u:.2g} % (the load cell's {100 * calibration.force:.2g} % and the accelerometer's "
                f"{100 * calibration.accel:.2g} %, an **assumption**: `--sensor-uncertainty`), so its intervals hold "
                f"the calibration already and nothing is added to them.")
    if not rows or f"{prefix}hdi_3%" not in rows[0]:
        return ""
    if u == 0:
        return ("The sensors' sensitivities are taken as exact (`--sensor-uncertainty 0 0`): no calibration "
                "uncertainty is added to b.")
    text = (f"These intervals take the sensors' sensitivities as exact. With the load cell's sensitivity known "
            f"to {100 * calibration.force:.2g} % and the accelerometer's to {100 * calibration.accel:.2g} % (standard "
            f"uncertainties, an **assumption**: `--sensor-uncertainty`), a record reads the same whether b or the "
            f"sensitivities' ratio is off (`records.sensitivity`), so b carries a further {100 * u:.2g} % of "
            f"b plus the moving mass that no record can reduce: the 94 % intervals widen to those of the first "
            f"table's column with sensor uncertainty.")
    if truth_b and gains is not None:
        if tuple(gains) == (1.0, 1.0):
            text += (" The records were generated with exact sensitivities, so the records-alone intervals are the "
                     "ones to hold against the generating b; these say how wide a real measurement's interval is.")
        else:
            known, missed = coverage(rows, truth_b, prefix)
            text += (f" The records were generated with a load cell reading {gains[0]:g} and an accelerometer "
                     f"{gains[1]:g} times the truth: these intervals hold the generating b for "
                     f"{len(known) - len(missed)} of {len(known)} settings.")
    return text


def regression_text(reg, joint: bool) -> str:
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


def record_coverage(recs, truth, prefix: str = "b_", label: str = "b") -> str:
    """'the 94 % intervals hold the generating <label> for n of m records (missed: ...)',
    or "" where no record has a generating value or an interval of it."""
    known, missed = coverage([r for r in recs if f"{prefix}hdi_3%" in r], truth, prefix)
    if not known:
        return ""
    missed = [r["record"] for r in missed]
    return (f"the 94 % intervals hold the generating {label} for {len(known) - len(missed)} of {len(known)} records"
            + (f" (missed: {', '.join(missed)})" if missed else ""))


def records_sentence(recs, truth_b, truth_app) -> str:
    """The per-record table's lead: how often b's and b_app's intervals hold their
    generating values, where the records were generated."""
    said = [t for t in (record_coverage(recs, truth_b), record_coverage(
        recs, truth_app, "b_app_", "b_app = b (1 + b k_n / c_n^2), the inertance seen through the nut,")) if t]
    return "Per record (`inertance_records.csv`)" + (": " + "; ".join(said) + "." if said else ":")


#: What the records cannot tell apart (``studies/ambiguity.py`` measures it on the paper's grid).
AMBIGUITY = (
    "What a record fixes is the driving-point impedance at its drive frequency, not b itself: to first order "
    "b (1 - 2 c_f2 / c_n + b k_n / c_n^2). Where the viscous friction acts (plate or rotation) and how stiff the "
    "nut is are not identified, and they move b at the same data: by 0.15 % between all the viscous friction on "
    "the rotation and all on the plate, and by 0.13 % (A0) to 3.4 % (B2 at 1.5 Hz) as the nut stiffness goes "
    "from 1e3 to 1e7 N/m (on the paper's devices: `results/sensitivity/ambiguity.csv`). b's posterior spreads "
    "along both; b_app, which takes in the nut's stiffness but not the viscous split, along the split only. "
    "A generating value at the edge of what the prior allows for them (the paper's viscous friction is all on "
    "the rotation, where b is largest) lies at the top of b's posterior, and may fall just outside its interval.")
