"""The paper's own identification beside the posterior, record by record.

Lin et al. tuned each record's parameters so that the simulated acceleration follows the
measured one (eq. 4) and reported phi (eq. 5, Table 2). With ``StudyPlan.identify`` the
study does the same by machine for every record (``inference.identify``: multi-start
least squares on the unfiltered record, b's interval from the cycle-clustered Hessian)
and sets it beside the posterior, the honest interval and the paper's Table 2
(``least_squares.csv``), so a reader sees what the Bayesian treatment adds.

Each record's least-squares fit is kept as ``<out>/least_squares/<record>.json`` and
reused by a later run with the same starts and seed.
"""

from __future__ import annotations

import json
from pathlib import Path

from ..device import SETTINGS
from ..inference.identify import LEAST_SQUARES, STARTS  # STARTS: least-squares starts per record
from .fits import RecordFit
from .honest import record_interval

__all__ = ["FOLDER", "STARTS", "identify_one", "run_least_squares", "least_squares_table", "least_squares_section"]

#: Where the fits are kept, under the study's folder.
FOLDER = "least_squares"


def identify_one(record: str, out: str, starts: int = STARTS, seed: int = 0) -> dict:
    """Eq. (4)'s fit of the CSV ``record`` (two-port model, the record's masses), written
    to ``out`` (JSON) and returned."""
    from ..inference.identify import identify
    from ..inference.posterior.model import PosteriorModel
    from ..masses import resolve_masses
    from ..records import read_record

    rec = read_record(record)
    masses = resolve_masses(rec)
    got = identify(PosteriorModel(rec, m_s=masses.m_s, m_B=masses.m_B, likelihood=LEAST_SQUARES), starts=starts,
                   seed=seed)
    info = {"record": Path(record).name, "seed": seed, **got.as_dict()}
    Path(out).write_text(json.dumps(info, indent=2) + "\n")
    return info


def _earlier(path: Path, record: str, starts: int, seed: int) -> dict | None:
    try:
        info = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    same = isinstance(info, dict) and (info.get("record"), info.get("starts"), info.get("seed")) == (
        Path(record).name, starts, seed)
    return info if same else None


def run_least_squares(records: dict, out: Path, *, starts: int = STARTS, seed: int = 0, processes: int = 1,
                      on_done=None) -> dict:
    """Each record's eq. (4) fit (``records``: name -> (CSV path, setting, frequency)),
    on ``processes`` local processes, into ``out``/least_squares; earlier ones with the
    same starts and seed are reused. Returns name -> the fit's dict, or -> {"error": ...}
    where it failed (the others go on). ``on_done(name)`` hears each one end."""
    from ..executor import LocalProcesses

    folder = Path(out) / FOLDER
    folder.mkdir(parents=True, exist_ok=True)
    got, todo = {}, []
    for i, (name, (path, _, _)) in enumerate(sorted(records.items())):
        earlier = _earlier(folder / f"{name}.json", str(path), starts, seed + i)
        if earlier is not None:
            got[name] = earlier
        else:
            todo.append((name, str(path), str(folder / f"{name}.json"), seed + i))
    with LocalProcesses(processes) as executor:
        for end in executor.as_completed(_one, todo):
            name = todo[end.index][0]
            got[name] = end.value if end.ok else {"error": f"{type(end.error).__name__}: {end.error}"}
            if on_done:
                on_done(name)
    return got


def _one(item) -> dict:
    _, path, out, seed = item
    return identify_one(path, out, seed=seed)


def least_squares_table(fits_ls: dict, fits: list[RecordFit], truth_b: dict | None = None) -> list[dict]:
    """One row per record: the least-squares b with its interval and phi (eq. 5 on the
    unfiltered record), the posterior's b (mean, 94 % HDI) and phi, the honest interval,
    and the paper's b and phi (Table 2); with ``truth_b`` (per setting), whether each
    interval holds it."""
    posterior = {f.name: f for f in fits if f.model == "two-port"}
    rows = []
    for name, ls in sorted(fits_ls.items(), key=lambda kv: _order(kv[0], posterior)):
        f = posterior.get(name)
        setting = f.setting if f is not None else None
        freq = f.freq if f is not None else None
        row = {"record": name, "setting": setting, "freq_hz": freq}
        if "error" in ls:
            row["ls_error"] = ls["error"]
        else:
            lo, hi = ls["b_interval"] or (None, None)
            row.update({"b_ls": ls["b"], "b_ls_3%": lo, "b_ls_97%": hi, "phi_ls": ls["phi"]})
        if f is not None:
            row.update({"b_post_mean": f.stat("b", "mean"), "b_post_3%": f.stat("b", "hdi_3%"),
                        "b_post_97%": f.stat("b", "hdi_97%"), "phi_post": f.stat("phi", "mean"),
                        "converged": f.converged})
            honest = record_interval(f)
            if honest is not None:
                row.update({"b_honest_3%": honest.lo if honest.identified else None,
                            "b_honest_97%": honest.hi if honest.identified else None,
                            "honest_identified": honest.identified})
        if setting in SETTINGS:
            row.update({"b_paper": SETTINGS[setting].b_paper, "phi_paper": SETTINGS[setting].fit_paper.get(freq)})
        if truth_b and setting in truth_b:
            b = truth_b[setting]
            row["b_truth"] = b
            for key in ("ls", "post", "honest"):
                lo, hi = row.get(f"b_{key}_3%"), row.get(f"b_{key}_97%")
                row[f"covers_{key}"] = None if lo is None or hi is None else bool(lo <= b <= hi)
        rows.append(row)
    return rows


def _order(name: str, posterior: dict):
    f = posterior.get(name)
    if f is None:
        return ("~", float("inf"), name)
    return (f.setting or "~", f.freq if f.freq is not None else float("inf"), name)


def least_squares_section(rows: list[dict]) -> list[str]:
    """REPORT.md's section on :func:`least_squares_table`'s rows, its sentences written
    from their numbers."""
    import math
    import statistics

    from .markdown import table

    done = [r for r in rows if "b_ls" in r]
    failed = [r["record"] for r in rows if "ls_error" in r]
    text = (f"Every record was also fitted as the paper did: eq. (4)'s least squares on the unfiltered record from "
            f"{STARTS} starts, phi by eq. (5) on the record as measured, and b's 94 % interval from the "
            "cycle-clustered Hessian (`inference.identify`; `least_squares.csv`, `least_squares/`). ")
    if failed:
        text += f"It failed for {len(failed)} record(s): {', '.join(failed)}. "
    both = [r for r in done if r.get("phi_paper") is not None]
    if both:
        gap = statistics.mean(abs(r["phi_ls"] - r["phi_paper"]) for r in both)
        text += (f"Its phi differs from the paper's Table 2 by {100 * gap:.1f} points on average over "
                 f"{len(both)} records (mean {100 * statistics.mean(r['phi_ls'] for r in both):.1f} % against "
                 f"{100 * statistics.mean(r['phi_paper'] for r in both):.1f} %). ")
    paired = [r for r in done if r.get("b_post_mean")]
    if paired:
        moves = sorted((abs(math.log(r["b_ls"] / r["b_post_mean"])), r["record"]) for r in paired)
        text += (f"The least-squares b and the posterior mean differ by a median {100 * moves[len(moves) // 2][0]:.1f} % "
                 f"(in log b; largest {100 * moves[-1][0]:.1f} %, {moves[-1][1]}). ")
    widths = []
    for key, name in (("ls", "least squares"), ("post", "posterior"), ("honest", "honest")):
        w = [(r[f"b_{key}_97%"] - r[f"b_{key}_3%"]) / r["b_ls"] for r in done
             if r.get(f"b_{key}_3%") is not None and r.get(f"b_{key}_97%") is not None]
        if w:
            widths.append(f"{name} {100 * statistics.median(w):.1f} % ({len(w)} records)")
    if widths:
        text += "Median 94 % widths, relative to b: " + "; ".join(widths) + ". "
    if any("b_truth" in r for r in rows):
        held = []
        for key, name in (("ls", "least squares"), ("post", "posterior"), ("honest", "honest")):
            got = [r[f"covers_{key}"] for r in rows if r.get(f"covers_{key}") is not None]
            if got:
                held.append(f"{name} {sum(got)} of {len(got)}")
        text += "Intervals holding the generating b: " + "; ".join(held) + " (the honest interval only where it " \
                "identifies b). "
    text += ("The least-squares interval says how far the record's own noise and misfit move the point estimate, "
             "assuming its cycles are independent; it knows nothing of the sensors' calibration or of what the "
             "model lacks.")
    cols = ["record", "b_ls", "b_ls_3%", "b_ls_97%", "phi_ls", "b_post_mean", "b_post_3%", "b_post_97%", "phi_post",
            "b_honest_3%", "b_honest_97%", "b_paper", "phi_paper", "b_truth", "covers_ls", "covers_post",
            "covers_honest"]
    present = [c for c in cols if any(c in r for r in rows)]
    fmt = {c: "{:.1f}" for c in cols if c.startswith("b_")} | {c: "{:.3f}" for c in ("phi_ls", "phi_post", "phi_paper")}
    return ["### The paper's least squares beside the posterior", "", text, "", table(rows, present, fmt), "",
            "![least squares beside the posterior](least_squares.png)", ""]
