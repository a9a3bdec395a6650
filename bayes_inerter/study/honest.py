"""Each setting's inertance with the honest interval (``inference.summaries.interval``).

Every record's fit reports b with its honest interval (fit.json ``b_interval``: the
posterior widened by the model discrepancy the record shows and the sensors'
calibration, or "not identified" where the model reproduces too little of the record).
A setting's records are combined by ``interval.combined_interval``: the identified
records' intervals as a product in log b, widened by the Birge ratio where the
frequencies disagree, and the sensors' share added once.
"""

from __future__ import annotations

from ..inference.summaries.interval import LEVEL, InertanceInterval, combined_interval
from ..records.sensitivity import SensorCalibration
from .fits import RecordFit

__all__ = ["honest_columns", "record_interval"]


def record_interval(fit: RecordFit) -> InertanceInterval | None:
    """The record's honest interval from its fit.json, or None for a fit made before the
    package reported one (refit it to get one)."""
    got = fit.info.get("b_interval")
    return InertanceInterval(**got) if isinstance(got, dict) else None


def honest_columns(inert: list[dict], fits: list[RecordFit], calibration: SensorCalibration | None,
                   truth_b: dict | None = None) -> list[dict]:
    """``inert``'s rows (one per setting, ``analysis.inertance_table``'s, whose
    ``moving_mass`` the sensors' share uses) with the honest combination of its two-port
    records added: ``b_honest_median``, ``b_honest_3%``, ``b_honest_97%`` (kg; the prior's
    range where no record identifies b), ``honest_identified`` and ``honest_records``
    ("used of all"); ``covers_truth_honest`` with ``truth_b``. A setting whose fits have no
    honest interval gets none of these."""
    out = []
    for row in inert:
        group = [f for f in fits if f.model == "two-port" and f.setting == row["setting"]]
        parts = [record_interval(f) for f in group]
        row = dict(row)
        if parts and all(p is not None for p in parts):
            got = combined_interval(parts, calibration=calibration, moving_mass=row["moving_mass"], level=LEVEL)
            used = sum(p.identified for p in parts)
            row.update({"b_honest_median": got.median, "b_honest_3%": got.lo, "b_honest_97%": got.hi,
                        "honest_identified": got.identified, "honest_records": f"{used} of {len(parts)}"})
            if truth_b and row["setting"] in truth_b:
                row["covers_truth_honest"] = bool(got.lo <= truth_b[row["setting"]] <= got.hi)
        out.append(row)
    return out
