"""Does the default fit's posterior hold b on the generator's noise-free records?

Issue 39, item 1's interval half, measured with chains: record k of the paper's grid
(``device.grid_case``; records 0 to 26 cover every setting at every frequency once) is
made by the project's own generator from Table I and Table 2 with every noise off
(:data:`NOISE_FREE`: the sensors' band limits kept), and fitted by ``fit_record`` as
``bayes-inerter fit`` runs it (the default likelihood, each chain to the convergence
rule, at most ``Config.max_steps``). ``Config.zeta_B`` gives the generator's plate mode
that damping ratio in place of Table I's c_B (a ratio of 8e-6, outside the fit's damping
prior of 0.5 to 10 %: ``priors.MODAL_PRIORS``). ``Config.tau_floor`` raises the floor of
the discrepancy tau's log-uniform prior (a probe of the likelihood, not the package's
default).

The study of results/noise-free-chains* (``studies/noise_free_chains.py``, through
``cli.study_script``): one JSON per record in ``out``/records (a run that stops goes on
where it stopped), chains.csv from all of them: b's posterior median and its error, the
94 % highest-density interval and whether it holds the true b, the chain's state and
seconds, the commit the process loaded.
"""

from __future__ import annotations

import csv
import dataclasses
import json
import math
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..device import grid_case, paper_parameters
from ..inference.fit import fit_record
from ..inference.sampling.tempering import Tempering
from ..inference.posterior.priors import tau_floor_prior
from ..inference.summaries.results import hdi
from ..records import GeneratorSettings, generate_record
from . import stop_rule
from .manifest import source_commit
from .output import StudyOutput, write_json

__all__ = ["Config", "run", "NOISE_FREE", "device", "fit_one"]

#: The generator with every noise off (its sensors' band limits kept).
NOISE_FREE = GeneratorSettings(force_noise=0.0, accel_noise=0.0, disp_noise=0.0)


@dataclass(frozen=True)
class Config:
    """Attributes
    ----------
    records : how many records of the paper's grid (1 to 27, from record 0).
    zeta_B : the generator's plate-mode damping ratio (None: Table I's c_B).
    max_steps : each chain's cap (cold steps where tempered).
    tempering : parallel tempering's temperatures (``sampler.Tempering``; None: the
        ensemble alone). A folder keeps one ladder.
    hottest_beta : the tempering ladder's hottest beta.
    only : fit these records alone (None: records 0 to ``records`` - 1).
    tau_rtol : the convergence rule's tolerance of tau's growth (None: the package's,
        ``Convergence.tau_rtol``); a folder keeps one (``stop_rule``).
    summarise : only write chains.csv from the records already there.
    """

    records: int = field(default=27, metadata={"help": "records of the paper's grid, 1 to 27"})
    zeta_B: float | None = field(default=None, metadata={"help": "the plate mode's damping ratio (default: Table I's c_B)"})
    max_steps: int = field(default=20000, metadata={"help": "each chain's cap"})
    tempering: int | None = field(default=None, metadata={"help": "parallel tempering's temperatures (default: none)"})
    hottest_beta: float = field(default=Tempering.beta_min, metadata={"help": "the tempering ladder's hottest beta"})
    only: tuple[int, ...] | None = field(default=None, metadata={"help": "fit these records alone"})
    tau_floor: float | None = field(default=None, metadata={
        "help": "the discrepancy tau's prior floor, N (default: the package's, priors.MOTION_DISCREPANCY_PRIORS)"})
    tau_rtol: float | None = field(default=None, metadata={
        "help": "the convergence rule's tolerance of tau's growth between checks (default: the package's, "
                "Convergence.tau_rtol); a folder keeps one"})
    summarise: bool = field(default=False, metadata={"help": "only write chains.csv from the records there"})

    def __post_init__(self) -> None:
        if not (isinstance(self.records, int) and 1 <= self.records <= 27):
            raise ValueError(f"records must lie in 1 to 27 (the paper's grid), got {self.records!r}")
        if self.zeta_B is not None and not 0.0 < self.zeta_B < 1.0:
            raise ValueError(f"zeta_B is a damping ratio in (0, 1), got {self.zeta_B}")
        if not (isinstance(self.max_steps, int) and self.max_steps >= 100):
            raise ValueError(f"max_steps must be a whole number of at least 100, got {self.max_steps!r}")
        if self.tempering is not None:
            self.ladder()  # its own check of the ladder
        if self.only is not None and not all(0 <= k < 27 for k in self.only):
            raise ValueError(f"only names records of the paper's grid, 0 to 26, got {list(self.only)}")
        if self.tau_floor is not None:
            tau_floor_prior(self.tau_floor)  # its own check

    def priors(self) -> dict:
        """The fit's priors beyond the package's: tau's floor raised where asked."""
        if self.tau_floor is None:
            return {}
        return {"tau": tau_floor_prior(self.tau_floor)}

    def ladder(self) -> Tempering | None:
        """The fit's tempering (None: the ensemble alone)."""
        return Tempering.of(self.tempering, self.hottest_beta)


def device(setting: str, zeta_b: float | None):
    """Table I and Table 2's device, its plate mode damped ``zeta_b`` (None: Table I's c_B)."""
    p = paper_parameters(setting)
    if zeta_b is None:
        return p
    return dataclasses.replace(p, c_B=2.0 * zeta_b * math.sqrt(p.k_B * p.m_B))


def fit_one(job) -> dict:
    """Record k's row (``job``: (k, out, config, commit)), written to ``out``/records as
    it ends; read from there where an earlier run finished it."""
    k, out, config, commit = job
    path = Path(out) / "records" / f"{k:04d}.json"
    if path.exists():
        return json.loads(path.read_text())
    setting, freq = grid_case(k)
    p = device(setting, config.zeta_B)
    rec = generate_record(p, freq, settings=NOISE_FREE, setting_name=setting)
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        res = fit_record(rec, Path(tmp) / "fit", seed=k, plots=False,
                         convergence=stop_rule.convergence(config.max_steps, config.tau_rtol),
                         tempering=config.ladder(), priors=config.priors())
    b = np.asarray(res.idata.posterior["b"]).ravel()
    lo, hi = hdi(b)
    tau = np.asarray(res.tau, dtype=float)
    row = {"record": k, "setting": setting, "freq_hz": freq, "zeta_B": config.zeta_B, "b_true": p.b,
           "b_median": float(np.median(b)), "error_pct": 100.0 * (float(np.median(b)) / p.b - 1.0),
           "hdi94_lo": float(lo), "hdi94_hi": float(hi), "holds94": bool(lo <= p.b <= hi),
           "width94_pct": 100.0 * (hi - lo) / p.b, "identified": bool(res.b_interval.identified),
           "converged": bool(res.converged), "steps": int(res.iterations),
           "tau_max": float(np.nanmax(tau)) if np.any(np.isfinite(tau)) else None,
           "seconds": round(time.perf_counter() - t0, 1), "commit": commit,
           "tau_rtol": stop_rule.resolved(config.tau_rtol)}
    if config.tempering is not None:  # absent for the ensemble alone: the rows before it have no such keys
        row.update(tempering=config.tempering, hottest_beta=config.hottest_beta,
                   swap_rates=res.tempering["swap_rates"])
    if config.tau_floor is not None:  # likewise absent for the package's prior
        row.update(tau_floor=config.tau_floor, tau_median=float(np.median(res.idata.posterior["tau"])))
    write_json(path, row, indent=1)
    return row


def _ladder(config: Config) -> tuple | None:
    return None if config.tempering is None else (config.tempering, config.hottest_beta)


def _row_ladder(row: dict) -> tuple | None:
    return (row["tempering"], row["hottest_beta"]) if "tempering" in row else None


def _line(r: dict) -> str:
    return (f"{r['setting']} {r['freq_hz']:g} Hz: b {r['b_median']:.1f} (true {r['b_true']:.1f}, "
            f"{r['error_pct']:+.3f} %), 94 % {'holds' if r['holds94'] else 'MISSES'}, converged {r['converged']} "
            f"({r['steps']} steps), {r['seconds']} s")


def run(config: Config, out, executor, *, progress=None) -> StudyOutput:
    """The records not yet in ``out``/records fitted on ``executor`` (one each), then
    chains.csv from every record there. A folder keeps one ``zeta_B``, one ladder and one
    tau floor: a run asking another is refused (ValueError). ``lines``: one per record
    fitted or read."""
    out = Path(out)
    (out / "records").mkdir(parents=True, exist_ok=True)
    kept = [json.loads(p.read_text()) for p in (out / "records").glob("*.json")]
    for key, want, of in (("zeta_B", config.zeta_B, lambda r: r["zeta_B"]), ("ladder", _ladder(config), _row_ladder),
                          ("tau_floor", config.tau_floor, lambda r: r.get("tau_floor"))):
        have = {of(r) for r in kept}
        if have - {want}:
            raise ValueError(f"{out} holds records of {key} {sorted(have, key=str)}, not {want}; "
                             "choose another folder")
    if not config.summarise:
        stop_rule.check_folder(kept, config.tau_rtol, out)
    failed = []
    if not config.summarise:
        commit = source_commit() or ""  # the code this run loaded: HEAD may move while it runs
        ks = range(config.records) if config.only is None else sorted(set(config.only))
        jobs = [(k, out, config, commit) for k in ks]
        if progress:
            progress(0, len(jobs))
        for i, got in enumerate(executor.as_completed(fit_one, jobs), 1):
            if not got.ok:  # one record's failure is reported, the others go on
                failed.append((f"record {jobs[got.index][0]}", str(got.error)))
            if progress:
                progress(i, len(jobs))
    rows = [json.loads(p.read_text()) for p in sorted((out / "records").glob("*.json"))]
    if not rows:
        raise ValueError(f"{out} holds no finished record; run without summarise first")
    with open(out / "chains.csv", "w", newline="") as f:  # every digit: the rows are the study's result
        writer = csv.DictWriter(f, fieldnames=list(dict.fromkeys(k for r in rows for k in r)))
        writer.writeheader()
        writer.writerows(rows)
    return StudyOutput(written=(out / "chains.csv",), failed=tuple(failed), lines=tuple(map(_line, rows)),
                       values={"rows": rows})
