"""Does the default fit's own posterior hold b on records of a richer device?

The study of results/coverage-paper-like* (``studies/paper_like_coverage.py``, through
``cli.study_script``): :class:`Config` and :func:`run`.

Issue 39's item 5 measured with real chains: replicate k is one paper-like record
(``records.paper_like``: the full network, Stribeck friction, nut backlash, miscalibrated
sensors, coloured noise; one laboratory drawn per replicate from seed ``seed0 + k``),
of flywheel setting and drive frequency ``device.grid_case(k)`` (every 27 replicates
hold each setting at each frequency once, the frequencies interleaved), fitted by
``fit_record`` as ``bayes-inerter fit`` runs it (the default likelihood, each chain to the
convergence rule, at most ``max_steps``). Each replicate writes one JSON into
``out``/replicates (a run that stops continues where it stopped: rerun the command);
``summarise`` writes coverage.csv (coverage where b is identified, and again among
the converged chains alone) and replicates.csv from them.

Per replicate: b's posterior median, its 94 % and 50 % highest-density intervals and
whether they hold the true b (Table 2's, which the generator uses), whether the fit
calls b identified (``FitResult.b_interval.identified``), the chain's state and seconds;
in replicates.csv also b's error beside the part its laboratory's sensor gains explain
(``with_errors``), so a bias of the likelihood is not confused with a laboratory's
miscalibrated sensors. Where the fit samples the sensors' gain ratio, also b / gain's
intervals, held against b g_F / g_a: b's own intervals are widened by the gain's prior,
which the generator's sensors are drawn from, so they alone cannot tell whether the
part the record decides is calibrated.
Also b with the model-form error drawn after the likelihood from the same chain
(``summaries.model_form``, a candidate: each draw of b times e^eps), its intervals held
against the true b, so that one run measures it beside the posterior's own.

``family`` makes the records of a device family the likelihood was not designed on
(``FAMILIES``: a wider nut backlash, a larger break-away, noise coloured at 20 Hz, the two
sensors' delays unequal); a folder keeps one family. ``model`` fits another model than the
paper's two-port one (``MOTION_MODELS``: the richer ones, which hold some of those
effects); a folder keeps one model. ``likelihood`` (``name=value,...``)
fits with those of ``LikelihoodSettings`` changed (``input_noise=16``,
``law_beyond_viscous=false``), a candidate beside the default on the same seeds; a
folder keeps one likelihood, its every setting recorded in each replicate (a change of
the library's default starts a new folder). ``tempering`` T fits with parallel tempering
(``sampler.Tempering``, T temperatures down to ``hottest_beta``), None with the ensemble
alone (the folders' default, and ``fit``'s); a folder keeps one sampler.
``tau_rtol`` stops the chains with that tolerance of the convergence rule
(``Convergence.tau_rtol``; a folder keeps one, each replicate names it, ``stop_rule``).
``freq`` F runs only the replicates driven at F Hz; ``parity`` "odd" or "even" only the
replicates of odd or even k (a method's settings chosen on one half are measured on the
other). ``duration`` D makes every record D s long, ramp included (the paper's are 10 s:
3 steady periods at 0.5 Hz, results/record-length); a folder keeps one length. ``work`` W
runs replicate k's fit in W/<k> (``fit_record``'s folder, its checkpoint included),
removed once the replicate is written: a run stopped mid-chain continues that chain when
run again, where the default (None, a temporary folder) starts it over. The folder is stamped with the run's output folder, cap and
tolerance, and one stamped otherwise is refused. A continued replicate's ``seconds``
count only its last run; ``sampling_s_all_runs`` over ``steps_timed`` is its seconds per
step (a run stopped before it wrote fit.json leaves its steps untimed).
"""

from __future__ import annotations

import csv
import dataclasses
import math
import shutil
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..device import FREQUENCIES_HZ, grid_case, paper_parameters
from ..inference.fit import fit_record
from ..inference.sampling.adaptation import Adaptation
from ..inference.sampling.identity import LATER_ADAPTATION, stored_likelihood
from ..inference.sampling.moves.block import PARTNERS
from ..inference.posterior.likelihood import LikelihoodSettings, settings_changes
from ..inference.posterior.model import MOTION_MODELS
from ..inference.sampling.tempering import Tempering
from ..inference.summaries.model_form import ModelFormError, accel_amplitude
from ..inference.summaries.results import hdi
from ..records.paper_like import PaperLike, laboratory, paper_like_record
from . import stop_rule
from .calibration import fit_folder, stamped_folder
from .manifest import source_commit
from .output import StudyOutput
from .replicate_store import finished, load_replicates, write_replicate

__all__ = ["Config", "run", "FAMILIES", "LEVELS", "PARITIES", "FORM_STREAM", "replicate", "with_errors", "summarise",
           "likelihood_settings", "pairs"]

LEVELS = (0.94, 0.5)
PARITIES = ("even", "odd")  # index k % 2
#: Device families: the default paper-like device, and the held-out ones of issue 39 (item 5),
#: each the default with one effect changed (none of them used to choose a setting).
FAMILIES = {
    "default": PaperLike(),
    "backlash": PaperLike(backlash=(5e-6, 1e-5)),  # m: a nut backlash 5 to 10 um
    "breakaway": PaperLike(ratio=(1.5, 1.5)),  # Stribeck break-away 1.5 times the Coulomb force
    "corner20": PaperLike(noise_corner=20.0),  # Hz: noise coloured inside the drive's harmonics
    "delays": PaperLike(force_delay=2e-4, accel_delay=7e-4),  # s: the load cell's and accelerometer's latencies
}


def likelihood_settings(text: str) -> dict:
    """Every field of the ``LikelihoodSettings`` that ``--likelihood text`` fits with:
    what a replicate records, so that a folder never mixes two likelihoods, not even
    when the library's default changes between its chunks."""
    return dataclasses.asdict(LikelihoodSettings(**settings_changes(text)))


def replicate(k: int, seed0: int, max_steps: int, family: str = "default", commit: str = "",
              likelihood: str = "default", tempering: Tempering | None = None,
              tau_rtol: float | None = None, duration: float | None = None, folder=None,
              block_partners: str | None = None, model: str = "two-port") -> dict:
    """Replicate ``k`` fitted (see the module docstring). ``folder``: where its fit runs,
    continued from the checkpoint there if an earlier run left one; the caller removes it
    once the replicate is written (None: a temporary folder, nothing kept if stopped).
    ``block_partners``: the adaptation's (``Adaptation.block_partners``; None: its default).
    ``model``: the model fitted (``fit_record``'s; the paper's two-port one by default)."""
    adaptation = Adaptation() if block_partners is None else Adaptation(block_partners=block_partners)
    setting, freq = grid_case(k)
    seed = seed0 + k
    rec = paper_like_record(setting, freq, seed=seed, device=FAMILIES[family], duration=duration)
    b_true = paper_parameters(setting).b
    t0 = time.perf_counter()
    with fit_folder(folder) as where:
        res = fit_record(rec, where, model=model, seed=seed, plots=False,
                         likelihood=LikelihoodSettings(**settings_changes(likelihood)),
                         convergence=stop_rule.convergence(max_steps, tau_rtol), tempering=tempering,
                         adaptation=adaptation)
    b = np.asarray(res.idata.posterior["b"]).ravel()
    tau = np.asarray(list(res.tau.values()) if isinstance(res.tau, dict) else res.tau, dtype=float)
    out = {"replicate": k, "setting": setting, "freq_hz": freq, "seed": seed, "b_true": b_true,
           "b_median": float(np.median(b)), "converged": bool(res.converged), "steps": int(res.iterations),
           "tau_max": float(np.nanmax(tau)) if np.any(np.isfinite(tau)) else None,
           "seconds": round(time.perf_counter() - t0, 1), "identified": bool(res.b_interval.identified),
           "phi": res.b_interval.phi, "commit": commit, "family": family, "likelihood": likelihood,
           "likelihood_settings": likelihood_settings(likelihood), "tau_rtol": stop_rule.resolved(tau_rtol),
           "max_steps": int(max_steps)}
    timings = getattr(res, "timings", None) or {}
    if "sampling_all_runs" in timings and "steps_timed" in timings:  # seconds per step across runs
        out["sampling_s_all_runs"] = round(float(timings["sampling_all_runs"]), 1)
        out["steps_timed"] = int(timings["steps_timed"])
    by_parameter = getattr(res, "tau_by_parameter", None)
    if by_parameter:  # which parameters are slow, readable without fitting again (absent before)
        out["tau_by_parameter"] = {n: round(float(t), 1) for n, t in by_parameter.items()}
    if tempering is not None:  # absent for the ensemble alone, as in the replicates written before the option
        out.update(tempering=_ladder_entry(tempering), swap_rates=res.tempering["swap_rates"])
    if duration is not None:  # absent for the paper's 10 s, as in the replicates written before the option
        out["duration_s"] = float(duration)
    if model != "two-port":  # absent for the paper's model, as in the replicates written before the option
        out["model"] = model
    if adaptation.block_partners != EARLIER_PARTNERS:  # absent for random blocks, as before the option
        out["block_partners"] = adaptation.block_partners
    for level in LEVELS:
        lo, hi = hdi(b, level)
        key = round(100 * level)
        out[f"hdi{key}"] = [float(lo), float(hi)]
        out[f"covered{key}"] = bool(lo <= b_true <= hi)
        out[f"width{key}_pct"] = 100.0 * (hi - lo) / b_true
    posterior = res.idata.posterior
    # the device's b with the model-form error drawn after the likelihood (summaries.model_form),
    # from the same chain, so that one run measures the posterior's b and this one side by side
    device_b = ModelFormError().draws(b, _coulomb(posterior, b.shape), accel_amplitude(rec, freq),
                                      np.random.default_rng([seed, FORM_STREAM]))
    for level in LEVELS:
        lo, hi = hdi(device_b, level)
        out[f"hdi{round(100 * level)}_form"] = [float(lo), float(hi)]
    if "gain" in posterior:  # b beyond the sensors' calibration, what the record itself tells (absent before)
        ratio = b / np.asarray(posterior["gain"]).ravel()
        for level in LEVELS:
            lo, hi = hdi(ratio, level)
            out[f"hdi{round(100 * level)}_b_over_gain"] = [float(lo), float(hi)]
    return out


#: The random stream of a replicate's model-form draws (with its laboratory's seed).
FORM_STREAM = 7


def _coulomb(posterior, shape) -> np.ndarray:
    """The Coulomb forces f1_0 + f2_0 at each draw (N; 0 for a model without them)."""
    if "f_0" in posterior:
        return np.asarray(posterior["f_0"]).ravel()
    if "f1_0" in posterior:
        return np.asarray(posterior["f1_0"]).ravel() + np.asarray(posterior["f2_0"]).ravel()
    return np.zeros(shape)


def _ladder_entry(tempering: Tempering | None) -> list | None:
    """A replicate's ``tempering`` entry: [temps, hottest beta], or None untempered."""
    return None if tempering is None else [tempering.temps, tempering.beta_min]


def _run(job) -> dict:
    k, out, config, commit = job
    folder = _work_folder(config, out, k)
    got = replicate(k, config.seed0, config.max_steps, config.family, commit, config.likelihood, config.ladder(),
                    config.tau_rtol, config.duration, folder, config.block_partners, config.model)
    write_replicate(out, k, got, indent=1)
    if folder is not None:  # only once the replicate is on disk: a crash before keeps the chain
        shutil.rmtree(folder, ignore_errors=True)
    return got


#: Block moves before ``Adaptation.block_partners`` existed (as a checkpoint's,
#: ``identity.LATER_ADAPTATION``): a replicate without the entry was fitted with them.
EARLIER_PARTNERS = LATER_ADAPTATION["block_partners"]


def _work_folder(config: Config, out: Path, k: int) -> Path | None:
    """Replicate ``k``'s folder in ``config.work`` (None without one), stamped with the
    study it runs for (``calibration.stamped_folder``): its output folder, cap and
    tolerance, which the chain's own checkpoint does not hold."""
    if config.work is None:
        return None
    return stamped_folder(Path(config.work) / f"{k:04d}", {
        "out": str(Path(out).resolve()), "max_steps": int(config.max_steps),
        "tau_rtol": stop_rule.resolved(config.tau_rtol)})


def with_errors(r: dict) -> dict:
    """A replicate with b's error beside the part of it its laboratory's sensors explain.

    A load cell that reads g_F times the force and an accelerometer that reads g_a times
    the acceleration make any model's b come out b g_F / g_a: ``gain_ratio_pct`` is
    100 (g_F / g_a - 1) of the replicate's laboratory (``records.paper_like.laboratory``),
    which the fit cannot learn from the record (it samples the ratio with its prior), and
    ``error_beyond_gain_pct`` the error that is left after it."""
    lab = laboratory(r["seed"], device=FAMILIES[r.get("family", "default")])
    gain = lab.force_gain / lab.accel_gain
    out = {**r, "error_pct": 100.0 * (r["b_median"] / r["b_true"] - 1.0), "gain_ratio_pct": 100.0 * (gain - 1.0),
           "error_beyond_gain_pct": 100.0 * (r["b_median"] / (r["b_true"] * gain) - 1.0)}
    apparent = r["b_true"] * gain  # what b / gain estimates: the sampled gain stands for g_a / g_F
    for key in ("94", "50"):
        if f"hdi{key}_form" in r:  # b with the model-form error, against the device's b
            lo, hi = r[f"hdi{key}_form"]
            out[f"covered{key}_form"] = bool(lo <= r["b_true"] <= hi)
            out[f"width{key}_form_pct"] = 100.0 * (hi - lo) / r["b_true"]
        if f"hdi{key}_b_over_gain" in r:
            lo, hi = r[f"hdi{key}_b_over_gain"]
            out[f"covered{key}_b_over_gain"] = bool(lo <= apparent <= hi)
            out[f"width{key}_b_over_gain_pct"] = 100.0 * (hi - lo) / apparent
    return out


#: The intervals a replicate may hold beside b's own, by their keys' suffix: b / gain's
#: (against b g_F / g_a) and b with the model-form error's (against b), in the tables' order.
OTHER_INTERVALS = ("_b_over_gain", "_form")


def summarise(out: Path) -> list[dict]:
    reps = [with_errors(r) for r in finished(out)]
    with (out / "replicates.csv").open("w", newline="") as f:
        fields = ["replicate", "setting", "freq_hz", "seed", "b_true", "b_median", "hdi94", "hdi50", "covered94",
                  "covered50", "width94_pct", "identified", "converged", "steps", "tau_max", "seconds", "phi",
                  "error_pct", "gain_ratio_pct", "error_beyond_gain_pct"]
        # the other intervals only in folders whose replicates hold them, so older tables are remade unchanged
        held_by = [suffix for suffix in OTHER_INTERVALS if any(f"covered94{suffix}" in r for r in reps)]
        fields += [f"{what}{key}{suffix}{unit}" for suffix in held_by for key in ("94", "50")
                   for what, unit in (("covered", ""), ("width", "_pct"))]
        w = csv.DictWriter(f, fields)
        w.writeheader()
        for r in reps:
            w.writerow({k: r.get(k) for k in fields})
    rows = []
    for freq in (*FREQUENCIES_HZ, None):
        sel = [r for r in reps if freq is None or r["freq_hz"] == freq]
        if not sel:
            continue
        ident = [r for r in sel if r["identified"]]
        row = {"freq_hz": "all" if freq is None else freq, "replicates": len(sel), "identified": len(ident),
               "converged": sum(r["converged"] for r in sel)}
        for key, nominal in (("94", 0.94), ("50", 0.5)):
            n = len(ident)
            row[f"coverage{key}"] = round(sum(r[f"covered{key}"] for r in ident) / n, 3) if n else ""
            row[f"se{key}"] = round(math.sqrt(nominal * (1 - nominal) / n), 3) if n else ""
            row[f"median_width{key}_pct"] = round(float(np.median([r[f"width{key}_pct"] for r in ident])), 2) if n \
                else ""
        good = [r for r in ident if r["converged"]]  # what the issue asks of: converged chains
        row["converged_identified"] = len(good)
        for key in ("94", "50"):
            row[f"coverage{key}_converged"] = round(sum(r[f"covered{key}"] for r in good) / len(good), 3) if good else ""
        for suffix in held_by:  # among the converged replicates that hold them
            held = [r for r in good if f"covered94{suffix}" in r]
            row[f"converged_with{suffix}"] = len(held)
            for key in ("94", "50"):
                row[f"coverage{key}{suffix}_converged"] = \
                    round(sum(r[f"covered{key}{suffix}"] for r in held) / len(held), 3) if held else ""
            row[f"median_width94{suffix}_pct"] = \
                round(float(np.median([r[f"width94{suffix}_pct"] for r in held])), 2) if held else ""
        row["median_seconds"] = round(float(np.median([r["seconds"] for r in sel])), 1)
        for key in ("error_pct", "error_beyond_gain_pct"):
            row[f"mean_{key}"] = round(float(np.mean([r[key] for r in sel])), 2)
        rows.append(row)
    _write_rows(out / "coverage.csv", rows)
    return rows


def _write_rows(path: Path, rows: list[dict]) -> None:
    with path.open("w", newline="") as f:
        w = csv.DictWriter(f, list(rows[0]))
        w.writeheader()
        w.writerows(rows)


_PAIRED = ("error_pct", "covered94", "covered50", "width94_pct", "width50_pct", "converged", "steps", "tau_max",
           "seconds")


def pairs(out: Path, against: Path) -> list[dict]:
    """The replicates of ``out`` beside the same replicates of ``against`` (the same
    laboratory seed, setting and frequency, fitted otherwise), one row each, written to
    ``out``/pairs.csv: each fit's b error, coverage, widths, chain; ``*_against`` is
    ``against``'s. Rows: the pairs, then one per frequency and one for all with the
    counts held, the mean errors and the median ratios of the widths and of tau.
    ValueError where a replicate of both folders is not the same record."""
    out, against = Path(out), Path(against)
    mine, theirs = load_replicates(out), load_replicates(against)
    rows = []
    for k in sorted(mine):
        if k not in theirs:
            continue
        a, b = with_errors(mine[k]), with_errors(theirs[k])
        same = ("seed", "setting", "freq_hz", "family")
        if any(a.get(f, "default") != b.get(f, "default") for f in same):
            raise ValueError(f"replicate {k} is not the same record in {out} and {against}: "
                             + ", ".join(f"{f} {a.get(f)} against {b.get(f)}" for f in same))
        row = {f: a[f] for f in ("replicate", "setting", "freq_hz", "seed", "identified")}
        row["identified_against"] = b["identified"]
        for f in _PAIRED:
            row[f], row[f"{f}_against"] = a.get(f), b.get(f)
        rows.append(row)
    if not rows:
        raise ValueError(f"no replicate of {out} is in {against}")
    summary = []
    for freq in (*FREQUENCIES_HZ, None):
        sel = [r for r in rows if freq is None or r["freq_hz"] == freq]
        if not sel:
            continue
        row = {"replicate": "all", "freq_hz": "all" if freq is None else freq, "pairs": len(sel)}
        for side in ("", "_against"):
            row[f"held94{side}"] = sum(bool(r[f"covered94{side}"]) for r in sel)
            row[f"held50{side}"] = sum(bool(r[f"covered50{side}"]) for r in sel)
            row[f"converged{side}"] = sum(bool(r[f"converged{side}"]) for r in sel)
            row[f"mean_error_pct{side}"] = round(float(np.mean([r[f"error_pct{side}"] for r in sel])), 3)
            row[f"median_abs_error_pct{side}"] = round(float(np.median([abs(r[f"error_pct{side}"]) for r in sel])), 3)
        for f in ("width94_pct", "width50_pct", "tau_max", "seconds"):
            got = [r[f] / r[f"{f}_against"] for r in sel if r[f] and r[f"{f}_against"]]
            row[f"median_ratio_{f}"] = round(float(np.median(got)), 3) if got else ""
        summary.append(row)
    _write_rows(out / "pairs.csv", rows)
    _write_rows(out / "pairs_summary.csv", summary)
    return summary


@dataclass(frozen=True)
class Config:
    """What ``studies/paper_like_coverage.py`` is asked (see the module docstring)."""

    replicates: int = field(default=27, metadata={"help": "replicates 0 to N - 1"})
    seed0: int = field(default=1000, metadata={"help": "replicate k's laboratory seed is seed0 + k"})
    max_steps: int = field(default=20000, metadata={"help": "each chain's cap"})
    family: str = field(default="default", metadata={"choices": tuple(FAMILIES), "help": "the device family"})
    model: str = field(default="two-port", metadata={
        "choices": MOTION_MODELS, "help": "the model fitted (default: the paper's two-port one); a folder keeps one"})
    likelihood: str = field(default="default", metadata={
        "help": "LikelihoodSettings changed from the default, NAME=VALUE,... (values as JSON)"})
    freq: float | None = field(default=None, metadata={"help": "only the replicates driven at this frequency, Hz"})
    parity: str | None = field(default=None, metadata={
        "choices": PARITIES, "help": "only the replicates of odd or even k (default: all)"})
    tempering: int | None = field(default=None, metadata={"help": "parallel tempering's temperatures (default: none)"})
    hottest_beta: float = field(default=Tempering.beta_min, metadata={"help": "the tempering ladder's hottest beta"})
    tau_rtol: float | None = field(default=None, metadata={
        "help": "the convergence rule's tolerance of tau's growth between checks (default: the package's, "
                "Convergence.tau_rtol); a folder keeps one"})
    duration: float | None = field(default=None, metadata={
        "help": "each record's length, s, ramp included (default: the paper's 10 s); a folder keeps one"})
    work: str | None = field(default=None, metadata={
        "help": "where each replicate's fit runs until done, continued there by the next run if this one stops "
                "(default: a temporary folder, a stopped fit starts over)"})
    block_partners: str = field(default=Adaptation().block_partners, metadata={
        "choices": PARTNERS, "help": "how the adaptation's block moves pick their coordinates "
                                     "(Adaptation.block_partners); a folder keeps one"})
    summarise: bool = field(default=False, metadata={"help": "only write the tables from the replicates there"})
    against: str | None = field(default=None, metadata={
        "help": "with summarise: a folder of the same replicates fitted otherwise; also writes pairs.csv and "
                "pairs_summary.csv, replicate by replicate"})

    def __post_init__(self) -> None:
        if not (isinstance(self.replicates, int) and self.replicates >= 1):
            raise ValueError(f"replicates must be a whole number of at least 1, got {self.replicates!r}")
        if self.family not in FAMILIES:
            raise ValueError(f"unknown family {self.family!r}; choose from {', '.join(FAMILIES)}")
        if self.model not in MOTION_MODELS:
            raise ValueError(f"unknown model {self.model!r}; choose from {', '.join(MOTION_MODELS)}")
        if self.freq is not None and self.freq not in FREQUENCIES_HZ:
            raise ValueError(f"freq must be one of {', '.join(f'{f:g}' for f in FREQUENCIES_HZ)} Hz, got {self.freq:g}")
        if self.parity is not None and self.parity not in PARITIES:
            raise ValueError(f"parity must be one of {', '.join(PARITIES)}, got {self.parity!r}")
        if self.duration is not None and not self.duration > 0:
            raise ValueError(f"duration must be a positive number of seconds, got {self.duration!r}")
        if self.block_partners not in PARTNERS:
            raise ValueError(f"block_partners must be one of {', '.join(PARTNERS)}, got {self.block_partners!r}")
        if self.against is not None and not self.summarise:
            raise ValueError("against compares finished replicates: give it with summarise")
        self.ladder()  # its own check of the ladder
        try:
            settings_changes(self.likelihood)
        except ValueError as exc:
            raise ValueError(f"likelihood {self.likelihood!r}: {exc}") from None

    def wants(self, k: int) -> bool:
        """Whether replicate ``k`` is among those asked (``freq``, ``parity``)."""
        return ((self.freq is None or grid_case(k)[1] == self.freq)
                and (self.parity is None or k % 2 == PARITIES.index(self.parity)))

    def ladder(self) -> Tempering | None:
        """The fit's tempering (None: the ensemble alone)."""
        return Tempering.of(self.tempering, self.hottest_beta)


def _table_line(row: dict) -> str:
    """A table's row as the line the script prints."""
    return ", ".join(f"{k} {v}" for k, v in row.items())


def _line(r: dict) -> str:
    return (f"{r['setting']} {r['freq_hz']:g} Hz seed {r['seed']}: b {r['b_median']:.0f} (true {r['b_true']:.0f}), "
            f"94 % {'holds' if r['covered94'] else 'MISSES'}, {'identified' if r['identified'] else 'not identified'}, "
            f"converged {r['converged']}, {r['seconds']} s")


def _refuse_mixing(found: list[dict], config: Config, out: Path) -> None:
    """ValueError naming the first setting in which a replicate in ``out`` differs from
    what ``config`` asks (family, model, likelihood, sampler, record length, stopping rule):
    their coverage counts would not belong to one configuration."""
    ladder = config.ladder()
    families = sorted({r.get("family", "default") for r in found})
    partners = sorted({r.get("block_partners", EARLIER_PARTNERS) for r in found} - {config.block_partners})
    asked = "the ensemble alone" if ladder is None else ladder.describe()
    length = "the paper's 10 s" if config.duration is None else f"{config.duration:g} s"
    checks = (
        (lambda r: r.get("family", "default") == config.family,
         f"of family {', '.join(families)}, not {config.family}"),
        (lambda r: r.get("model", "two-port") == config.model,
         f"of the model {', '.join(sorted({r.get('model', 'two-port') for r in found}))}, not {config.model}"),
        (lambda r: stored_likelihood(r.get("likelihood_settings")) == likelihood_settings(config.likelihood),
         f"fitted with other likelihood settings than {config.likelihood!r} gives today (or made before "
         "replicates recorded them)"),
        (lambda r: r.get("tempering") == _ladder_entry(ladder), f"fitted with another sampler than {asked}"),
        (lambda r: r.get("duration_s") == config.duration, f"of records of another length than {length}"),
        (lambda r: r.get("block_partners", EARLIER_PARTNERS) == config.block_partners,
         f"fitted with other block moves than {config.block_partners!r} (give --block-partners "
         f"{' or '.join(partners)} to go on with theirs)"),
    )
    for same, what in checks:
        if not all(same(r) for r in found):
            raise ValueError(f"{out} holds replicates {what}; choose another folder")
    stop_rule.check_folder(found, config.tau_rtol, out)


def run(config: Config, out, executor, *, progress=None) -> StudyOutput:
    """The replicates not yet in ``out``/replicates fitted on ``executor`` (one each),
    then replicates.csv and coverage.csv from every replicate there. A folder keeps one
    family, one likelihood's settings and one sampler: a run asking others is refused
    (ValueError).
    ``lines``: one per replicate fitted, then the coverage rows."""
    out = Path(out)
    found = finished(out)
    if not config.summarise:
        _refuse_mixing(found, config, out)
    lines, failed = [], []
    if not config.summarise:
        commit = source_commit() or ""  # the code this run loaded, read once: HEAD may move while it runs
        wanted = [k for k in range(config.replicates) if config.wants(k)]
        done = {r["replicate"] for r in found}
        todo = [k for k in wanted if k not in done]
        jobs = [(k, out, config, commit) for k in todo]
        if progress:
            progress(len(wanted) - len(todo), len(wanted))
        for i, got in enumerate(executor.as_completed(_run, jobs), len(wanted) - len(todo) + 1):
            if got.ok:
                lines.append(_line(got.value))
            else:  # one replicate's failure is reported, the rest go on
                failed.append((f"replicate {jobs[got.index][0]}", str(got.error)))
            if progress:
                progress(i, len(wanted))
    if not finished(out):
        raise ValueError(f"{out} holds no finished replicate; run without summarise first")
    rows = summarise(out)
    lines += map(_table_line, rows)
    written, values = (out / "replicates.csv", out / "coverage.csv"), {"coverage": rows}
    if config.against is not None:
        values["pairs"] = pairs(out, Path(config.against))
        lines += map(_table_line, values["pairs"])
        written += (out / "pairs.csv", out / "pairs_summary.csv")
    return StudyOutput(written=written, failed=tuple(failed), lines=tuple(lines), values=values)
