"""A study's finished fits, as read from their folders: each one's summary rows,
fit.json and LOO, the input of the study's tables (``analysis``)."""

from __future__ import annotations

import csv
import json
import math
from dataclasses import dataclass
from pathlib import Path

from .. import arviz_import

__all__ = ["RecordFit", "collect", "fit_loo"]


@dataclass
class RecordFit:
    """One finished fit: its record's setting and frequency, model, summary rows, fit.json."""

    name: str
    setting: str | None
    freq: float | None
    model: str
    folder: Path
    summary: dict  # name -> row
    info: dict  # fit.json

    @property
    def converged(self) -> bool:
        return bool(self.info.get("converged"))

    def stat(self, name: str, column: str) -> float:
        return float(self.summary[name][column])


def _read_summary(path: Path) -> dict:
    with open(path, newline="") as f:
        return {row["name"]: row for row in csv.DictReader(f)}


def collect(fits_dir: Path) -> list[RecordFit]:
    """Every finished fit under ``fits_dir``/<model>/<record>/ (summary.csv and fit.json),
    in the order of model, setting, drive frequency (as numbers: 0.5, 1, 1.5 Hz) and name."""
    out = []
    for summary in sorted(Path(fits_dir).glob("*/*/summary.csv")):
        folder = summary.parent
        info = json.loads((folder / "fit.json").read_text())
        meta = info.get("record_metadata") or {}
        freq = meta.get("drive_frequency_hz")
        out.append(RecordFit(folder.name, meta.get("setting"), float(freq) if freq else None, info["model"],
                             folder, _read_summary(summary), info))
    return sorted(out, key=lambda f: (f.model, f.setting or "", f.freq if f.freq is not None else math.inf, f.name))


def fit_loo(fit: RecordFit) -> dict:
    """A fit's PSIS-LOO (``inference.summaries.results.loo_summary``): from its ``loo.json``, or
    computed from its ``posterior.nc`` and kept in ``loo.json`` for next time."""
    from ..inference.summaries.results import LOO_FILE, write_loo

    path = fit.folder / LOO_FILE
    if path.is_file():
        return json.loads(path.read_text())
    az = arviz_import.module()

    return write_loo(fit.folder, az.from_netcdf(str(fit.folder / "posterior.nc")))
