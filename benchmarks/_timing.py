"""Shared by the benchmarks: the median wall time of a call, a point where the log
posterior is finite to time it at, and a row of results written with the commit,
machine and date it was measured on."""

import csv
import datetime
import subprocess
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
PERFORMANCE = ROOT / "results" / "performance"


#: The plate mode's damping ratio a timed point takes where the model samples it: Table
#: I's c_B is a ratio of about 8e-6, outside the physical prior (0.5 to 10 %), where the
#: log posterior is -inf and returns before the likelihood is computed.
ZETA_B = 0.02


def supported_theta(model, params, sigma=3e-3, rho=0.5):
    """theta of ``model`` (a ``PosteriorModel``) at ``params``, the plate mode's damping
    ratio at :data:`ZETA_B` where the model samples it; the script stops if the log
    posterior there is not finite (a timing of it would time nothing)."""
    theta = model.to_theta(params, sigma, rho)
    if "zeta_B" in model.names:
        log_scale = model.all_priors["zeta_B"].log_scale
        theta[model.names.index("zeta_B")] = np.log(ZETA_B) if log_scale else ZETA_B
    if not np.isfinite(model.log_prob(theta)[0]):
        raise SystemExit("error: the log posterior is not finite at the point to time; the benchmark needs updating")
    return theta


def median_time(fn, repeats=30):
    """Median seconds of ``repeats`` calls of ``fn`` after one warm-up call."""
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def _commit() -> str:
    """The checkout's short commit, ``-dirty`` where tracked files have uncommitted changes."""
    def git(*args):
        return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True).stdout.strip()

    return git("rev-parse", "--short", "HEAD") + ("-dirty" if git("status", "--porcelain", "--untracked-files=no")
                                                  else "")


#: Read when the benchmark starts: its own rows, appended to tracked CSVs, must not make
#: its later rows ``-dirty``, nor a commit made while it runs change what they name.
START_COMMIT = _commit()


def provenance() -> dict:
    """The commit the run started from (:data:`START_COMMIT`), the machine and the date (UTC)."""
    import os

    from bayes_inerter.inference.fit import versions

    v = versions()
    machine = f"{v['machine']} {v['cpu']}, {os.cpu_count()} cores"
    commit = START_COMMIT
    return {"commit": commit, "machine": machine, "date": datetime.datetime.now(datetime.timezone.utc).date().isoformat()}


def record_row(name: str, row: dict) -> Path:
    """Append ``row`` (with :func:`provenance`) to results/performance/<name>.csv. A row
    with columns the file lacks widens it: the new columns go after the old ones, empty
    in the rows measured before they existed."""
    path = PERFORMANCE / f"{name}.csv"
    full = {**provenance(), **row}
    path.parent.mkdir(parents=True, exist_ok=True)
    rows, fields = [], list(full)
    if path.exists():
        with open(path, newline="") as f:
            reader = csv.DictReader(f)
            rows = list(reader)
            fields = list(reader.fieldnames or []) + [k for k in full if k not in (reader.fieldnames or [])]
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=fields, restval="")
        w.writeheader()
        w.writerows(rows + [full])
    return path
