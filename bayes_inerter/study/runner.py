"""Run many fit jobs: on local worker processes (default) or on a Dask cluster.

Each finished job leaves ``done.json`` in its folder (the job's settings and what came
out); running the study again skips a job whose ``done.json`` matches it, and a job that
was interrupted continues its emcee checkpoint (``fit_record`` does that). A job that
fails, or whose worker process dies, is reported as failed and the others go on.

Local runs give every job a process of its own (at most ``processes`` at a time), so a
worker that dies takes only its own job with it.
"""

from __future__ import annotations

import dataclasses
import json
import functools
import time
from pathlib import Path

from ..executor import Dask, Executor, LocalProcesses, WorkerDied
from ..inference.summaries.results import LOO_FILE
from ..inference.sampling.tempering import Tempering, default_convergence
from .plan import FitJob

__all__ = ["run_job", "run_jobs", "finished", "DONE_FILE"]

DONE_FILE = "done.json"


#: What a finished fit must still have for the study's tables: these, and where its
#: record is fitted by several models (the model comparison), its LOO
#: (:data:`LOO_SOURCES`: ``loo.json``, committed with results, or ``posterior.nc``, which
#: is not), so a fresh clone of committed results reuses their fits.
NEEDED = ("summary.csv", "fit.json")
LOO_SOURCES = (LOO_FILE, "posterior.nc")


def finished(job: FitJob, needs_loo: bool = True) -> dict | None:
    """The outcome recorded by an earlier run of ``job``, if it finished with the same
    settings and the outputs the study needs are all still there (its LOO only if
    ``needs_loo``)."""
    folder = Path(job.out)
    if not all((folder / name).is_file() for name in NEEDED):
        return None
    if needs_loo and not any((folder / name).is_file() for name in LOO_SOURCES):
        return None
    try:
        done = json.loads((folder / DONE_FILE).read_text())
    except (OSError, ValueError):
        return None
    return done if _same_job(done.get("job"), job) else None


def _same_job(recorded, job: FitJob) -> bool:
    """Whether ``recorded`` (a done.json's job) is ``job``: the same settings and the same
    record file name. Paths are compared by name, not as written: a study run with
    ``--out results/full`` and one with that folder's absolute path, or a fresh clone
    in another place, are the same study."""
    if not isinstance(recorded, dict):
        return False
    # a job recorded before these options was untempered, with fit's own cap
    recorded = {"tempering": None, "max_steps": None, **recorded}
    want = dataclasses.asdict(job)
    names = ("record", "out")
    if {k: v for k, v in recorded.items() if k not in names} != {k: v for k, v in want.items() if k not in names}:
        return False
    return all(isinstance(recorded.get(k), str) and Path(recorded[k]).name == Path(want[k]).name for k in names)


def run_job(job: FitJob, plots: bool = True) -> dict:
    """Fit one job (in the calling process) and record its outcome in ``done.json``;
    ``plots``: draw the fit's figures too (``fit_record``)."""
    from ..inference import fit_record
    from ..records import read_record

    t0 = time.perf_counter()
    rec = read_record(job.record)
    tempering = Tempering.of(job.tempering)
    convergence = (None if job.max_steps is None
                   else dataclasses.replace(default_convergence(tempering), max_steps=job.max_steps))
    res = fit_record(rec, job.out, model=job.model, steps=job.steps, walkers=job.walkers, seed=job.seed,
                     processes=1, plots=plots, tempering=tempering, convergence=convergence)
    outcome = {
        "key": job.key, "status": "done", "converged": bool(res.converged), "reason": res.reason,
        "iterations": int(res.iterations), "seconds": time.perf_counter() - t0,
        "timings": {k: float(v) for k, v in res.timings.items()},
        "job": dataclasses.asdict(job),
    }
    (Path(job.out) / DONE_FILE).write_text(json.dumps(outcome, indent=2) + "\n")
    return outcome


def _failed(job: FitJob, error: str) -> dict:
    return {"key": job.key, "status": "failed", "error": error, "job": dataclasses.asdict(job)}


def _run(jobs, executor: Executor, on_done, plots: bool) -> list[dict]:
    """Each job on ``executor``, in a worker process of its own where it runs locally; a
    job that fails, or whose worker dies, is reported as failed and the others go on."""
    outcomes = []
    for got in executor.as_completed(functools.partial(run_job, plots=plots), jobs):
        job = jobs[got.index]
        outcome = got.value if got.ok else _failed(job, _message(got.error))
        outcomes.append(outcome)
        on_done(outcome)
    return outcomes


def _message(error: BaseException) -> str:
    """A failed job's error as done.json and the study's report name it; a worker that
    died says so with its exit code."""
    if isinstance(error, WorkerDied):
        return str(error)
    return f"{type(error).__name__}: {error}"


def run_jobs(jobs, *, processes: int = 1, scheduler: str | None = None, on_done=None,
             plots: bool = False, executor: Executor | None = None) -> list[dict]:
    """Run the jobs not finished before; return one outcome per job (in job order).
    ``plots``: each fit draws its figures too.

    ``processes``: local worker processes at a time; ``scheduler``: the address of a
    Dask scheduler (``tcp://host:port``) to run them there instead; ``executor``: an
    executor to run them on, in place of both (left open). ``on_done`` is called with
    each outcome as it comes (skipped ones first).
    """
    if processes < 1:
        raise ValueError(f"processes must be at least 1, got {processes}")
    on_done = on_done or (lambda outcome: None)
    outcomes = {}
    todo = []
    models = {}
    for job in jobs:
        models[job.record] = models.get(job.record, 0) + 1
    for job in jobs:
        done = finished(job, needs_loo=models[job.record] > 1)
        if done is not None:
            outcomes[job.key] = {**done, "status": "skipped"}
            on_done(outcomes[job.key])
        else:
            todo.append(job)
    if executor is not None:
        ran = _run(todo, executor, on_done, plots)
    else:  # locally, every job runs in a process of its own, one process at a time included
        with (Dask(scheduler) if scheduler else LocalProcesses(processes)) as mine:
            ran = _run(todo, mine, on_done, plots)
    outcomes.update((o["key"], o) for o in ran)
    return [outcomes[job.key] for job in jobs]
