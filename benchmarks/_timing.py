"""Shared by the benchmarks: the median wall time of a call, and a row of results
written with the commit, machine and date it was measured on."""

import csv
import datetime
import subprocess
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
PERFORMANCE = ROOT / "results" / "performance"


def median_time(fn, repeats=30):
    """Median seconds of ``repeats`` calls of ``fn`` after one warm-up call."""
    fn()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return float(np.median(times))


def provenance() -> dict:
    """The commit (``-dirty`` with uncommitted changes), the machine and the date (UTC)."""
    def git(*args):
        return subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True).stdout.strip()

    commit = git("rev-parse", "--short", "HEAD") + ("-dirty" if git("status", "--porcelain", "--untracked-files=no")
                                                     else "")
    import os

    from bayes_inerter.inference.fit import versions

    v = versions()
    machine = f"{v['machine']} {v['cpu']}, {os.cpu_count()} cores"
    return {"commit": commit, "machine": machine, "date": datetime.datetime.now(datetime.timezone.utc).date().isoformat()}


def record_row(name: str, row: dict) -> Path:
    """Append ``row`` (with :func:`provenance`) to results/performance/<name>.csv."""
    path = PERFORMANCE / f"{name}.csv"
    full = {**provenance(), **row}
    new = not path.exists()
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "a", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(full))
        if new:
            w.writeheader()
        w.writerow(full)
    return path
