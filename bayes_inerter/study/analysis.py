"""From a study's finished fits to its tables: inertance per setting against theory,
the inertance added per flywheel, the fit accuracy phi against the paper's Table 2,
model comparison, and what the data identify.

b per setting: where the study ran the joint model (one set of frictions and
deformations for all records, one b per setting: the paper's model), ``inertance.csv``
gives its b (``joint_estimate``), with each setting's records combined one by one
beside it (``b_product_*``); without it, that combination.

Combining records one by one: each record's posterior is sampled on its own (its own
frictions and deformations). A setting's inertance from its records at several
frequencies is their product, taken in a normal approximation (precision-weighted mean
and sd of the per-record posteriors); a chi-square of the per-record means about it
says whether they agree, and where they disagree by more than their sds allow
(chi-square above its degrees of freedom) the combined sd is scaled up by the Birge
ratio sqrt(chi2 / (records - 1)), the Particle Data Group's rule for averaging
discrepant measurements: their sds are then taken to be too small by a common factor.
(A chi-square far beyond that, p < 1 %, says more: b may change with the frequency; the
report flags it.)

The increments per flywheel come from a weighted least-squares regression of the
per-setting b's on the numbers of small and big flywheels: of every joint posterior
draw where there is one (the b's are correlated through the shared parameters), else of
the per-setting normals (a normal posterior under flat priors).

The sensors' calibration (``records.sensitivity.SensorCalibration``) is what no record
can check: with one, every table also gives b's sd and 94 % interval with the
calibration's share added (``b_cal_*`` columns, ``cal_*`` in the regression; normal
intervals, mean +- 1.88 sd), beside the records-alone ones. A share is ``u`` times the
inertance plus the moving mass m_s + m_B; for the regression's terms, ``u`` times the
term plus the same regression of the moving masses (m_s grows with the flywheels).
"""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np

from ..device import DEFAULT_GEOMETRY, SETTINGS, theoretical_inertance
from ..inference.summaries.results import hdi
from ..records.sensitivity import SensorCalibration
from .fits import RecordFit, collect, fit_loo  # the tables' input, named here as before

__all__ = ["read_csv", "TEXT_COLUMNS", "RecordFit", "birge_ratio", "collect", "added_calibration", "inertance_table", "is_joint", "joint_estimate", "joint_inertance",
           "record_table",
           "flywheel_regression", "phi_table", "model_comparison", "fit_loo", "contraction_table", "write_csv", "Z94"]

#: Half-width of a central 94 % interval of a normal, in sd.
Z94 = 1.880793608151251


def _normal(fit: RecordFit) -> tuple[float, float]:
    """Mean and sd of b (kg) from a fit's summary."""
    return fit.stat("b", "mean"), fit.stat("b", "sd")


def record_table(fits: list[RecordFit]) -> list[dict]:
    """b, b_app (the inertance seen through the nut, which the records fix more tightly
    than b: ``device.apparent_inertance``) and phi of every two-port fit, one row per record."""
    rows = []
    for f in fits:
        if f.model != "two-port":
            continue
        rows.append({
            "record": f.name, "setting": f.setting, "freq_hz": f.freq,
            "b_mean": f.stat("b", "mean"), "b_sd": f.stat("b", "sd"),
            "b_hdi_3%": f.stat("b", "hdi_3%"), "b_hdi_97%": f.stat("b", "hdi_97%"), "b_r_hat": f.stat("b", "r_hat"),
            "phi_mean": f.stat("phi", "mean"), "phi_hdi_3%": f.stat("phi", "hdi_3%"),
            "phi_hdi_97%": f.stat("phi", "hdi_97%"), "converged": f.converged,
            "iterations": int(f.info["iterations"]),
        })
        if "b_app" in f.summary:
            rows[-1].update({f"b_app_{c}": f.stat("b_app", c) for c in ("mean", "hdi_3%", "hdi_97%")})
    return rows


def _combine(normals):
    """Product of normals: mean, sd, and the chi-square of the means about it."""
    means = np.array([m for m, _ in normals])
    prec = np.array([1.0 / s**2 for _, s in normals])
    mean = float(np.sum(prec * means) / np.sum(prec))
    chi2 = float(np.sum(prec * (means - mean) ** 2))
    return mean, float(1.0 / math.sqrt(np.sum(prec))), chi2


def birge_ratio(chi2: float, n: int) -> float:
    """sqrt(chi2 / (n - 1)) when n values disagree by more than their sds allow, else 1
    (one value, or chi2 no larger than its degrees of freedom)."""
    return math.sqrt(chi2 / (n - 1)) if n > 1 and chi2 > n - 1 else 1.0


def _moving_mass(f: RecordFit) -> float:
    """m_s + m_B of a fit's record (kg), from its fit.json; nan when it does not say."""
    try:
        return float(f.info["m_s"]) + float(f.info["m_B"])
    except (KeyError, TypeError, ValueError):
        return math.nan


def _with_calibration(row: dict, calibration: SensorCalibration | None, mean: float, sd: float, mass: float,
                      prefix: str, truth: float | None = None) -> None:
    """Add ``<prefix>sd``, ``<prefix>hdi_3%``, ``<prefix>hdi_97%`` (and ``covers_truth_cal``
    with ``truth``) of an inertance of posterior ``mean`` and ``sd`` with the calibration's
    share for ``mass`` kg of moving mass (nan when the mass is unknown: then so are they)."""
    if calibration is None:
        return
    total = calibration.inertance_sd(mean, sd, mass)
    row.update({f"{prefix}sd": total, f"{prefix}hdi_3%": mean - Z94 * total, f"{prefix}hdi_97%": mean + Z94 * total})
    if truth is not None:
        row["covers_truth_cal"] = bool(abs(mean - truth) <= Z94 * total)


def added_calibration(fits: list[RecordFit], calibration: SensorCalibration | None) -> SensorCalibration | None:
    """The sensors' calibration to add to the two-port fits' b, or None where every one of
    them sampled the sensors' relative gain (a ``gain`` row in its summary: the harmonic
    and motion-in likelihoods), whose posterior then holds the calibration already;
    adding it again would count it twice."""
    two_port = [f for f in fits if f.model == "two-port"]
    if two_port and all("gain" in f.summary for f in two_port):
        return None
    return calibration


def inertance_table(fits: list[RecordFit], geometry=None, calibration: SensorCalibration | None = None) -> list[dict]:
    """Per setting: theory, the paper's identified b, and the posterior (all its records).

    Columns ``setting, b_theory, b_paper, b_median, b_hdi_3%, b_hdi_97%`` (the normal
    approximation's median and central 94 % interval), then ``b_sd``, ``records``,
    ``chi2`` (of the per-record means about the combined one; about records - 1 when
    they agree), ``scale`` (the Birge ratio the sd was multiplied by, 1 when they
    agree: see the module docstring), ``converged`` (all its chains) and
    ``moving_mass`` (m_s + m_B of its records, kg). With ``calibration``:
    ``b_cal_sd``, ``b_cal_hdi_3%``, ``b_cal_hdi_97%`` (the sensors' share added).
    """
    by_setting = {}
    for f in fits:
        if f.model == "two-port" and f.setting in SETTINGS:
            by_setting.setdefault(f.setting, []).append(f)
    rows = []
    for name in SETTINGS:
        group = by_setting.get(name)
        if not group:
            continue
        mean, sd, chi2 = _combine([_normal(f) for f in group])
        scale = birge_ratio(chi2, len(group))
        sd *= scale
        rows.append({
            "setting": name, "b_theory": theoretical_inertance(name, geometry), "b_paper": SETTINGS[name].b_paper,
            "b_median": mean, "b_hdi_3%": mean - Z94 * sd, "b_hdi_97%": mean + Z94 * sd, "b_sd": sd,
            "records": len(group), "chi2": chi2, "scale": scale, "converged": all(f.converged for f in group),
            "moving_mass": float(np.mean([_moving_mass(f) for f in group])),
        })
        _with_calibration(rows[-1], calibration, mean, sd, rows[-1]["moving_mass"], "b_cal_")
    return rows


def joint_inertance(joint_rows: list[dict], inertance: list[dict], truth_b: dict | None = None,
                    truth_app: dict | None = None, calibration: SensorCalibration | None = None) -> list[dict]:
    """Per setting, the joint model's b (posterior mean, sd, 94 % HDI) beside theory and
    the single-record combination (``inertance``'s ``b_median``, taken before
    ``joint_estimate``). ``covers_truth`` with ``truth_b``.
    Where the joint summary has the apparent inertance ``b_app_<setting>``
    (``device.apparent_inertance``): its mean and 94 % HDI, and with ``truth_app`` (its
    generating values) ``b_app_truth`` and ``covers_truth_app``. With ``calibration``:
    ``b_joint_cal_sd`` and the 94 % interval ``b_joint_cal_hdi_3%``, ``b_joint_cal_hdi_97%``
    (normal, the sensors' share added; ``covers_truth_cal`` with ``truth_b``)."""
    by_name = {r["name"]: r for r in joint_rows}
    rows = []
    for row in inertance:
        j = by_name.get(f"b_{row['setting']}")
        if j is None:
            continue
        out = {"setting": row["setting"], "b_theory": row["b_theory"], "b_joint_mean": float(j["mean"]),
               "b_joint_sd": float(j["sd"]), "b_joint_hdi_3%": float(j["hdi_3%"]),
               "b_joint_hdi_97%": float(j["hdi_97%"]), "r_hat": float(j["r_hat"]), "ess_bulk": float(j["ess_bulk"]),
               "b_single_median": row["b_median"]}
        if truth_b and row["setting"] in truth_b:
            t = truth_b[row["setting"]]
            out.update(b_truth=t, covers_truth=bool(out["b_joint_hdi_3%"] <= t <= out["b_joint_hdi_97%"]))
        _with_calibration(out, calibration, out["b_joint_mean"], out["b_joint_sd"], row.get("moving_mass", math.nan),
                          "b_joint_cal_", out.get("b_truth"))
        app = by_name.get(f"b_app_{row['setting']}")
        if app is not None:
            out.update({"b_app_joint_mean": float(app["mean"]), "b_app_joint_hdi_3%": float(app["hdi_3%"]),
                        "b_app_joint_hdi_97%": float(app["hdi_97%"])})
            if truth_app and row["setting"] in truth_app:
                t = truth_app[row["setting"]]
                out.update(b_app_truth=t,
                           covers_truth_app=bool(out["b_app_joint_hdi_3%"] <= t <= out["b_app_joint_hdi_97%"]))
        rows.append(out)
    return rows


#: The columns of the records' combination that ``joint_estimate`` keeps beside the joint model's b.
PRODUCT_COLUMNS = ("b_median", "b_hdi_3%", "b_hdi_97%", "b_sd")


def joint_estimate(inertance: list[dict], draws: dict, converged: bool,
                   calibration: SensorCalibration | None = None) -> list[dict]:
    """The rows of ``inertance`` (``inertance_table``: each setting's records combined as a
    product of normals) with b from the joint model instead, the model the study is run
    for: one set of frictions and deformations for all records, one b per setting.

    ``draws``: ``b_<setting>`` -> the joint chain's kept draws of that b (any shape).
    ``b_median``, ``b_hdi_3%``, ``b_hdi_97%`` (94 % HDI) and ``b_sd`` are then the joint
    posterior's, ``estimate`` is ``"joint"`` and ``converged`` the joint chain's; the
    product's values move to ``b_product_median`` ... ``b_product_sd`` (``records``,
    ``chi2`` and ``scale`` stay: they describe the product). With ``calibration`` the
    ``b_cal_*`` columns are recomputed about the joint b. Settings the joint model does not
    have keep the product (``estimate`` ``"records combined"``).
    """
    out = []
    for row in inertance:
        row = dict(row, estimate="records combined")
        x = draws.get(f"b_{row['setting']}")
        if x is not None:
            x = np.asarray(x, dtype=float).ravel()
            lo, hi = hdi(x)
            row.update({f"b_product_{c[2:]}": row[c] for c in PRODUCT_COLUMNS})
            row.update({"b_median": float(np.median(x)), "b_hdi_3%": float(lo), "b_hdi_97%": float(hi),
                        "b_sd": float(np.std(x, ddof=1)), "estimate": "joint", "converged": bool(converged)})
            _with_calibration(row, calibration, float(np.mean(x)), row["b_sd"], row["moving_mass"], "b_cal_")
        out.append(row)
    return out


def is_joint(rows: list[dict]) -> bool:
    """Whether every row's b is the joint model's (``joint_estimate``); False for no rows."""
    return bool(rows) and all(r.get("estimate") == "joint" for r in rows)


def _design(settings: list[str], geometry):
    """The regression's terms (name, column, geometric value) that ``settings`` can
    separate and their design matrix; None where they cannot separate any."""
    ns = np.array([SETTINGS[s].n_small for s in settings], dtype=float)
    nb = np.array([SETTINGS[s].n_big for s in settings], dtype=float)
    terms = [("base (A0)", np.ones_like(ns), geometry.inertance(0, 0))]
    if np.any(ns > 0):
        terms.append(("per small flywheel", ns, geometry.inertance(1, 0) - geometry.inertance(0, 0)))
    if np.any(nb > 0):
        terms.append(("per big flywheel", nb, geometry.inertance(0, 1) - geometry.inertance(0, 0)))
    X = np.column_stack([t[1] for t in terms])
    if np.linalg.matrix_rank(X) < X.shape[1]:
        return None
    return terms, X


def flywheel_regression(inertance: list[dict], geometry=None, truth_b: dict | None = None,
                        calibration: SensorCalibration | None = None, draws: np.ndarray | None = None) -> list[dict]:
    """Base, per-small and per-big-flywheel inertance: posterior against geometry.

    A weighted least-squares regression of the rows' b (``b_median``, weights
    ``1 / b_sd^2``) on the numbers of small and big flywheels. Only the terms the
    settings can separate are estimated: the small (big) increment needs a setting with
    small (big) flywheels, and the base needs more settings than increments.

    Without ``draws`` the rows' b are taken as independent normals and so are the terms
    (a normal posterior under flat priors; intervals mean +- 1.88 sd). With ``draws``,
    jointly sampled b's of the rows, shape (draws, rows) (the joint model's): every draw
    is regressed, and each term's mean, sd and 94 % HDI are those of its draws, which keeps
    the b's correlation (the joint model's b's share the frictions and the nut, and
    correlate up to 0.98 on the full study) that the normal form leaves out.

    With ``truth_b`` (setting -> the b its records were generated with), the same
    regression of those values is given as ``truth`` and whether the interval holds it
    (``covers_truth``). With ``calibration``: ``cal_sd``, ``cal_hdi_3%``, ``cal_hdi_97%``
    (and ``covers_truth_cal``), the sensors' share added (normal): ``u`` times the term
    plus the same regression of the rows' ``moving_mass`` (nan where a row has none).
    """
    geometry = geometry or DEFAULT_GEOMETRY
    if not inertance:
        return []
    design = _design([r["setting"] for r in inertance], geometry)
    if design is None:
        return []
    terms, X = design
    w = 1.0 / np.array([r["b_sd"] for r in inertance]) ** 2
    cov = np.linalg.inv(X.T @ (w[:, None] * X))
    project = cov @ (X.T * w)  # terms = project @ b
    if draws is None:
        coef = project @ np.array([r["b_median"] for r in inertance])
        spread = [(float(c), math.sqrt(v), c - Z94 * math.sqrt(v), c + Z94 * math.sqrt(v))
                  for c, v in zip(coef, np.diag(cov))]
    else:
        draws = np.asarray(draws, dtype=float)
        if draws.ndim != 2 or draws.shape[1] != len(inertance):
            raise ValueError(f"draws: shape (draws, {len(inertance)}) wanted, got {draws.shape}")
        coef_draws = draws @ project.T  # (draws, terms)
        spread = [(float(np.mean(c)), float(np.std(c, ddof=1)), *hdi(c))
                  for c in coef_draws.T]
    truth = None
    if truth_b and all(r["setting"] in truth_b for r in inertance):
        truth = project @ np.array([truth_b[r["setting"]] for r in inertance])
    # b = r (b_id + m) - m for every setting, so each term's share is u (term + that term of m's regression)
    mass_coef = project @ np.array([r.get("moving_mass", math.nan) for r in inertance], dtype=float)
    rows = []
    for k, ((name, _, theory), (mean, sd, lo, hi)) in enumerate(zip(terms, spread)):
        row = {"term": name, "theory": theory, "mean": mean, "sd": sd, "hdi_3%": lo, "hdi_97%": hi,
               "covers_theory": bool(lo <= theory <= hi)}
        if truth is not None:
            row.update(truth=float(truth[k]), covers_truth=bool(lo <= truth[k] <= hi))
        _with_calibration(row, calibration, mean, sd, float(mass_coef[k]), "cal_",
                          None if truth is None else float(truth[k]))
        rows.append(row)
    return rows


def phi_table(fits: list[RecordFit]) -> list[dict]:
    """The fit accuracy phi per record (two-port), beside the paper's Table 2."""
    rows = []
    for f in fits:
        if f.model != "two-port":
            continue
        paper = SETTINGS[f.setting].fit_paper.get(f.freq) if f.setting in SETTINGS else None
        rows.append({"setting": f.setting, "freq_hz": f.freq, "phi_mean": f.stat("phi", "mean"),
                     "phi_hdi_3%": f.stat("phi", "hdi_3%"), "phi_hdi_97%": f.stat("phi", "hdi_97%"),
                     "phi_paper": paper})
    return rows


def model_comparison(fits: list[RecordFit]) -> list[dict]:
    """Per record fitted with several models: LOO (arviz, ``fit_loo``) and phi of each."""
    by_record = {}
    for f in fits:
        by_record.setdefault(f.name, []).append(f)
    rows = []
    paper = {"linear": 0.49, "rigid": 0.65, "two-port": 0.75}
    for name, group in sorted(by_record.items()):
        if len(group) < 2:
            continue
        for f in sorted(group, key=lambda g: list(paper).index(g.model)):
            loo = fit_loo(f)
            rows.append({"record": name, "model": f.model, "elpd_loo": loo["elpd_loo"], "elpd_se": loo["elpd_se"],
                         "p_loo": loo["p_loo"], "pareto_k_max": loo["pareto_k_max"], "phi_mean": f.stat("phi", "mean"),
                         "phi_paper_overall": paper[f.model], "converged": f.converged})
    return rows


def contraction_table(fits: list[RecordFit]) -> list[dict]:
    """Posterior contraction of every sampled quantity, per two-port fit (from fit.json)."""
    rows = []
    for f in fits:
        if f.model == "two-port" and f.info.get("contraction"):
            rows.append({"record": f.name, **{k: round(float(v), 3) for k, v in f.info["contraction"].items()}})
    return rows


def write_csv(path: Path, rows: list[dict], fields=None) -> None:
    """``rows`` as CSV, floats to 6 significant digits, the columns every key of the rows
    in the order they first come; with no rows the header of ``fields`` alone (an empty
    file where none are given)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as f:
        if not rows and not fields:
            return
        w = csv.DictWriter(f, fieldnames=list(dict.fromkeys(k for r in rows for k in r)) if rows else list(fields))
        w.writeheader()
        for row in rows:
            w.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in row.items()})


#: Columns :func:`read_csv` keeps as text, whatever they hold.
TEXT_COLUMNS = ("setting", "record")


def read_csv(path) -> list[dict]:
    """The rows of a table this package wrote, as numbers where they are: floats,
    "True"/"False" as booleans, an empty cell as None; :data:`TEXT_COLUMNS` as text."""
    def value(v):
        if v in ("True", "False"):
            return v == "True"
        try:
            return float(v)
        except ValueError:
            return v or None

    with open(path, newline="") as f:
        return [{k: (v if k in TEXT_COLUMNS else value(v)) for k, v in r.items()} for r in csv.DictReader(f)]
