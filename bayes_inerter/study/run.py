"""Run a study end to end: records, fits (resumable, parallel), tables, figures, report."""

from __future__ import annotations

import dataclasses
import datetime
import json
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..device import SETTINGS, apparent_inertance, paper_parameters
from ..lock import folder_lock
from ..masses import resolve_masses
from ..records import paper_grid, read_record, write_record
from ..records.checks import b_range_for, require_physical
from ..records.drive import resolve_drive
from .analysis import (
    added_calibration,
    collect,
    contraction_table,
    flywheel_regression,
    inertance_table,
    is_joint,
    joint_estimate,
    joint_inertance,
    model_comparison,
    phi_table,
    record_table,
    write_csv,
)
from .honest import honest_columns
from .least_squares import least_squares_table, run_least_squares
from .manifest import source_commit
from .plan import StudyPlan, record_name
from .runner import run_jobs

__all__ = ["run_study", "run_joint", "StudyResult", "prepare_records"]


@dataclass
class StudyResult:
    out: Path
    outcomes: list
    tables: dict
    report: Path
    seconds: dict


def prepare_records(plan: StudyPlan, out: Path) -> dict:
    """name -> (CSV path, setting, frequency): the user's folder, or the generated grid
    (written once into ``out``/records; the same seed makes the same records)."""
    records = {}
    if plan.records_dir:
        folder = Path(plan.records_dir)
        paths = sorted(folder.glob("*.csv"))
        if not paths:
            raise ValueError(f"{folder}: no .csv records there")
        for path in paths:
            rec = read_record(path)  # refused here, before any fitting, if bad
            masses = None
            try:
                masses = resolve_masses(rec)
            except ValueError:
                pass  # the fit names the missing mass
            require_physical(rec, m_s=masses and masses.m_s, m_B=masses and masses.m_B, b_range=b_range_for(rec),
                             skip=plan.skip_checks, where=str(path))
            setting = rec.metadata.get("setting")
            setting = str(setting).upper() if setting else None
            # the metadata's drive frequency, or the record's own estimate, as its fit will use
            records[path.stem] = (path, setting if setting in SETTINGS else None, resolve_drive(rec).hz)
        return records
    folder = out / "records"
    grid = paper_grid(settings=plan.generator, seed=plan.seed, frequencies=plan.frequencies, names=plan.settings)
    for setting, freq, rec in grid:  # 0.15 s a record: regenerating is cheaper than bookkeeping
        name = record_name(setting, freq)
        path = folder / f"{name}.csv"
        if not path.exists():
            write_record(path, rec)
        records[name] = (path, setting, float(freq))
    return records


def run_joint(plan: StudyPlan, out: Path, fits: list, records: dict, *, processes: int = 1, progress=None):
    """The joint model of the study's two-port records (``plan.joint``), into
    ``out``/joint, started from each record's posterior means; an earlier run's chain
    there is continued. Only records that name their flywheel setting take part (the
    joint model has one b per setting). Returns the FitResult, or None with fewer than
    two such records."""
    from ..inference.fit import fit_joint
    from ..inference.posterior.model import PosteriorModel

    # in the records' name order: the checkpoint's digest depends on the order of the records
    chosen = sorted((f for f in fits if f.model == "two-port" and f.name in records and records[f.name][1] in SETTINGS),
                    key=lambda f: f.name)
    if len(chosen) < 2:
        return None
    recs = [read_record(records[f.name][0]) for f in chosen]
    reused = finished_joint(out / "joint", recs, plan)
    if reused is not None:
        return reused
    names = PosteriorModel(recs[0]).names
    centres = [{n: f.stat(n, "mean") for n in names} for f in chosen]
    return fit_joint(recs, out / "joint", centres=centres, steps=plan.joint_steps, seed=plan.seed,
                     processes=processes, progress=progress, plots=plan.figures)


def finished_joint(folder: Path, records, plan: StudyPlan):
    """The joint model's outputs from an earlier run into ``folder``, as a FitResult,
    if it finished converged (or with ``plan.joint_steps`` steps) on the same records with
    the same seed and today's likelihood settings and left what the tables need
    (summary.csv, fit.json, b_draws.npz); else None. A fresh clone of committed results
    thus rebuilds its tables and report without sampling the joint chain again (its
    checkpoint is not committed)."""
    import csv

    from ..inference.fit import DRAWS_FILE, FitResult, joint_records
    from ..inference.posterior.joint import JointModel

    try:
        info = json.loads((folder / "fit.json").read_text())
        with open(folder / "summary.csv", newline="") as f:
            rows = [{k: (v if k in ("name", "kind", "flag") else float(v)) for k, v in r.items()}
                    for r in csv.DictReader(f)]
        with np.load(folder / DRAWS_FILE) as npz:
            draws = {k: npz[k] for k in npz.files}
    except (OSError, ValueError, KeyError):
        return None
    from ..inference.sampling.identity import stored_likelihood

    jm = JointModel(tuple(records))
    same = (info.get("records") == joint_records(jm) and info.get("seed") == plan.seed
            and stored_likelihood(info.get("likelihood")) == dataclasses.asdict(jm.likelihood))
    ended = info.get("converged") if plan.joint_steps is None else info.get("iterations") == plan.joint_steps
    if not (same and ended):
        return None
    return FitResult(folder, rows, bool(info["converged"]), info.get("reason", ""), int(info["iterations"]),
                     np.array(list(info.get("tau", {}).values())), None, info.get("timings_s", {}), {}, "", draws,
                     tau_by_parameter=info.get("tau", {}), coordinates=info.get("coordinates", ""))


def run_study(plan: StudyPlan, out, *, processes: int = 1, scheduler: str | None = None, on_done=None,
              on_jobs=None, on_joint_step=None, on_identified=None, executor=None) -> StudyResult:
    """Run ``plan`` into ``out``: records, fits, tables (CSV), figures (PNG), REPORT.md.

    ``processes`` local worker processes (one fit each) or a Dask ``scheduler`` address.
    ``on_jobs(n)`` is told the number of fits before they start; ``on_done(outcome)``
    hears each one as it ends. Fits finished by an earlier run are reused. The joint
    model (``plan.joint``) runs here after them, its walkers on ``processes`` local
    processes (also with a scheduler); ``on_joint_step(iteration, target)`` hears its steps.
    With ``plan.identify`` every record's least-squares fit (``study.least_squares``)
    then runs on ``processes`` local processes; ``on_identified(name)`` hears each end.
    ``executor``: the fits run on it instead (``processes`` is then its workers).
    """
    import matplotlib

    matplotlib.use("Agg")

    from ..inference.fit import check_output_folder

    out = Path(out)
    check_output_folder(out)
    with folder_lock(out):
        if executor is not None:
            processes = executor.workers
        return _run_study(plan, out, processes=processes, scheduler=scheduler, on_done=on_done, on_jobs=on_jobs,
                          on_joint_step=on_joint_step, on_identified=on_identified, executor=executor)


def _run_study(plan: StudyPlan, out: Path, *, processes, scheduler, on_done, on_jobs, on_joint_step,
               on_identified, executor=None) -> StudyResult:
    """:func:`run_study`'s work, with the folder locked."""
    from ..inference.fit import versions as fit_versions  # one list of versions for fits and studies
    from .report import write_report

    commit = source_commit()  # of the source this run loaded, before its outputs change the tree
    t0 = time.perf_counter()
    records = prepare_records(plan, out)
    jobs = plan.jobs(records, out)
    if on_jobs:
        on_jobs(len(jobs))
    t1 = time.perf_counter()
    outcomes = run_jobs(jobs, processes=processes, scheduler=scheduler, on_done=on_done, plots=plan.figures,
                        executor=executor)
    t2 = time.perf_counter()
    fits = collect(out / "fits")
    joint = run_joint(plan, out, fits, records, processes=processes, progress=on_joint_step) if plan.joint else None
    t_joint = time.perf_counter()
    ls = (run_least_squares(records, out, seed=plan.seed, processes=processes, on_done=on_identified)
          if plan.identify else None)
    t_ls = time.perf_counter()
    truth_b, truth_app = _truths(plan, records)
    tables, files = _tables(plan, fits, joint, truth_b, truth_app)
    if ls:
        tables["least_squares"] = least_squares_table(ls, fits, truth_b)
        files["least_squares"] = "least_squares.csv"
    for key, name in files.items():
        write_csv(out / name, tables[key])
    _write_figures(out, tables)
    versions = fit_versions()
    report = write_report(out, plan, tables, outcomes, versions, truth_b, truth_app)
    t3 = time.perf_counter()
    seconds = {"records": t1 - t0, "fits": t2 - t1, "joint": t_joint - t2, "least_squares": t_ls - t_joint,
               "analysis_and_report": t3 - t_ls, "total": t3 - t0}
    _write_study_json(out, plan, versions, seconds, processes, scheduler, outcomes, commit)
    return StudyResult(out, outcomes, tables, report, seconds)


def _truths(plan: StudyPlan, records: dict | None = None):
    """(b, b_app) per setting of the generated records, which are made with the paper's
    parameters. A folder's records have a truth only where every record of a setting
    carries the same generating b in its metadata (``true_parameters``, as records made
    by ``bayes-inerter generate`` do, paper-like ones included); a measured record has
    none, and (None, None) is returned when no setting has one."""
    if not plan.records_dir:
        truth = {s: paper_parameters(s) for s in plan.settings}
        return ({s: p.b for s, p in truth.items()},
                {s: apparent_inertance(p.b, p.k_n, p.c_n) for s, p in truth.items()})
    found: dict[str, set] = {}
    for path, setting, _ in (records or {}).values():
        if setting is None:
            continue
        true = read_record(path).metadata.get("true_parameters")
        key = (float(true["b"]), float(true["k_n"]), float(true["c_n"])) if isinstance(true, dict) and {
            "b", "k_n", "c_n"} <= set(true) else None
        found.setdefault(setting, set()).add(key)
    known = {s: next(iter(keys)) for s, keys in found.items() if len(keys) == 1 and None not in keys}
    if not known:
        return None, None
    return ({s: b for s, (b, _, _) in known.items()},
            {s: apparent_inertance(b, k, c) for s, (b, k, c) in known.items()})


def _tables(plan: StudyPlan, fits: list, joint, truth_b, truth_app) -> tuple[dict, dict]:
    """The study's tables by name, and the CSV file each one is written to (``joint_info``
    is for the report only)."""
    cal = added_calibration(fits, plan.calibration)  # None where the posteriors hold it
    inert = inertance_table(fits, calibration=cal)  # each setting's records combined (product of normals)
    tables = {"records": record_table(fits), "phi": phi_table(fits), "models": model_comparison(fits),
              "contraction": contraction_table(fits), "calibration_in_posterior": cal is None}
    files = {"records": "inertance_records.csv", "inertance": "inertance.csv", "regression": "flywheels.csv",
             "phi": "phi.csv", "models": "model_comparison.csv", "contraction": "contraction.csv"}
    draws = None
    if joint is not None:
        tables["joint"] = joint_inertance(joint.summary, inert, truth_b=truth_b, truth_app=truth_app, calibration=cal)
        tables["joint_info"] = {"converged": joint.converged, "reason": joint.reason, "iterations": joint.iterations}
        # the regression of the product's b's, to set beside the joint model's
        tables["product_regression"] = flywheel_regression(inert, truth_b=truth_b, calibration=cal)
        files.update(joint="joint_inertance.csv", product_regression="flywheels_product.csv")
        inert = joint_estimate(inert, joint.draws, joint.converged, calibration=cal)
        if is_joint(inert):  # every setting's b jointly sampled: regress the draws
            draws = np.column_stack([np.ravel(joint.draws[f"b_{r['setting']}"]) for r in inert])
    tables["inertance"] = honest_columns(inert, fits, cal, truth_b)
    tables["regression"] = flywheel_regression(inert, truth_b=truth_b, calibration=cal, draws=draws)
    return tables, files


def _write_figures(out: Path, tables: dict) -> None:
    """The study's figures beside its tables, each closed once saved."""
    import matplotlib.pyplot as plt

    from .plots import plot_inertance, plot_least_squares, plot_models, plot_phi_map

    figures = {"theory_vs_identified.png": (plot_inertance, tables["inertance"]),
               "phi_map.png": (plot_phi_map, tables["phi"]), "model_comparison.png": (plot_models, tables["models"]),
               "least_squares.png": (plot_least_squares, tables.get("least_squares"))}
    for name, (plot, rows) in figures.items():
        if rows:
            fig = plot(rows)
            try:
                fig.savefig(out / name, dpi=110)
            finally:
                plt.close(fig)


def _write_study_json(out: Path, plan: StudyPlan, versions: dict, seconds: dict, processes, scheduler,
                      outcomes: list, commit: str | None) -> None:
    """study.json: the plan, versions, timings and outcomes, and every run into the folder
    with the commit of the source it ran (``manifest.source_commit`` when the run began:
    None outside a clone)."""
    this_run = {**_run_entry(datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"), seconds,
                             processes, outcomes), "commit": commit}
    plan_dict = dataclasses.asdict(plan)
    if plan.records_dir:  # no machine's path in a file that may be committed: relative to the working folder
        plan_dict["records_dir"] = _portable(plan.records_dir)
    info = {"plan": plan_dict, "versions": versions, "seconds": seconds,
            "processes": processes, "scheduler": scheduler,
            "outcomes": [{k: v for k, v in o.items() if k != "job"} for o in outcomes],
            # every run into this folder, oldest first: a run that reuses finished fits
            # takes seconds, and must not hide the time the sampling took
            "runs": _earlier_runs(out / "study.json") + [this_run]}
    (out / "study.json").write_text(json.dumps(info, indent=2, default=str) + "\n")


def _portable(path) -> str:
    """``path`` relative to the working folder where it lies inside it (as ``--records``
    takes it from there), else as given."""
    import os

    p = Path(path)
    try:
        return Path(os.path.relpath(p.resolve(), Path.cwd().resolve())).as_posix() if p.resolve().is_relative_to(
            Path.cwd().resolve()) else str(path)
    except (OSError, ValueError):
        return str(path)


def _earlier_runs(path: Path) -> list:
    """The ``runs`` of an earlier study.json in the folder (one entry made from its
    ``seconds`` if it predates the list); none if there is none or it cannot be read."""
    try:
        info = json.loads(path.read_text())
    except (OSError, ValueError):
        return []
    if not isinstance(info, dict):
        return []
    runs = info.get("runs")
    if isinstance(runs, list):
        return runs
    if isinstance(info.get("seconds"), dict):
        return [_run_entry(None, info["seconds"], info.get("processes"), info.get("outcomes") or [])]
    return []


def _run_entry(finished, seconds: dict, processes, outcomes: list) -> dict:
    """One entry of study.json's ``runs``: when it finished, its timings, and how many
    fits it sampled and reused."""
    return {"finished": finished, "seconds": seconds, "processes": processes,
            "sampled": sum(o.get("status") == "done" for o in outcomes),
            "reused": sum(o.get("status") == "skipped" for o in outcomes)}
