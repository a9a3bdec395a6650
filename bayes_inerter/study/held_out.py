"""The held-out device families side by side: how b's intervals held on each.

Issue 39's item 5 asks b's coverage also on device families the likelihood was not
designed on (``paper_like_coverage.FAMILIES``). Each family has its own folder of
replicates (``studies/paper_like_coverage.py --family NAME``); :func:`families_table`
reads them and sets one row per family beside their pool, counting among converged,
identified chains (what the issue asks of):

- how often b's 94 % and 50 % intervals held the true b, and how far each rate lies from
  nominal in binomial standard errors at nominal (``z94``, ``z50``);
- the same for b / gain's intervals against b g_F / g_a, where the replicates hold them
  (``paper_like_coverage.with_errors``): b's interval is widened by the prior of the
  sensors' gain ratio, from which the generator also draws each laboratory's sensors, so
  b's rates alone cannot tell whether the part the record decides is calibrated;
- the median widths and b's mean error, whole and beyond the sensors' gains.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .paper_like_coverage import LEVELS, with_errors
from .replicate_store import finished

__all__ = ["families_table", "NOMINAL"]

#: the intervals' levels (``paper_like_coverage.LEVELS``), by the key their replicates use
NOMINAL = {str(round(100 * level)): level for level in LEVELS}


def _z(held: int, n: int, nominal: float) -> float | str:
    """(rate - nominal) in binomial standard errors at nominal; "" without records."""
    return round((held / n - nominal) / math.sqrt(nominal * (1 - nominal) / n), 2) if n else ""


def _rates(row: dict, reps: list[dict], suffix: str) -> None:
    n = len(reps)
    row[f"n{suffix}"] = n
    for key, nominal in NOMINAL.items():
        held = sum(bool(r[f"covered{key}{suffix}"]) for r in reps)
        row[f"held{key}{suffix}"] = held
        row[f"rate{key}{suffix}"] = round(held / n, 3) if n else ""
        row[f"z{key}{suffix}"] = _z(held, n, nominal)
    width = [r[f"width94{suffix}_pct"] for r in reps]
    row[f"median_width94{suffix}_pct"] = round(float(np.median(width)), 2) if width else ""


def _row(name: str, reps: list[dict]) -> dict:
    good = [r for r in reps if r["converged"] and r["identified"]]
    row = {"family": name, "records": len(reps), "converged": sum(bool(r["converged"]) for r in reps),
           "identified": sum(bool(r["identified"]) for r in reps)}
    _rates(row, good, "")
    _rates(row, [r for r in good if "covered94_b_over_gain" in r], "_b_over_gain")
    for key in ("error_pct", "error_beyond_gain_pct"):
        row[f"mean_{key}"] = round(float(np.mean([r[key] for r in good])), 2) if good else ""
    return row


def families_table(folders) -> list[dict]:
    """One row per folder of replicates (``paper_like_coverage``'s, one family each),
    then ``all``, their pool; see the module docstring. Refuses a folder without
    replicates or one that mixes families."""
    rows, pooled = [], []
    for folder in map(Path, folders):
        reps = [with_errors(r) for r in finished(folder)]
        if not reps:
            raise ValueError(f"{folder} holds no finished replicates; run studies/paper_like_coverage.py there first")
        families = sorted({r.get("family", "default") for r in reps})
        if len(families) != 1:
            raise ValueError(f"{folder} mixes the families {', '.join(families)}; a folder keeps one")
        rows.append(_row(families[0], reps))
        pooled += reps
    rows.append(_row("all", pooled))
    return rows
