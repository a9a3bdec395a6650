"""Per-fit figures drawn again from the fits' checkpoints: ``bayes-inerter report DIR``.

Committed results keep each fit's tables (summary.csv, fit.json, loo.json, done.json),
not its figures or posterior files, which are large and remade by a command. A study
fit's ``done.json`` names its record and settings; with its checkpoint (``chain.h5``,
kept where the fit ran) the fit is run again, which continues nothing (the chain is
complete) and writes every output, the figures among them. A fit without a checkpoint
is reported, not sampled again.
"""

from __future__ import annotations

import json
from pathlib import Path

__all__ = ["redraw_fits"]


def redraw_fits(folder, *, on_fit=None) -> list[tuple[str, str]]:
    """Draw the figures of every study fit under ``folder`` (a study's folder, or one
    fit's) that has a checkpoint. Returns (fit folder, "drawn" or why not) per fit;
    ``on_fit(folder, status)`` hears each as it ends. ValueError if there is no fit."""
    from .plan import FitJob
    from .runner import run_job

    folder = Path(folder)
    dones = sorted(folder.glob("fits/*/*/done.json")) or sorted(folder.glob("done.json"))
    if not dones:
        raise ValueError(f"{folder}: no study fits there (no done.json); a fit of your own draws its figures itself")
    out = []
    for done in dones:
        fit = done.parent
        try:
            job = json.loads(done.read_text())["job"]
        except (OSError, ValueError, KeyError):
            status = "done.json unreadable"
        else:
            if not (fit / "chain.h5").exists():
                status = "no checkpoint here (fitted elsewhere): run the study into this folder to draw it"
            elif not Path(job["record"]).exists():
                status = f"its record {job['record']} is not there"
            else:
                run_job(FitJob(**{**job, "out": str(fit)}), plots=True)
                status = "drawn"
        out.append((str(fit), status))
        if on_fit:
            on_fit(str(fit), status)
    return out
