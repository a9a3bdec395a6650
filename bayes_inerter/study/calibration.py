"""Simulation-based calibration (Talts et al. 2018): do the intervals hold the truth as
often as they say?

Each replicate draws parameters from the prior, makes data from them, samples the
posterior exactly as a user's fit does (optimiser start, Laplace ensemble, emcee), and
records the rank of every true value among L posterior draws. With a correct sampler
and a model that made the data, each rank is uniform on 0..L and each central q
interval holds the truth with probability q.

Two ways to make the data (``truth``):

- ``"model"``: the likelihood's own model: the low-passed simulated acceleration on
  the likelihood's grid plus AR(1) noise with the drawn sigma and rho. The force is a
  fixed generated record's (an exogenous input). This tests the sampler.
- ``"generator"``: the realistic record generator (servo, sensors, anti-aliasing, and
  optionally a Stribeck hump or backlash through ``generator``), driven at the drawn
  physical parameters; its noise is the sensors', so sigma and rho have no true value
  and only the physical parameters are ranked. This tests the model as well, and shows
  what the AR(1) residual option (``residual="ar1"`` against ``"iid"``) does.

**Assumptions** (documented defaults, all options): the calibration prior
(:data:`SBC_PRIORS`) is log-normal around the paper's values (log-sd 0.5) for the
physical sums, uniform shares, sigma log-uniform on [1e-3, 3e-2] m/s^2 and rho uniform
on [0, 0.9]: the default priors span orders of magnitude where most draws are devices
nobody builds and chains need far longer to mix. A draw the simulator refuses is drawn
again (the posterior gives those parameters zero density too). Chains are a fixed
number of steps (``steps``); a replicate whose chain did not mix shows in the ranks.
"""

from __future__ import annotations

import contextlib
import copy
import csv
import json
import math
import shutil
import tempfile
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path

import numpy as np

from ..device import TABLE_I, paper_parameters
from ..executor import make_executor
from ..inference.posterior.model import LikelihoodSettings, PosteriorModel
from ..inference.posterior.priors import LogNormal, LogUniform, Uniform
from ..inference.summaries.results import ar1_noise, posterior_sample
from ..inference.sampling.identity import LATER_ADAPTATION, LATER_TEMPERING, stored_likelihood
from ..inference.sampling.sampler import run_sampler
from ..records.generator import GeneratorSettings, generate_record
from ..simulate import SimulationError
from .replicate_store import load_replicates, write_replicate

__all__ = ["SBC_PRIORS", "CalibrationSettings", "replicate", "run_replicates", "fit_folder", "stamped_folder",
           "work_stamp", "run_calibration", "coverage_table", "compare_calibrations", "Config", "run", "case_name",
           "failed_items"]

_P = paper_parameters("A1")
#: The calibration prior (see module docstring).
SBC_PRIORS = {
    "b": LogNormal(_P.b, 0.5),
    "f_0": LogNormal(_P.f1_0 + _P.f2_0, 0.5),
    "c_f": LogNormal(_P.c_f1 + _P.c_f2, 0.5),
    "c_n": LogNormal(TABLE_I["c_n"], 0.5),
    "k_n": LogNormal(TABLE_I["k_n"], 0.5),
    "c_B": LogNormal(TABLE_I["c_B"], 0.5),
    "k_B": LogNormal(TABLE_I["k_B"], 0.5),
    "sigma": LogUniform(1e-3, 3e-2),
    "rho": Uniform(0.0, 0.9),
}


@dataclass(frozen=True)
class CalibrationSettings:
    """One calibration run.

    Attributes
    ----------
    truth : "model" or "generator" (see module docstring).
    setting, freq : the flywheel setting (masses) and drive frequency of the records.
    generator : how records are made (the force template, and the data for "generator");
        default 2 s records with a 0.6 s ramp, so a hundred replicates fit in an hour on
        two cores (an **assumption** of the calibration: shorter than the paper's records).
    steps : steps per chain (default 800).
    draws : L, the posterior draws each truth is ranked among (default 99).
    residual : the likelihood's residual model, "ar1" (default) or "iid".
    seed : replicate k uses the seed sequence (seed, k).
    """

    truth: str = "model"
    setting: str = "A1"
    freq: float = 1.0
    generator: GeneratorSettings = field(default_factory=lambda: GeneratorSettings(duration=2.0, ramp=0.6))
    steps: int = 800
    draws: int = 99
    residual: str = "ar1"
    seed: int = 0

    def __post_init__(self) -> None:
        if self.truth not in ("model", "generator"):
            raise ValueError(f"truth must be 'model' or 'generator', got {self.truth!r}")
        if not (isinstance(self.steps, int) and self.steps >= 20):
            raise ValueError(f"steps must be a whole number of at least 20, got {self.steps!r}")
        if not (isinstance(self.draws, int) and self.draws >= 9):
            raise ValueError(f"draws must be a whole number of at least 9, got {self.draws!r}")

    def model(self, record) -> PosteriorModel:
        return PosteriorModel(record, priors=SBC_PRIORS, likelihood=LikelihoodSettings(residual=self.residual))

    def replicate(self, k: int) -> dict:
        return replicate(self, k)


def _draw(model: PosteriorModel, rng: np.random.Generator) -> np.ndarray:
    return np.array([model.all_priors[n].sample(rng) for n in model.names])


def _ranked_names(cs: CalibrationSettings, model: PosteriorModel) -> list[str]:
    return model.names if cs.truth == "model" else model.names[: model.n_phys]


def replicate(cs: CalibrationSettings, k: int, checkpoint=None) -> dict:
    """Replicate ``k``: the truth's rank among ``cs.draws`` posterior draws per parameter,
    whether the central 50 % and 90 % intervals hold it, and the chain's diagnostics."""
    rng = np.random.default_rng([cs.seed, k])
    template = generate_record(paper_parameters(cs.setting), cs.freq, settings=cs.generator,
                               rng=np.random.default_rng([cs.seed, 10**6]), setting_name=cs.setting)
    base = cs.model(template)
    for redraws in range(100):
        theta = _draw(base, rng)
        try:
            if cs.truth == "model":
                sim = base.simulate_lp(theta)
                if not np.all(np.isfinite(sim)):
                    continue
                sigma, rho = base.noise(theta)
                model = copy.copy(base)
                model.observed = sim[base.grid] + ar1_noise(rng, len(base.grid), sigma, rho)
            else:
                rec = generate_record(base.parameters(theta), cs.freq, settings=cs.generator, rng=rng,
                                      setting_name=cs.setting)
                model = cs.model(rec)
        except (SimulationError, ValueError):
            continue
        break
    else:
        raise RuntimeError("100 prior draws in a row could not be simulated")
    path = Path(checkpoint) if checkpoint else None
    if path is None:
        import tempfile

        tmp = tempfile.TemporaryDirectory()
        path = Path(tmp.name) / "chain.h5"
    run = run_sampler(model, path, steps=cs.steps, seed=int(rng.integers(2**31)), fresh=True)
    sample = posterior_sample(model, run)
    flat = sample.theta.reshape(-1, model.ndim)
    if len(flat) < cs.draws:
        raise RuntimeError(f"only {len(flat)} posterior draws kept, fewer than the {cs.draws} to rank among")
    draws = flat[rng.choice(len(flat), cs.draws, replace=False)]
    out = {"replicate": k, "redraws": redraws, "iterations": int(run.iteration), "converged": bool(run.converged),
           "tau_max": float(np.nanmax(run.tau)) if np.any(np.isfinite(run.tau)) else None, "L": cs.draws,
           "ranks": {}, "in50": {}, "in90": {}, "truth": {}}
    for i, name in enumerate(model.names):
        if name not in _ranked_names(cs, model):
            continue
        x, t = flat[:, i], theta[i]
        out["truth"][name] = float(t)
        out["ranks"][name] = int(np.sum(draws[:, i] < t))
        for q, key in ((0.5, "in50"), (0.9, "in90")):
            lo, hi = np.quantile(x, [0.5 - q / 2, 0.5 + q / 2])
            out[key][name] = bool(lo <= t <= hi)
    return out


#: Where a replicate whose settings resume (``resumes``) runs its fit by default:
#: ``out``/.running/<k>, removed once the replicate's result is written (kept where it
#: failed; not committed: .gitignore).
#: A chain's checkpoint there is tens of megabytes: a study keeping its results small
#: gives ``run_replicates`` a ``work`` folder elsewhere.
RUNNING = ".running"


@contextlib.contextmanager
def fit_folder(folder=None):
    """Where a replicate's fit runs: ``folder``/fit, kept on leaving so that a stopped
    run continues its chain there (the caller removes ``folder`` once the replicate is
    written, as :func:`run_replicates` does), or for None a fit folder in a temporary
    folder, removed on leaving (nothing kept if stopped)."""
    if folder is not None:
        yield Path(folder) / "fit"
        return
    with tempfile.TemporaryDirectory() as tmp:
        yield Path(tmp) / "fit"


#: The file in a replicate's work folder that names the run its chain belongs to.
WORK_STAMP = "study.json"


def stamped_folder(folder, stamp: dict, *, create: bool = True) -> Path:
    """``folder``, where a replicate's fit runs, checked against the run it is for:
    ``stamp`` (JSON-able; the run's output folder and what the chain's checkpoint does
    not hold, such as its cap and tolerance). A folder stamped otherwise in what
    ``stamp`` names is refused (ValueError), so that two runs sharing a work folder, or
    a rerun with another cap where the cap is stamped, never continue each other's
    chains; a folder without a stamp (an earlier version's) is taken. With ``create``,
    the folder is made and stamped where it is not."""
    folder = Path(folder)
    path = folder / WORK_STAMP
    if path.exists():
        found = json.loads(path.read_text())
        differ = ", ".join(f"{key} {found.get(key)!r} there, {value!r} here" for key, value in stamp.items()
                           if found.get(key) != value)  # what ``stamp`` names: a key it no longer holds is let be
        if differ:
            raise ValueError(f"{folder} holds a replicate's chain for another run ({differ}); "
                             "give another work folder or remove that one")
    elif create:
        folder.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(stamp) + "\n")
    return folder


def work_stamp(cs, out) -> dict:
    """The stamp of ``cs``'s run into ``out`` (:func:`stamped_folder`): the output
    folder, and the tolerance where ``cs`` has one. settings.json pins the rest of
    ``out``'s settings; the cap is left out, because a chain stopped under a cap goes on
    as the same chain under the one :func:`.study_calibration.raise_cap` raises it to."""
    return {"out": str(Path(out).resolve()), **({"tau_rtol": cs.tau_rtol} if hasattr(cs, "tau_rtol") else {})}


def _worker(args):
    cs, k, out, work = args
    folder = (stamped_folder(work / f"{k:04d}", work_stamp(cs, out)) if getattr(cs, "resumes", False)
              else None)
    try:
        result = cs.replicate(k) if folder is None else cs.replicate(k, folder)
    except Exception as exc:  # one replicate's failure is reported, the others go on
        result = {"replicate": k, "error": f"{type(exc).__name__}: {exc}"}
    write_replicate(out, k, result)
    if folder is not None and "error" not in result:  # only once the result is on disk
        shutil.rmtree(folder, ignore_errors=True)
    return result


#: Settings added after runs were saved without them, with the value those runs had
#: (which need not stay the default): a study's block moves, as a checkpoint's
#: (``identity.LATER_ADAPTATION``), were random before ``block_partners`` existed.
LATER_SETTINGS = {"block_partners": LATER_ADAPTATION["block_partners"]}


def _with_defaults(saved: dict, defaults: dict) -> dict:
    """Settings saved before a field existed hold no value for it: it had its default
    (a tempering ladder's too, :data:`..inference.sampling.identity.LATER_TEMPERING`,
    where the study's own default is no ladder), or for those of :data:`LATER_SETTINGS`
    the value it names."""
    out = {**{k: v for k, v in LATER_SETTINGS.items() if k in defaults}, **saved}
    if isinstance(out.get("tempering"), dict):
        out["tempering"] = {**LATER_TEMPERING, **out["tempering"]}
    for k, v in defaults.items():
        if k not in out:
            out[k] = v
        elif isinstance(v, dict) and isinstance(out[k], dict):
            out[k] = _with_defaults(out[k], v)
    return out


def _stored_settings(cs) -> dict:
    """``cs`` as settings.json holds it (JSON data)."""
    return json.loads(json.dumps(asdict(cs), default=str))


def _saved_settings(path: Path) -> dict:
    """settings.json as saved, a likelihood saved before some of its settings existed
    holding the values in effect then (``identity.stored_likelihood``), not today's
    defaults."""
    saved = json.loads(path.read_text())
    if isinstance(saved.get("likelihood"), dict):
        saved["likelihood"] = stored_likelihood(saved["likelihood"])
    return saved


def run_replicates(cs, out, replicates: int, *, processes: int = 1, progress=None, work=None,
                   executor=None) -> list[dict]:
    """Run replicates 0..``replicates``-1 of ``cs`` (any frozen settings dataclass with a
    ``replicate(k)`` method) into ``out``/replicates, one JSON each, those already there
    reused, and return them all in order. A replicate that raised holds ``error``.
    Settings that resume (``resumes`` true) have ``replicate(k, folder)`` run replicate
    k's fit in ``work``/<k> (None: ``out``/:data:`RUNNING`), continued there by the next
    run if this one stops. ``executor``: where the replicates run (each in a process of
    its own on local processes); None: ``processes`` local processes."""
    from ..inference.fit import check_output_folder
    from .manifest import write_manifest

    out = Path(out)
    check_output_folder(out)
    out.mkdir(parents=True, exist_ok=True)
    settings_file = out / "settings.json"
    mine, defaults = _stored_settings(cs), _stored_settings(type(cs)())
    if settings_file.exists() and _with_defaults(_saved_settings(settings_file), defaults) != mine:
        raise ValueError(f"{out} holds replicates of other calibration settings; choose another output folder")
    settings_file.write_text(json.dumps(mine, indent=2) + "\n")
    write_manifest(out, {"settings": mine, "replicates": replicates, "processes": processes})
    finished = load_replicates(out)
    todo = [k for k in range(replicates) if k not in finished]
    done = replicates - len(todo)
    if progress:
        progress(done, replicates)
    work = out / RUNNING if work is None else Path(work)
    if getattr(cs, "resumes", False):  # refused here, before any fit starts, not in a worker
        stamp = work_stamp(cs, out)
        for k in todo:
            stamped_folder(work / f"{k:04d}", stamp, create=False)
    jobs = [(cs, k, out, work) for k in todo]
    mine = executor is None
    executor = make_executor(processes if len(jobs) > 1 else 1) if mine else executor
    try:
        for outcome in executor.as_completed(_worker, jobs):  # each replicate in a process of its own
            if not outcome.ok:
                raise outcome.error
            done += 1
            if progress:
                progress(done, replicates)
    finally:
        if mine:
            executor.close()
    finished = load_replicates(out)
    return [finished[k] for k in range(replicates)]


def run_calibration(cs: CalibrationSettings, out, replicates: int, *, processes: int = 1, progress=None,
                    executor=None) -> dict:
    """Run ``replicates`` replicates into ``out`` (one JSON each; those already there are
    reused) and write ranks.csv, coverage.csv, ranks.png and REPORT.md."""
    from ..inference.fit import versions

    results = run_replicates(cs, out, replicates, processes=processes, progress=progress, executor=executor)
    return write_calibration(Path(out), cs, results, versions())


def coverage_table(results: list[dict]) -> list[dict]:
    """Per parameter: replicates, coverage of the 50 % and 90 % intervals with binomial
    standard errors, and a chi-square test of uniform ranks (in 10 bins)."""
    from scipy import stats

    ok = [r for r in results if "ranks" in r]
    if not ok:
        return []
    rows = []
    for name in ok[0]["ranks"]:
        n = len(ok)
        L = ok[0]["L"]
        row = {"parameter": name, "replicates": n}
        for key, q in (("in50", 0.5), ("in90", 0.9)):
            p = sum(r[key][name] for r in ok) / n
            row[f"coverage_{int(100 * q)}"] = p
            row[f"se_{int(100 * q)}"] = math.sqrt(q * (1 - q) / n)  # binomial sd under correct coverage
        ranks = np.array([r["ranks"][name] for r in ok])
        counts = np.histogram(ranks, bins=10, range=(0, L + 1))[0]
        row["rank_chi2_p"] = float(stats.chisquare(counts).pvalue)
        rows.append(row)
    return rows


def write_calibration(out: Path, cs: CalibrationSettings, results: list[dict], versions: dict) -> dict:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .analysis import write_csv
    from .plots import plot_ranks
    from .calibration_report import calibration_report

    ok = [r for r in results if "ranks" in r]
    failed = [r for r in results if "error" in r]
    names = list(ok[0]["ranks"]) if ok else []
    write_csv(out / "ranks.csv", [{"replicate": r["replicate"], **r["ranks"], "iterations": r["iterations"],
                                    "tau_max": r["tau_max"]} for r in ok])
    table = coverage_table(results)
    write_csv(out / "coverage.csv", table)
    if ok:
        fig = plot_ranks({n: [r["ranks"][n] for r in ok] for n in names}, ok[0]["L"],
                         title=f"SBC rank histograms, truth '{cs.truth}', residual {cs.residual}, {len(ok)} replicates")
        fig.savefig(out / "ranks.png", dpi=100)
        plt.close(fig)
    report = calibration_report(out, cs, table, len(ok), failed, versions)
    return {"coverage": table, "replicates": len(ok), "failed": failed, "report": report}


def compare_calibrations(root) -> Path | None:
    """``root``/REPORT.md and coverage.png: the 50 % and 90 % coverage of every
    calibration case found in ``root``'s sub-folders (each a run of
    :func:`run_calibration`), side by side. Returns the report's path, or None when no
    case holds results."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .plots import plot_coverage
    from .calibration_report import calibration_comparison

    root = Path(root)
    cases = {}
    for folder in sorted(p for p in root.iterdir() if (p / "coverage.csv").is_file() and (p / "settings.json").is_file()):
        with open(folder / "coverage.csv", newline="") as f:
            rows = [{k: (v if k == "parameter" else float(v)) for k, v in r.items()} for r in csv.DictReader(f)]
        if rows:
            cases[folder.name] = rows
    if not cases:
        return None
    fig = plot_coverage(cases)
    fig.savefig(root / "coverage.png", dpi=100)
    plt.close(fig)
    return calibration_comparison(root, cases)


@dataclass(frozen=True)
class Config:
    """What ``studies/calibration.py`` is asked: a case of :class:`CalibrationSettings`
    (its generator's friction, backlash and noise colour as options) and how many
    replicates."""

    replicates: int = field(default=100, metadata={"help": "how many replicates"})
    truth: str = field(default="model", metadata={"choices": ("model", "generator"), "help": "what makes the data"})
    residual: str = field(default="ar1", metadata={"choices": ("ar1", "iid"), "help": "the likelihood's residual"})
    friction: str = field(default="coulomb", metadata={"choices": ("coulomb", "stribeck", "smooth"),
                                                       "help": "the generator's friction law"})
    backlash: float = field(default=0.0, metadata={"help": "the generator's nut backlash, m"})
    noise_corner: float | None = field(default=None, metadata={
        "help": "colour the generator's sensor noise with a low-pass at this frequency, Hz"})
    steps: int = field(default=CalibrationSettings.steps, metadata={"help": "steps per chain"})
    seed: int = field(default=0, metadata={"help": "replicate k uses the seed sequence (seed, k)"})

    def __post_init__(self) -> None:
        if not (isinstance(self.replicates, int) and self.replicates >= 1):
            raise ValueError(f"replicates must be a whole number of at least 1, got {self.replicates!r}")
        self.settings()  # a bad value fails here, before anything runs

    def settings(self) -> CalibrationSettings:
        base = CalibrationSettings()
        return replace(base, truth=self.truth, residual=self.residual, steps=self.steps, seed=self.seed,
                       generator=replace(base.generator, friction=self.friction, backlash=self.backlash,
                                         noise_corner=self.noise_corner))


def case_name(config: Config) -> str:
    """The case's folder name under results/calibration: truth, richer physics, residual."""
    richer = "" if config.friction == "coulomb" and not config.backlash else f"-{config.friction}-bl{config.backlash:g}"
    richer += f"-colour{config.noise_corner:g}Hz" if config.noise_corner else ""
    return f"{config.truth}{richer}-{config.residual}"


def failed_items(results: list[dict]) -> tuple:
    """``StudyOutput.failed`` of the replicates that raised (each holds ``error``)."""
    return tuple((f"replicate {r.get('replicate', '?')}", r["error"]) for r in results if "error" in r)


def run(config: Config, out, executor, *, progress=None):
    """The case's replicates into ``out`` (those not yet there on ``executor``), its
    report, then every case beside it in ``out``'s parent compared
    (:func:`compare_calibrations`)."""
    from .output import StudyOutput

    res = run_calibration(config.settings(), out, config.replicates, progress=progress, executor=executor)
    compared = compare_calibrations(Path(out).parent)
    return StudyOutput(written=(res["report"],) + ((compared,) if compared else ()),
                       lines=(f"{res['replicates']} replicates, {len(res['failed'])} failed",),
                       failed=failed_items(res["failed"]),
                       values=res)
