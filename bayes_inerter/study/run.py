"""Run a study end to end: records, fits (resumable, parallel), tables, figures, report."""

from __future__ import annotations

import dataclasses
import json
import time
from dataclasses import dataclass
from pathlib import Path

from ..device import SETTINGS, paper_parameters
from ..records import paper_grid, read_record, write_record
from .analysis import (collect, contraction_table, flywheel_regression, inertance_table, model_comparison,
                       phi_table, record_table, write_csv)
from .plan import StudyPlan, record_name
from .runner import run_jobs

__all__ = ["run_study", "StudyResult", "prepare_records"]


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
            setting = rec.metadata.get("setting")
            setting = str(setting).upper() if setting else None
            records[path.stem] = (path, setting if setting in SETTINGS else None, rec.drive_frequency)
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


def run_study(plan: StudyPlan, out, *, processes: int = 1, scheduler: str | None = None, on_done=None,
              on_jobs=None) -> StudyResult:
    """Run ``plan`` into ``out``: records, fits, tables (CSV), figures (PNG), REPORT.md.

    ``processes`` local worker processes (one fit each) or a Dask ``scheduler`` address.
    ``on_jobs(n)`` is told the number of fits before they start; ``on_done(outcome)``
    hears each one as it ends. Fits finished by an earlier run are reused.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from ..inference.fit import check_output_folder
    from ..inference.fit import versions as fit_versions  # one list of versions for fits and studies
    from .plots import plot_inertance, plot_models, plot_phi_map
    from .report import write_report

    out = Path(out)
    check_output_folder(out)
    t0 = time.perf_counter()
    records = prepare_records(plan, out)
    jobs = plan.jobs(records, out)
    if on_jobs:
        on_jobs(len(jobs))
    t1 = time.perf_counter()
    outcomes = run_jobs(jobs, processes=processes, scheduler=scheduler, on_done=on_done)
    t2 = time.perf_counter()
    fits = collect(out / "fits")
    inert = inertance_table(fits)
    truth_b = None if plan.records_dir else {s: paper_parameters(s).b for s in plan.settings}
    tables = {
        "records": record_table(fits), "inertance": inert, "regression": flywheel_regression(inert, truth_b=truth_b),
        "phi": phi_table(fits), "models": model_comparison(fits), "contraction": contraction_table(fits),
    }
    files = {"records": "inertance_records.csv", "inertance": "inertance.csv", "regression": "flywheels.csv",
             "phi": "phi.csv", "models": "model_comparison.csv", "contraction": "contraction.csv"}
    for key, name in files.items():
        write_csv(out / name, tables[key])
    figures = {"theory_vs_identified.png": (plot_inertance, inert), "phi_map.png": (plot_phi_map, tables["phi"]),
               "model_comparison.png": (plot_models, tables["models"])}
    for name, (plot, rows) in figures.items():
        if rows:
            fig = plot(rows)
            fig.savefig(out / name, dpi=110)
            plt.close(fig)
    versions = fit_versions()
    report = write_report(out, plan, tables, outcomes, versions, truth_b)
    t3 = time.perf_counter()
    seconds = {"records": t1 - t0, "fits": t2 - t1, "analysis_and_report": t3 - t2, "total": t3 - t0}
    info = {"plan": dataclasses.asdict(plan), "versions": versions, "seconds": seconds,
            "processes": processes, "scheduler": scheduler,
            "outcomes": [{k: v for k, v in o.items() if k != "job"} for o in outcomes]}
    (out / "study.json").write_text(json.dumps(info, indent=2, default=str) + "\n")
    return StudyResult(out, outcomes, tables, report, seconds)
