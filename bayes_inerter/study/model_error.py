"""Coverage of b's intervals on records of a device richer than the model.

The study of results/model-error (``studies/model_error.py``, through
``cli.study_script``): :class:`Config` and :func:`run`.

Each replicate is one paper-like laboratory (``records.paper_like``, seed = replicate
number + ``--seed`` x 100,000) and one flywheel setting drawn uniformly from the nine; its
records are that setting at 0.5, 1 and 1.5 Hz. A single-record method (``two-port``, or
a richer model's name) fits the record at one frequency drawn uniformly from the three;
``joint`` fits the setting's three records together (one b); ``setting`` fits each of
the three alone and combines their intervals (``interval.combined_interval``). Every
draw's seed is written to replicates.csv. ``--device model`` makes the records with the
model itself instead (``records.generator.paper_record``): the control where the model
is right.

Each fit is summarised by the normal (Laplace) approximation of its posterior at the
optimum the sampler would start from (``optimize.find_start``, then
``optimize.laplace_covariance``), in log b: the intervals are exp(mu +- z sd) at 50 % and
94 %; these are approximate posteriors, not MCMC. A method's ``+`` terms add shares to
the sd: ``+sensors`` the sensors' calibration uncertainty
(``records.sensitivity.SensorCalibration``'s defaults), ``+discrepancy`` the harmonic
model discrepancy (``inference.posterior.discrepancy``; the other parameters held, decay 1),
``+discrepancy_flat`` the same with decay 0, ``+discrepancy_free`` with the other
parameters free (the Laplace covariance's linear response); ``+guard`` reports b as not identified (the prior's range) where phi is
below ``end_state.PHI_WARNING`` (for ``setting``: leaves such records out).
``two-port+discrepancy+sensors+guard`` and ``setting+sensors+guard`` are what ``fit``
and ``study`` report by default (``interval.INTERVALS["honest"]``).

Writes replicates.csv (one row per replicate and method), coverage.csv (per method:
replicates, coverage of the 50 % and 94 % intervals with binomial standard errors, the
share identified, median relative width of the identified 94 % intervals, median
relative error of the centre) and coverage.png.
"""


from __future__ import annotations

import csv
import json
import math
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..device import FREQUENCIES_HZ, SETTINGS
from ..inference.posterior.discrepancy import DECAY, harmonic_discrepancy
from ..inference.posterior.joint import JointModel
from ..inference.posterior.model import PosteriorModel
from ..inference.posterior.priors import DEFAULT_PRIORS
from ..inference.sampling.optimize import NM_RESTARTS, find_start, laplace_covariance, local_optimum
from ..inference.summaries.end_state import PHI_WARNING
from ..inference.summaries.interval import InertanceInterval, combined_interval
from ..records.generator import GeneratorSettings, paper_record
from ..records.paper_like import PaperLike, paper_like_record
from ..records.sensitivity import SensorCalibration
from .output import StudyOutput

__all__ = ["Config", "run", "METHODS", "DEFAULT_METHODS", "replicate", "rescore", "coverage"]

Z50, Z94 = 0.6744897501960817, 1.8807936081512509  # normal quantiles of 0.75 and 0.97
#: What the script measures unless told: today's posterior, each share alone and the
#: defaults of ``fit`` (``two-port+discrepancy+sensors+guard``) and ``study``
#: (``setting+sensors+guard``).
DEFAULT_METHODS = ("two-port", "two-port+sensors", "two-port+discrepancy+sensors", "two-port+discrepancy_flat+sensors",
                   "two-port+discrepancy_free+sensors", "two-port+discrepancy+sensors+guard", "setting",
                   "setting+sensors", "setting+sensors+guard")
PRIOR_B = tuple(float(v) for v in np.exp(DEFAULT_PRIORS["b"].bounds))  # b's prior range, kg: "not identified"
METHODS = ("two-port", "two-port+sensors", "two-port+discrepancy", "two-port+discrepancy+sensors",
           "two-port+discrepancy_flat", "two-port+discrepancy_flat+sensors", "joint+discrepancy_flat+sensors",
           "two-port+discrepancy_free+sensors", "joint+discrepancy_free+sensors", "setting", "setting+sensors",
           "two-port+discrepancy+sensors+guard", "setting+sensors+guard",
           "two-port-stribeck", "two-port-backlash", "two-port-rich", "two-port-rich+discrepancy", "joint",
           "joint+sensors", "joint+discrepancy", "joint+discrepancy+sensors")


@dataclass(frozen=True)
class Config:
    """The study as ``studies/model_error.py`` runs it (see the module docstring).

    Attributes
    ----------
    replicates : how many replicates (0 to replicates - 1).
    methods : the methods measured, each a name of :data:`METHODS`.
    duration : each record's length, s.
    seed : replicate k's laboratory seed is k + seed x 100,000.
    device : "paper-like" (richer than the model) or "model" (the model itself: a control).
    rescore : remake the rows for ``methods`` from those already in the folder, no fitting.
    only : run these replicates alone (None: all).
    """

    replicates: int = field(default=100, metadata={"help": "how many replicates"})
    methods: tuple[str, ...] = field(default=DEFAULT_METHODS, metadata={"help": "the methods measured"})
    duration: float = field(default=10.0, metadata={"help": "record length, s"})
    seed: int = field(default=0, metadata={"help": "laboratory seeds k + seed x 100,000"})
    device: str = field(default="paper-like", metadata={
        "choices": ("paper-like", "model"),
        "help": "the records' device: paper-like (richer than the model) or the model itself (a control)"})
    rescore: bool = field(default=False, metadata={
        "help": "remake replicates.csv and the table from the rows in --out for --methods, with no fitting"})
    only: tuple[int, ...] | None = field(default=None, metadata={"help": "run these replicates alone"})

    def __post_init__(self) -> None:
        object.__setattr__(self, "methods", tuple(self.methods))
        unknown = sorted(set(self.methods) - set(METHODS))
        if unknown:
            raise ValueError(f"unknown methods {', '.join(unknown)}; choose from {', '.join(METHODS)}")
        if self.rescore and "two-port" not in self.methods:
            raise ValueError("rescore reads each replicate's two-port row: keep two-port among the methods")
        if not (isinstance(self.replicates, int) and self.replicates >= 1):
            raise ValueError(f"replicates must be a whole number of at least 1, got {self.replicates!r}")
        if not self.duration > 0:
            raise ValueError(f"duration must be positive (s), got {self.duration}")
        if self.device not in ("paper-like", "model"):
            raise ValueError(f"device must be paper-like or model, got {self.device!r}")


def _laplace_b(model, theta, name: str, cov=None) -> tuple[float, float]:
    """(mu, sd) of log b in the Laplace approximation at ``theta`` (its covariance ``cov``,
    computed here unless given)."""
    cov = laplace_covariance(model, theta) if cov is None else cov
    i = model.names.index(name)
    return float(theta[i]), float(math.sqrt(max(cov[i, i], 0.0)))


def _single(rec, model_name: str, rng) -> dict:
    pm = PosteriorModel(rec, model_name)
    theta, _ = find_start(pm, rng)
    cov = laplace_covariance(pm, theta)
    mu, sd = _laplace_b(pm, theta, "b", cov)
    held = harmonic_discrepancy(pm, theta)
    return {"mu": mu, "sd": sd, "phi": pm.log_prob(theta)[1], "discrepancy": held.sd_log_b,
            "discrepancy_flat": harmonic_discrepancy(pm, theta, decay=0.0).sd_log_b,
            "discrepancy_free": harmonic_discrepancy(pm, theta, cov=cov).sd_log_b, "power": list(held.power)}


def _joint(recs, setting: str, rng) -> dict:
    jm = JointModel(tuple(recs))
    centres = [part.values(find_start(part, rng)[0]) for part in jm.parts]
    theta, _ = local_optimum(jm, jm.start(centres), restarts=NM_RESTARTS)
    mu, sd = _laplace_b(jm, theta, f"b_{setting}")
    # each record's discrepancy at the joint optimum, combined as independent evidence
    got = {"mu": mu, "sd": sd, "phi": jm.log_prob(theta)[1]}
    for key, decay in (("discrepancy", DECAY), ("discrepancy_flat", 0.0), ("discrepancy_free", DECAY)):
        parts = [harmonic_discrepancy(part, jm.part_theta(theta, k), decay=decay).sd_log_b
                 for k, part in enumerate(jm.parts)]
        precision = sum(1.0 / v ** 2 for v in parts if v > 0)
        got[key] = math.sqrt(1.0 / precision) if precision > 0 else 0.0
    return got


def _setting(singles: dict, moving_mass: float, guard: bool) -> dict:
    """The setting's b from its records' single fits (``interval.combined_interval``, the
    sensors left to ``+sensors``; with ``guard``, records whose phi is below
    ``PHI_WARNING`` left out); ``parts`` keeps each record's (freq, mu, sd, discrepancy,
    phi) for other combinations."""
    parts = [InertanceInterval("honest", math.exp(g["mu"]), *PRIOR_B, 0.94, g["sd"], 0.0, g["discrepancy"],
                               identified=not guard or g["phi"] >= PHI_WARNING, phi=g["phi"])
             for g in singles.values()]
    got = combined_interval(parts, calibration=None, moving_mass=moving_mass)
    sd = math.log(got.hi / got.median) / Z94 if got.identified else math.nan
    return {"mu": math.log(got.median), "sd": sd, "phi": min(g["phi"] for g in singles.values()),
            "identified": got.identified, "discrepancy": 0.0, "discrepancy_flat": 0.0, "discrepancy_free": 0.0,
            "parts": [[f, g["mu"], g["sd"], g["discrepancy"], g["phi"]] for f, g in singles.items()]}


def _interval(mu: float, sd: float, z: float) -> tuple[float, float]:
    return math.exp(mu - z * sd), math.exp(mu + z * sd)


def _draw(k: int, config: Config, every: bool):
    """Replicate k's seed, setting, drive frequency and records (all three frequencies'
    with ``every``, else the drawn one's)."""
    seed = k + 100_000 * config.seed
    rng = np.random.default_rng([config.seed, k])
    setting = str(rng.choice(list(SETTINGS)))
    freq = float(rng.choice(FREQUENCIES_HZ))
    base = GeneratorSettings(duration=config.duration)
    device = PaperLike(base=base)
    recs = {f: (paper_like_record(setting, f, seed=seed, device=device) if config.device == "paper-like" else
                paper_record(setting, f, settings=base, seed=seed))
            for f in (FREQUENCIES_HZ if every else (freq,))}
    return seed, setting, freq, recs


def replicate(job) -> list[dict]:
    """Replicate k's rows, one per method (``job``: (k, config))."""
    k, config = job
    every = any(m.split("+")[0] in ("joint", "setting") for m in config.methods)
    seed, setting, freq, recs = _draw(k, config, every)
    m = recs[freq].metadata["m_s"] + recs[freq].metadata["m_B"]
    fits, seconds = {}, {}  # one fit per model; its variants add terms to the same posterior
    for method in config.methods:
        t0 = time.perf_counter()
        model_name, *terms = method.split("+")
        key = _key(model_name, terms)
        if model_name == "setting" and key not in fits:
            if "singles" not in fits:
                fits["singles"] = {f: (fits["two-port"] if f == freq and "two-port" in fits else
                                       _single(r, "two-port", np.random.default_rng([config.seed, k, 1, int(10 * f)])))
                                   for f, r in recs.items()}
            fits[key] = _setting(fits["singles"], m, "guard" in terms)
        if key not in fits:
            fit_rng = np.random.default_rng([config.seed, k, 1])
            fits[key] = (_joint(list(recs.values()), setting, fit_rng) if model_name == "joint" else
                         _single(recs[freq], model_name, fit_rng))
        seconds[method] = round(time.perf_counter() - t0, 2)
    return _rows(k, seed, setting, freq, recs[freq].metadata, fits, config.methods, seconds)


def _key(model_name: str, terms) -> str:
    """The fit a method reads: a setting's combination differs with the guard; the other
    methods' terms only add to the same fit's sd."""
    return model_name + ("+guard" if "guard" in terms and model_name == "setting" else "")


def _rows(k, seed, setting, freq, meta, fits, methods, seconds) -> list[dict]:
    """One row per method from the replicate's fits (``_single``, ``_joint``, ``_setting``)."""
    truth = meta["true_parameters"]["b"]
    gen = {name: meta["generator"].get(name, math.nan) for name in
           ("stribeck_ratio", "stribeck_velocity", "backlash", "force_gain", "accel_gain")}
    m = meta["m_s"] + meta["m_B"]
    rows = []
    for method in methods:
        model_name, *terms = method.split("+")
        got = fits[_key(model_name, terms)]
        # a setting's guard is in its combination (records left out); a single record's here
        identified = got.get("identified", True) and not (
            "guard" in terms and model_name != "setting" and got["phi"] < PHI_WARNING)
        b = math.exp(got["mu"])
        shares = {"stat": got["sd"], "sensors": SensorCalibration().inertance_sd(b, 0.0, m) / b,
                  "discrepancy": got["discrepancy"], "discrepancy_flat": got["discrepancy_flat"],
                  "discrepancy_free": got["discrepancy_free"]}
        sd = math.sqrt(got["sd"] ** 2 + sum(shares[t] ** 2 for t in terms if t in shares))
        lo50, hi50 = _interval(got["mu"], sd, Z50) if identified else PRIOR_B
        lo94, hi94 = _interval(got["mu"], sd, Z94) if identified else PRIOR_B
        rows.append({
            "replicate": k, "seed": seed, "setting": setting,
            "freq_hz": freq if model_name not in ("joint", "setting") else "all",
            "method": method, "b_true": truth, "b_centre": b, "sd_log_b": sd,
            "lo50": lo50, "hi50": hi50, "lo94": lo94, "hi94": hi94, "identified": int(identified),
            "covered50": int(lo50 <= truth <= hi50), "covered94": int(lo94 <= truth <= hi94),
            "phi": got["phi"], **gen, "seconds": seconds.get(method, 0.0),
            **{f"sd_{name}": v for name, v in shares.items()},
            # what --rescore needs, once a replicate: the other records' fits, the harmonics' power
            "parts": json.dumps(got.get("parts", [])) if model_name == "setting" else "",
            "power": json.dumps(got.get("power", [])) if not terms else "",
        })
    return rows


def rescore(rows: list[dict], config: Config) -> list[dict]:
    """Every replicate's rows remade for ``config.methods`` from the fits' numbers that
    earlier rows keep (the single record's from its ``two-port`` row, the other records'
    from a ``setting`` row's parts), with no fitting: for methods that only combine
    those numbers differently."""
    out = []
    for k in sorted({int(r["replicate"]) for r in rows}):
        mine = {r["method"]: r for r in rows if int(r["replicate"]) == k}
        one = mine["two-port"]
        single = {"mu": math.log(float(one["b_centre"])), "sd": float(one["sd_stat"]), "phi": float(one["phi"]),
                  **{name: float(one[f"sd_{name}"]) for name in ("discrepancy", "discrepancy_flat",
                                                                 "discrepancy_free")},
                  "power": json.loads(one.get("power") or "[]")}
        fits = {"two-port": single}
        parts = next((json.loads(r["parts"]) for r in mine.values() if r.get("parts") not in (None, "", "[]")), [])
        if parts:
            fits["singles"] = {f: {"mu": mu, "sd": sd, "discrepancy": disc, "phi": phi}
                               for f, mu, sd, disc, phi in parts}
        seed, setting, freq, recs = _draw(k, config, every=False)
        m = recs[freq].metadata["m_s"] + recs[freq].metadata["m_B"]
        for method in config.methods:
            model_name, *terms = method.split("+")
            if model_name == "setting":
                fits[_key(model_name, terms)] = _setting(fits["singles"], m, "guard" in terms)
        seconds = {r["method"]: float(r["seconds"]) for r in mine.values()}
        out.extend(_rows(k, seed, setting, freq, recs[freq].metadata, fits, config.methods, seconds))
    return out


def coverage(rows: list[dict]) -> list[dict]:
    out = []
    for method in dict.fromkeys(r["method"] for r in rows):
        mine = [r for r in rows if r["method"] == method]
        n = len(mine)
        row = {"method": method, "replicates": n}
        for level in ("50", "94"):
            p = float(np.mean([r[f"covered{level}"] for r in mine]))
            row[f"coverage{level}"] = round(p, 3)
            row[f"se{level}"] = round(math.sqrt(p * (1 - p) / n), 3)
        shown = [r for r in mine if int(r.get("identified", 1))]
        row["identified"] = round(len(shown) / n, 3)
        row["median_width94_pct"] = round(100 * float(np.median([(r["hi94"] - r["lo94"]) / r["b_true"]
                                                                  for r in shown])), 3) if shown else math.nan
        row["median_abs_error_pct"] = round(100 * float(np.median([abs(r["b_centre"] / r["b_true"] - 1) for r in mine])), 3)
        out.append(row)
    return out


_NUMBERS = ("b_true", "b_centre", "sd_log_b", "lo50", "hi50", "lo94", "hi94", "phi")


def _read(path: Path) -> list[dict]:
    """Rows written by an earlier run (numbers as numbers), or none."""
    if not path.exists():
        return []
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        r.update({k: float(r[k]) for k in _NUMBERS}, covered50=int(r["covered50"]), covered94=int(r["covered94"]))
    return rows


def _append(path: Path, rows: list[dict]) -> None:
    new = not path.exists()
    with open(path, "a", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        if new:
            w.writeheader()
        w.writerows(rows)


def _write(path: Path, rows: list[dict]) -> None:
    """The rows as CSV, numbers to 7 significant digits (the partial file keeps them all)."""
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows([{k: f"{v:.7g}" if isinstance(v, float) else v for k, v in r.items()} for r in rows])


def _figure(path: Path, table: list[dict]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 3.6))
    y = np.arange(len(table))
    for level, colour, nominal in (("50", "tab:blue", 0.5), ("94", "tab:red", 0.94)):
        ax.errorbar([r[f"coverage{level}"] for r in table], y, xerr=[2 * r[f"se{level}"] for r in table], fmt="o",
                    color=colour, label=f"{level} % interval (2 se)")
        ax.axvline(nominal, color=colour, ls=":", lw=1)
    ax.set_yticks(y, [r["method"] for r in table])
    ax.set_xlim(0, 1)
    ax.set_xlabel("share of replicates whose interval covers the true b")
    ax.set_title(f"b's intervals on paper-like records ({table[0]['replicates']} replicates)")
    ax.legend(loc="upper left", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def run(config: Config, out, executor, *, progress=None) -> StudyOutput:
    """The study into ``out``: replicates.csv, coverage.csv and coverage.png. Each
    replicate's rows are appended to replicates.partial.csv as it ends, so that a run
    stopped goes on from them; the replicates not yet there run on ``executor``, one
    each. A replicate that fails is named in the output's ``failed``; the table is made
    from the others. ``lines``: the coverage table's rows."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    partial = out / "replicates.partial.csv"  # each replicate's rows as it ends: a rerun goes on from them
    rows = _read(partial)
    done = {int(r["replicate"]) for r in rows}
    wanted = list(range(config.replicates)) if config.only is None else [k for k in config.only
                                                                       if k < config.replicates]
    todo = [] if config.rescore else [(k, config) for k in wanted if k not in done]
    if config.rescore:
        rows = rescore([r for r in rows if int(r["replicate"]) in set(wanted)], config)
    failed = []
    if progress:
        progress(len(wanted) - len(todo), len(wanted))
    for n, got in enumerate(executor.as_completed(replicate, todo), len(wanted) - len(todo) + 1):
        if got.ok:
            _append(partial, got.value)
            rows.extend(got.value)
        else:
            failed.append((f"replicate {todo[got.index][0]}", str(got.error)))
        if progress:
            progress(n, len(wanted))
    rows = [r for r in rows if int(r["replicate"]) in set(wanted) and r["method"] in config.methods]
    if not rows:
        return StudyOutput(failed=tuple(failed))
    rows.sort(key=lambda r: (int(r["replicate"]), config.methods.index(r["method"])))
    _write(out / "replicates.csv", rows)
    table = coverage(rows)
    _write(out / "coverage.csv", table)
    _figure(out / "coverage.png", table)
    return StudyOutput(written=(out / "replicates.csv", out / "coverage.csv", out / "coverage.png"),
                       failed=tuple(failed), lines=tuple(", ".join(f"{k} {v}" for k, v in r.items()) for r in table),
                       values={"coverage": table, "rows": rows})
