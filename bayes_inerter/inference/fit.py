"""Fit one record: the Python API behind ``bayes-inerter fit``.

Writes into the output folder: ``chain.h5`` (the emcee checkpoint, written as it goes),
``summary.csv``, ``posterior.nc`` (arviz InferenceData), ``loo.json`` (its PSIS-LOO in
five numbers), ``corner.png``, ``bands.png``, ``trace.png``, ``phi.png`` and ``fit.json``
(convergence, settings, versions, timings).
"""

from __future__ import annotations

import dataclasses
import json
import math
import os
import platform
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import arviz_import
from ..records.drive import resolve_drive, with_drive
from ..records.reactance import drive_impedance
from ..records.record import Record
from .sampling.checkpoint import WRITE_SECONDS
from ..lock import folder_lock
from ..masses import Masses, resolve_masses
from .sampling.coordinates import default_coordinates
from .sampling.coordinates import EDGE_WARNING, MAX_SENSITIVITY_CHANGE
from .summaries.end_state import (EndWarning, convergence_warning, end_state_warnings, few_periods_warning,
                                  friction_dominated_warning)
from .summaries.interval import DEFAULT_INTERVAL, INTERVALS, IntervalSettings, inertance_interval
from .posterior.model import LikelihoodSettings, PosteriorModel
from .sampling.optimize import laplace_covariance
from .summaries.results import contraction, posterior_sample, summary_rows, to_inference_data, write_loo, write_summary
from .sampling.sampler import Adaptation, Convergence, Tempering, check_run_options, run_sampler
from .sampling.tempering import default_convergence

__all__ = ["fit_record", "fit_joint", "FitResult", "check_output_folder", "versions", "DRAWS_FILE",
           "ALL_DRAWS_FILE", "JOINT_DRAWS_KEPT", "thinned_draws"]

#: The joint model's kept draws of each b (``b_<setting>``: walkers x draws), numpy's npz:
#: what the study's regression per flywheel needs, kept beside the summary because the
#: chain itself is too large to keep with the results.
DRAWS_FILE = "b_draws.npz"
#: Every sampled parameter's kept draws, by name (``fit_joint(all_draws=True)``,
#: ``fit_record(all_draws=True)``).
ALL_DRAWS_FILE = "draws.npz"
#: At most this many draws of each parameter go to ``DRAWS_FILE`` and ``ALL_DRAWS_FILE``
#: (and into the ``FitResult``'s draws that a study's tables are made from): the chain's
#: kept draws thinned evenly along the steps, every walker kept (**assumption**). A
#: converged chain's kept draws are already spaced by its autocorrelation time, so 4,000
#: of them put a median's Monte Carlo error near 2 % of the posterior sd; the full study's
#: 11,960 made b_draws.npz 707 kB, past the 300 kB a committed result may take.
JOINT_DRAWS_KEPT = 4000
#: Posterior draws (evenly spaced over the kept chain) whose predicted force makes
#: loops.png's band.
LOOP_DRAWS = 200


@dataclass
class FitResult:
    """What ``fit_record`` produced (files are in ``out``)."""

    out: Path
    summary: list
    converged: bool
    reason: str
    iterations: int
    tau: np.ndarray
    idata: object
    timings: dict = field(default_factory=dict)
    contraction: dict = field(default_factory=dict)
    #: what was done to continue a damaged checkpoint ("" when nothing was)
    recovered: str = ""
    #: the joint model's kept draws of each b, ``b_<setting>`` -> (walkers, draws) (empty for one record)
    draws: dict = field(default_factory=dict)
    #: warnings about how the fit ended (``end_state.EndWarning``): b at a prior bound, a poor fit
    warnings: list = field(default_factory=list)
    #: the masses used and where each came from (``masses.Masses``; None for the joint model)
    masses: object = None
    #: the theoretical inertance from the device file's geometry, kg (None without one)
    b_theory: float | None = None
    #: b's reported interval (``interval.InertanceInterval``; None for the joint model)
    b_interval: object = None
    #: the drive frequency used and where it came from (``records.drive.DriveFrequency``;
    #: None for the joint model)
    drive: object = None
    #: the draws kept: those after step ``burn_in`` (the ``warmup`` and 2 tau), every ``thin``th
    burn_in: int = 0
    warmup: int = 0
    thin: int = 1
    #: the fit's PSIS-LOO as loo.json holds it (``results.loo_summary``; empty for the joint model)
    loo: dict = field(default_factory=dict)
    #: each sampled parameter's autocorrelation time, steps, by name (fit.json's "tau")
    tau_by_parameter: dict = field(default_factory=dict)
    #: the sampler's coordinates, described (fit.json's "coordinates")
    coordinates: str = ""
    #: the figures this fit drew into ``out``, by file name (none with ``plots=False``)
    figures: tuple = ()
    #: the tempering ladder and its swap rates as fit.json holds them (None: untempered)
    tempering: dict | None = None

    def row(self, name: str) -> dict:
        for r in self.summary:
            if r["name"] == name:
                return r
        raise KeyError(name)


def check_output_folder(out: Path) -> None:
    """Refuse, before any work, an output folder that cannot be made or written."""
    if out.exists() and not out.is_dir():
        raise ValueError(f"{out}: exists and is not a folder")
    parent = out if out.exists() else next((p for p in out.parents if p.exists()), Path("."))
    if not os.access(parent, os.W_OK | os.X_OK):
        raise ValueError(f"{out}: cannot write there (permission denied); choose another --out")


def versions() -> dict:
    """Versions of the package, Python and the libraries that shape its numbers."""
    arviz = arviz_import.module()
    import emcee
    import numba
    import scipy

    from .. import __version__

    return {"bayes_inerter": __version__, "numpy": np.__version__, "scipy": scipy.__version__,
            "emcee": emcee.__version__, "arviz": arviz.__version__, "numba": numba.__version__,
            "python": platform.python_version(), "machine": platform.machine(), "cpu": _cpu_model()}


def _cpu_model() -> str:
    """The processor's model name: numbers are reproduced bit for bit only on the same
    kind of processor (docs/reproducibility.md), so each result names its own."""
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or "unknown"


def fit_record(record: Record, out, *, model: str = "two-port", m_s: float | None = None, m_B: float | None = None,
               device=None, walkers: int | None = None, steps: int | None = None, seed: int = 0, fresh: bool = False,
               processes: int = 1, likelihood: LikelihoodSettings | None = None, priors: dict | None = None,
               convergence: Convergence | None = None, progress=None, report=None, plots: bool = True,
               coordinates: str = "impedance", adaptation: Adaptation | None = Adaptation(),
               checkpoint_seconds: float = WRITE_SECONDS,
               interval: str | IntervalSettings | None = None, freq: float | None = None,
               name: str | None = None, modal: bool | None = None, masses: Masses | None = None,
               tempering: Tempering | None = None, all_draws: bool = False) -> FitResult:
    """Sample the posterior of one record and write every output into ``out``.

    ``all_draws``: also write every sampled parameter's kept draws, by name, to
    ``ALL_DRAWS_FILE`` (at most ``JOINT_DRAWS_KEPT``, thinned evenly along the steps,
    every walker kept, as the joint fit's): the draws summary.csv's intervals come from,
    where posterior.nc holds at most ``summaries.results.MAX_DRAWS`` of them (those that
    carry a simulation).

    ``modal``: the bearing's damper sampled as the plate mode's damping ratio under its
    physical prior (``model.PosteriorModel``; None: wherever the model can).

    ``interval``: how b's reported interval is made, a name of ``interval.INTERVALS``
    ("honest": the posterior widened by the sensors' calibration and the model
    discrepancy; "posterior": the posterior alone) or ``IntervalSettings``; None (the
    default): "posterior" for the harmonic likelihoods, whose posterior holds the
    discrepancy and the gain itself, "honest" for the time-domain ones. It is
    in fit.json (``b_interval``) and ``FitResult.b_interval``; summary.csv keeps the
    posterior's own.

    ``coordinates``: where the walkers move (``coordinates.COORDINATES``; the outputs are
    in the model's parameters whichever is used). ``adaptation``: the fitted independence
    move (``sampler.Adaptation``; None: the ensemble moves alone). ``checkpoint_seconds``:
    the steps reach chain.h5 at most this far apart (0: every step; ``run_sampler``).
    ``tempering``: parallel tempering's ladder (``sampler.Tempering``; None, the
    default: the ensemble alone, see docs/inference.md for the measurements that chose
    it); fit.json gives it, its swap rates and the replicas' tau the rule read. ``convergence`` None: the package's rule, capped at ``tempering.MAX_STEPS``
    (10,000) steps where tempered (``tempering.default_convergence``). ``progress``, ``report``:
    ``run_sampler``'s callbacks. The folder is locked for the run (``lock.folder_lock``):
    a second run into it is refused at once.

    ``m_s``, ``m_B``, ``device`` (a ``device_file.DeviceFile``): the masses, resolved by
    ``masses.resolve_masses`` (option, metadata, device file, paper default); fit.json
    records each with its source, and the device file's theoretical inertance.
    ``masses``: the masses already resolved (the command line resolves them once, to
    print them and to refuse a record before anything runs), in place of ``m_s`` and
    ``m_B``.

    ``name``: the record's name in the figures' titles (``fit`` gives its file's name).

    ``freq``: the drive frequency, Hz; else the record's metadata's, else estimated from
    the record (``records.drive.resolve_drive``). It is settled here, before sampling,
    and every step uses the same: the sampler's coordinates, the discrepancy, the
    interval, the figures; fit.json and ``FitResult.drive`` say where it came from.

    Everything that can be checked is checked before sampling starts (record, masses,
    options, output folder); the folder is not touched if any check fails. The
    record's physical sense (``records.checks``) is the caller's to check first.
    """
    out = Path(out)
    likelihood = likelihood or LikelihoodSettings()
    convergence = convergence or default_convergence(tempering)
    if interval is None:
        interval = "posterior" if likelihood.residual in ("harmonic", "motion") else DEFAULT_INTERVAL
    interval_settings = _interval_settings(interval)
    drive = resolve_drive(record, freq)
    record = with_drive(record, drive)
    if masses is None:
        masses = resolve_masses(record, m_s=m_s, m_B=m_B, device=device)
    elif m_s is not None or m_B is not None:
        raise ValueError("give the masses resolved (masses=) or as m_s and m_B, not both")
    b_theory = device.theoretical_inertance if device is not None else None
    pm = PosteriorModel(record, model, m_s=masses.m_s, m_B=masses.m_B, priors=priors or {},
                        likelihood=likelihood or LikelihoodSettings(), modal=modal)
    check_run_options(pm.ndim, walkers, steps)
    coords = default_coordinates(pm, coordinates)
    check_output_folder(out)
    with folder_lock(out):
        out.mkdir(parents=True, exist_ok=True)
        t0 = time.perf_counter()
        got = _sample_into(out, pm, nwalkers=walkers, steps=steps, seed=seed, fresh=fresh, processes=processes,
                           convergence=convergence, progress=progress, report=report, coordinates=coords,
                           adaptation=adaptation, checkpoint_seconds=checkpoint_seconds, tempering=tempering)
        run, sample, pm = got.run, got.sample, got.model
        idata, sims = to_inference_data(pm, sample, rng=np.random.default_rng(seed + 1))
        t_post = time.perf_counter() - t0 - got.seconds
        idata.to_netcdf(str(out / "posterior.nc"))
        loo = write_loo(out, idata)
        best = sample.theta.reshape(-1, pm.ndim)[int(np.argmax(sample.lp))]
        b_interval = inertance_interval(pm, sample.values[..., pm.names.index("b")], best,
                                        cov=laplace_covariance(pm, best) if interval_settings.others == "free"
                                        else None, phi=float(np.median(sample.phi)),
                                        settings=interval_settings, rng=np.random.default_rng(seed + 2))
        impedance = _drive_impedance(record, drive.hz)
        got = _finish(out, pm, got, steps, convergence, b_identified=b_interval.identified,
                      ratios=(("b", None, None if impedance is None else impedance.ratio),))
        if all_draws:
            kept = thinned_draws(sample.values)
            np.savez_compressed(out / ALL_DRAWS_FILE, **{n: kept[:, :, i] for i, n in enumerate(pm.names)})
        figures = _write_plots(out, pm, sample, sims, label=_label(pm, name), warmup=int(run.warmup),
                               b_interval=b_interval, b_theory=b_theory) if plots else ()
        info = _run_info(model, pm, got, seed, {
            "m_s": pm.m_s, "m_B": pm.m_B, "masses": masses.as_dict(), "b_theory_device_file": b_theory,
            "drive_frequency": drive.as_dict(),
            "drive_impedance": None if impedance is None else impedance.as_dict(),
            "stride": pm.stride, "record_metadata": record.metadata, "b_interval": b_interval.as_dict(),
            "interval_settings": dataclasses.asdict(interval_settings)})
        info["timings_s"] = {"sampling": got.seconds, "posterior_draws": t_post, "total": time.perf_counter() - t0,
                             **_start_seconds(run),
                             **_sampling_all_runs(out, got.seconds, run, fresh or run.start_theta is not None)}
        (out / "fit.json").write_text(json.dumps(info, indent=2, default=str) + "\n")
        return FitResult(out, got.rows, run.converged, run.reason, run.iteration, run.tau, idata,
                         info["timings_s"], got.shrink, run.recovered, warnings=got.ended, masses=masses,
                         b_theory=b_theory, b_interval=b_interval, drive=drive, burn_in=sample.burn,
                         warmup=int(run.warmup), thin=sample.thin, loo=loo, tau_by_parameter=info["tau"],
                         coordinates=info["coordinates"], figures=figures, tempering=info["tempering"])


def _drive_impedance(record: Record, hz: float):
    """The record's ``records.reactance.DriveImpedance`` at ``hz``, or None where it holds
    too few steady periods to read one."""
    try:
        return drive_impedance(record, hz)
    except ValueError:
        return None


def thinned_draws(values: np.ndarray, most: int | None = None) -> np.ndarray:
    """``values`` (walkers, draws, ...) thinned evenly along the draws to at most
    ``most`` in all (None: ``JOINT_DRAWS_KEPT``), every walker kept (every step-th of
    each walker's draws)."""
    most = JOINT_DRAWS_KEPT if most is None else most
    n_walkers, n_kept = values.shape[:2]
    per_walker = max(1, most // n_walkers)
    return values[:, ::math.ceil(n_kept / per_walker)]


def _interval_settings(interval) -> IntervalSettings:
    if isinstance(interval, IntervalSettings):
        return interval
    if interval not in INTERVALS:
        raise ValueError(f"unknown interval {interval!r}; choose {', '.join(INTERVALS)} or pass IntervalSettings")
    return INTERVALS[interval]


def fit_joint(records, out, *, model: str = "two-port", centres: list[dict] | None = None, walkers: int | None = None,
              steps: int | None = None, seed: int = 0, processes: int = 1, likelihood: LikelihoodSettings | None = None,
              priors: dict | None = None, convergence: Convergence | None = None, progress=None, report=None,
              plots: bool = True, coordinates: str = "impedance",
              adaptation: Adaptation | None = Adaptation(), all_draws: bool = False,
              tempering: Tempering | None = None) -> FitResult:
    """Sample the joint posterior of several records (``joint.JointModel``: shared
    frictions and deformations, one b per flywheel setting) into ``out``: chain.h5,
    summary.csv, fit.json, b_draws.npz (``DRAWS_FILE``; at most ``JOINT_DRAWS_KEPT`` draws of
    each b, as the result's ``draws``), corner.png (the b's), trace.png.
    ``model``: each record's model (``JointModel.model``). ``all_draws``: also write
    every sampled parameter's kept draws, by name, to ``ALL_DRAWS_FILE`` (what a
    prediction of another record needs; megabytes for a study's 27 records).

    ``centres``: one dict of single-record posterior centres (sampled values by name) per
    record; the run starts from the joint optimum that Nelder-Mead, restarted while it
    gains (``optimize.local_optimum``), reaches from the best of one pass from each of
    ``JointModel.start_candidates`` (their median, and each record's own or, beyond
    ``joint.RECORD_STARTS`` records, each group of the friction split). Without
    them the centres are each record's own optimum found first (``optimize.find_start``,
    minutes a record). A continued chain needs no start and skips both searches. The
    medians of the records' centres are far from the joint optimum (about 1,000 nats
    below where the chain settles on the 27 records of the full study), so the walkers
    would otherwise spend their first hundreds of steps getting there.

    ``tempering``: parallel tempering's ladder (``sampler.Tempering``; None: none).
    """
    from .posterior.joint import JointModel, pooled_log_prob
    from .sampling.optimize import NM_RESTARTS, find_start, local_optimum

    out = Path(out)
    convergence = convergence or default_convergence(tempering)
    jm = JointModel(tuple(records), priors=priors or {}, likelihood=likelihood or LikelihoodSettings(), model=model)
    check_run_options(jm.ndim, walkers, steps)
    coords = default_coordinates(jm, coordinates)
    check_output_folder(out)
    with folder_lock(out):
        out.mkdir(parents=True, exist_ok=True)
        t0 = time.perf_counter()

        def start():  # run_sampler calls it only when the chain starts over
            given = centres
            if given is None:
                rng = np.random.default_rng(seed)
                given = [part.values(find_start(part, rng)[0]) for part in jm.parts]
            # Nelder-Mead takes one point at a time: its records are shared among the processes
            with pooled_log_prob(jm, processes) as log_prob:
                candidates = jm.start_candidates(given)
                if len(candidates) > 1:  # one pass from each, the best polished
                    reached = [local_optimum(jm, c, log_prob=log_prob) for c in candidates]
                    candidates = [max(reached, key=lambda r: r[1])[0]]
                return local_optimum(jm, candidates[0], restarts=NM_RESTARTS, log_prob=log_prob)

        got = _sample_into(out, jm, nwalkers=walkers, steps=steps, seed=seed, processes=processes,
                           convergence=convergence, progress=progress, report=report, start=start,
                           coordinates=coords, adaptation=adaptation, tempering=tempering)
        jm = got.model if got.model is not None else jm  # with its reference point, if it took one
        labels = joint_records(jm)
        impedances = [_drive_impedance(r, f) for r, f in zip(jm.records, jm.freq_of)]
        got = _finish(out, jm, got, steps, convergence,
                      ratios=tuple((f"b_{s}", label, None if z is None else z.ratio)
                                   for s, label, z in zip(jm.setting_of, labels, impedances)))
        run, sample = got.run, got.sample
        nb = len(jm.settings)
        kept = thinned_draws(sample.values)
        draws = {name: kept[:, :, i] for i, name in enumerate(jm.names[:nb])}
        np.savez_compressed(out / DRAWS_FILE, **draws)
        if all_draws:
            np.savez_compressed(out / ALL_DRAWS_FILE, **{n: kept[:, :, i] for i, n in enumerate(jm.names)})
        if plots:
            _write_joint_plots(out, jm, sample, warmup=int(run.warmup))
        info = _run_info("joint", jm, got, seed, {
            "records": labels, "record_model": model,
            "drive_impedance": {label: None if z is None else z.as_dict() for label, z in zip(labels, impedances)}})
        info["timings_s"] = {"sampling": got.seconds, "total": time.perf_counter() - t0, **_start_seconds(run),
                             **_sampling_all_runs(out, got.seconds, run, run.start_theta is not None)}
        (out / "fit.json").write_text(json.dumps(info, indent=2, default=str) + "\n")
        return FitResult(out, got.rows, run.converged, run.reason, run.iteration, run.tau, None, info["timings_s"],
                         got.shrink, run.recovered, draws, warnings=got.ended, burn_in=sample.burn,
                         warmup=int(run.warmup), thin=sample.thin, tau_by_parameter=info["tau"],
                         coordinates=info["coordinates"])


@dataclass(frozen=True)
class _Sampled:
    """A finished run, its kept draws and what is read from them."""

    run: object
    sample: object
    rows: list
    ended: list
    shrink: dict
    seconds: float
    #: the model the chain sampled (``SamplerRun.model``)
    model: object = None
    #: how near the draws come to the coordinates' domain edge (``Coordinates.domain_edge``;
    #: set by ``_finish``, which warns of it, and kept in fit.json)
    edge: float | None = None


def _sample_into(out: Path, model, **options) -> _Sampled:
    """Run the sampler into ``out``/chain.h5 (``options``: ``run_sampler``'s), keep its
    draws and read its summary rows and end-state warnings (``_finish`` completes them)."""
    t0 = time.perf_counter()
    run = run_sampler(model, out / "chain.h5", **options)
    model = run.model if run.model is not None else model  # with its reference point, if it took one
    seconds = time.perf_counter() - t0
    sample = posterior_sample(model, run)
    rows = summary_rows(sample, kinds=_kinds(model, sample))
    return _Sampled(run, sample, rows, end_state_warnings(model, sample), contraction(model, sample), seconds, model)


def _kinds(model, sample) -> dict:
    """summary.csv's ``kind`` of each row: sampled (its prior is in fit.json), derived
    (a function of sampled ones) or the fit accuracy."""
    kinds = {n: "sampled" for n in sample.names}
    kinds.update({n: "derived" for n in sample.derived})
    kinds["phi"] = "fit accuracy (derived)"
    return kinds


def _finish(out: Path, model, got: _Sampled, steps, convergence, b_identified: bool = True,
            ratios: tuple = ()) -> _Sampled:
    """Every warning of the run (its end state, the coordinates' edge, convergence, in
    the order ``fit`` prints them), flagged in its rows, and summary.csv written.
    ``ratios``: (b's row, the record's name or None, its force ratio or None) of each
    record (``friction_dominated_warning``)."""
    run, sample = got.run, got.sample
    ended = list(got.ended)
    edge = run.coordinates.domain_edge(sample.theta) if run.coordinates is not None else None
    if edge is not None and edge > EDGE_WARNING:
        ended.append(EndWarning(model.names[0], "near the coordinates' edge",
                                f"the posterior reaches |dZ/dZ_theta - 1| = {edge:.2f}, near the edge of the impedance "
                                f"coordinates' domain ({MAX_SENSITIVITY_CHANGE:g}), which may cut it; compare with "
                                "--coordinates unconstrained"))
    late = convergence_warning(converged=run.converged, reason=run.reason, iteration=run.iteration,
                               tau=dict(zip(model.names, map(float, run.tau))), rows=got.rows,
                               conv=convergence, steps=steps, b_identified=b_identified)
    if late is not None:
        ended.append(late)
    few = few_periods_warning(model.harmonic.periods if getattr(model, "harmonic", None) is not None else None)
    if few is not None:
        ended.append(few)
    for name, record, ratio in ratios:
        friction = friction_dominated_warning(ratio, name, record)
        if friction is not None:
            ended.append(friction)
    _flag(got.rows, ended)
    write_summary(out / "summary.csv", got.rows)
    return dataclasses.replace(got, ended=ended, edge=edge)


def _run_info(name: str, model, got: _Sampled, seed: int, extra: dict) -> dict:
    """fit.json's facts of a run (``extra``: the single-record or joint ones)."""
    run, sample = got.run, got.sample
    return {
        "model": name, "converged": run.converged, "reason": run.reason, "checkpoint_recovered": run.recovered,
        "iterations": int(run.iteration), "walkers": run.sampler.nwalkers, "seed": seed,
        "tau": dict(zip(model.names, map(float, run.tau))), "burn_in": sample.burn, "thin": sample.thin,
        "transient": int(run.transient), "warmup": int(run.warmup), **extra,
        "warnings": [dataclasses.asdict(w) for w in got.ended],
        "likelihood": dataclasses.asdict(model.likelihood),
        # the priors of what was sampled; the derived quantities (raw frictions from sums
        # and shares, b_app) have none of their own
        "priors": {n: model.all_priors[n].describe() for n in model.names},
        "derived": list(model.derived_names),
        "acceptance_fraction": float(np.mean(run.sampler.acceptance_fraction)),
        "moves": list(run.moves),
        "coordinates": run.coordinates.describe(),
        "tempering": None if run.tempering is None else {
            "ladder": run.tempering.describe(), "betas": run.tempering.betas.tolist(),
            "swap_rates": list(run.swap_rates),
            "replica_tau": None if run.replica_tau is None else dict(zip(model.names, map(float, run.replica_tau)))},
        "coordinates_domain_edge": got.edge,
        "contraction": got.shrink,
        "versions": versions(),
    }


def _write_joint_plots(out: Path, jm, sample, warmup: int) -> None:
    """corner.png (the b's, with the records' true b's where all have one), trace.png,
    and for the motion-in likelihood loops.png (two panels per record, as a single fit's)."""
    import matplotlib.pyplot as plt

    from .summaries.loops import period_loops
    from .summaries.plots import plot_corner, plot_loops, plot_trace

    nb = len(jm.settings)
    flat = sample.values.reshape(-1, jm.ndim)
    truths = [rec.metadata.get("true_parameters", {}).get("b") for rec in
              (next(r for r, s in zip(jm.records, jm.setting_of) if s == name) for name in jm.settings)]
    figs = {"corner.png": plot_corner(flat[:, :nb], jm.names[:nb],
                                      truths=truths if all(t is not None for t in truths) else None,
                                      title=f"joint model, {len(jm.records)} records: inertance per setting"),
            "trace.png": plot_trace(sample.theta, jm.names, burn=sample.burn, thin=sample.thin, warmup=warmup)}
    if all(part.motion is not None for part in jm.parts):
        thetas = _loop_draws(sample.theta, jm.ndim)
        try:  # as a single fit's: no usable draw, no loops, the other outputs kept
            figs["loops.png"] = plot_loops([period_loops(part, [jm.part_theta(t, k) for t in thetas])
                                            for k, part in enumerate(jm.parts)], joint_records(jm))
        except ValueError:
            pass
    for name, fig in figs.items():
        fig.savefig(out / name, dpi=100)
        plt.close(fig)


def joint_records(jm) -> list[str]:
    """The joint model's records as fit.json names them ("A0 1 Hz", ...): what an earlier
    run's outputs are matched by (``study.run.finished_joint``)."""
    return [f"{s} {f:g} Hz" for s, f in zip(jm.setting_of, jm.freq_of)]


def _flag(rows: list, ended: list) -> list:
    """Write each warning's flag into its summary rows (``flag``); return the warnings."""
    flags: dict = {}
    for w in ended:
        for name in w.names:
            flags.setdefault(name, []).append(w.flag)
    for r in rows:
        r["flag"] = "; ".join(flags.get(r["name"], []))
    return ended


def _start_seconds(run) -> dict:
    """A new chain's start by phase, in the sampling time (``start_search``,
    ``start_modes``, ``start_ensemble``: ``SamplerRun.start_seconds``); none where the
    run continued a checkpoint."""
    return {f"start_{phase}": seconds for phase, seconds in run.start_seconds.items()}


def _sampling_all_runs(out: Path, t_sample: float, run, started_over: bool) -> dict:
    """Sampling seconds of the chain in all runs that built it and the steps they timed
    (``sampling_all_runs``, ``steps_timed``): this run's plus what the previous fit.json
    recorded, unless the chain started over (``--fresh``, or no checkpoint was there, as
    in a fresh clone beside a committed fit.json); a run that continues a checkpoint, or
    finds it complete, would otherwise report only its own share. Steps of a run killed
    before it wrote fit.json are in the chain but not timed, so seconds per step are
    ``sampling_all_runs / steps_timed``, not per ``iterations``. A fit.json that describes
    more steps than the checkpoint held when this run began is of another chain (one that
    started over in a run killed before it wrote fit.json, beside the old fit.json) and
    adds nothing."""
    own = {"sampling_all_runs": t_sample, "steps_timed": int(run.iteration - run.resumed_at)}
    previous = out / "fit.json"
    if started_over or not previous.exists():
        return own
    try:
        before = json.loads(previous.read_text())
        timings = before.get("timings_s", {})
        seconds = float(timings.get("sampling_all_runs", timings.get("sampling", 0.0)))
        steps = int(timings.get("steps_timed", before.get("iterations", 0)))
        other_chain = int(before.get("iterations", 0)) > run.resumed_at
    except (OSError, ValueError, TypeError):
        return own
    if other_chain:
        return own
    return {"sampling_all_runs": own["sampling_all_runs"] + seconds, "steps_timed": own["steps_timed"] + steps}


def _residual_sd(sample, pm: PosteriorModel) -> float:
    """Posterior median of the residual's marginal sd, sigma / sqrt(1 - rho^2); for the
    harmonic likelihood, of the periodic error's, sqrt(sum_k V_k / 2) (over up to 200
    draws)."""
    if pm.harmonic is not None:
        theta = sample.theta.reshape(-1, pm.ndim)
        pick = theta[:: max(1, len(theta) // 200)]
        return float(np.median([math.sqrt(pm.accel_error_variance(t).sum() / 2.0) for t in pick]))
    vals = sample.as_dict()
    rho = vals.get("rho", np.zeros_like(vals["sigma"]))
    return float(np.median(vals["sigma"] / np.sqrt(1.0 - rho**2)))


def _label(pm: PosteriorModel, name: str | None) -> str:
    """The figures' name of a record: its file's ``name``, its setting and its drive."""
    setting = pm.record.metadata.get("setting")
    words = [w for w in (name, str(setting) if setting else None) if w] or ["record"]
    return ", ".join(words) + f", {pm.drive.hz:.4g} Hz"


def _loop_draws(theta: np.ndarray, ndim: int) -> np.ndarray:
    """Up to :data:`LOOP_DRAWS` kept draws, evenly spaced over the chain (walkers x draws x
    ndim), for the loops' band."""
    flat = theta.reshape(-1, ndim)
    return flat[np.unique(np.linspace(0, len(flat) - 1, min(LOOP_DRAWS, len(flat))).astype(int))]


def _write_plots(out: Path, pm: PosteriorModel, sample, sims, *, label: str, warmup: int, b_interval=None,
                 b_theory: float | None = None) -> tuple:
    """corner.png (with b's reported interval, where it identifies b, and the device
    file's theoretical b), bands.png, trace.png (naming the burn-in as ``fit`` prints it),
    phi.png, and for the motion-in likelihood loops.png (the force against displacement
    and velocity over a steady period, measured and predicted, ``loops``). Returns the
    names of the figures drawn."""
    import matplotlib.pyplot as plt

    from .summaries.loops import period_loops
    from .summaries.plots import plot_bands, plot_corner, plot_loops, plot_phi, plot_trace, reference_values

    meta = pm.record.metadata
    flat = sample.values.reshape(-1, len(sample.names))
    truths, paper = reference_values(pm, meta)
    figs = {
        "corner.png": plot_corner(flat, sample.names, truths=truths, paper=paper,
                                  title=f"{label}: {pm.model} model",
                                  interval=(b_interval.lo, b_interval.hi) if b_interval is not None
                                  and b_interval.identified else None, theory=b_theory),
        # inside the likelihood's window: the low-pass rings at the record's ends
        "bands.png": plot_bands(pm.record.time[pm.window], pm.measured_lp[pm.window], sims[:, pm.window],
                                freq=pm.record.drive_frequency, noise_sd=_residual_sd(sample, pm),
                                title=f"{label}: predicted acceleration ({pm.model}), "
                                      f"{pm.likelihood.edge:g} s cut at each end"),
        "trace.png": plot_trace(sample.theta, sample.names, burn=sample.burn, thin=sample.thin, warmup=warmup),
        "phi.png": plot_phi(sample.phi, title=f"{label}: fit accuracy"),
    }
    if pm.motion is not None:
        try:  # a figure never costs the fit's other outputs: without a usable draw there is no loop
            figs["loops.png"] = plot_loops([period_loops(pm, _loop_draws(sample.theta, pm.ndim))],
                                           [f"{label}: force over a steady period ({pm.model} model)"])
        except ValueError:
            pass
    for name, fig in figs.items():
        fig.savefig(out / name, dpi=100)
        plt.close(fig)
    return tuple(figs)
