"""Simulation-based calibration in the configuration the study reports.

``study.calibration`` checks the sampler on short records with one record per fit.
The study's numbers come from elsewhere: 10 s records made by the record generator, the
joint model (one b per flywheel setting, the frictions and deformations shared), a start
searched by differential evolution, and the 94 % interval. This module checks that.

Each replicate draws one device from :data:`STUDY_SBC_PRIORS`, makes its records at
each of ``frequencies`` with the record generator (10 s, the control's physics: the
model's own network and Coulomb friction, the generator's sensors and servo), and fits
them with :func:`inference.fit.fit_joint` exactly as the study's joint fit runs, under
the same prior. For every physical parameter it records the truth's rank among ``draws``
posterior draws and whether the 94 % and 50 % intervals hold it, both the highest-density
ones the study reports and the equal-tailed ones.

**Failed replicates are counted, not dropped**: a replicate whose fit raised holds
``error`` and counts as a miss at every level (:func:`coverage_rows`).

**Assumptions** (documented defaults, all settings of :class:`StudyCalibration`):

- the prior (:data:`STUDY_SBC_PRIORS`): the study's forms (log-uniform sums, uniform
  shares) over a narrower box. b is log-uniform on [300, 30,000] kg, which holds the
  nine settings' inertances (753 to 20,287 kg); every other physical sum is log-uniform
  over a factor of 10 either side of Table I. The study's own priors span three to five
  decades, and most of their draws are devices nobody builds (a nut of 1e3 N/m behind
  1e5 kg turns the device into a spring at 0.02 Hz). The noise priors are the study's;
- the flywheel setting (``setting``, default A3) gives the masses m_s and m_B only; b is
  drawn;
- the two drive frequencies 0.5 and 1.5 Hz (the ends of the paper's three), so each fit
  is a joint fit of two records; the study's joint fit of 27 records costs hours and
  cannot be replicated hundreds of times;
- a fixed number of steps per chain (``steps``, default 600, about 24 times the
  longest autocorrelation time a trial replicate showed); the study runs until
  converged, so each replicate also records whether its chain met the convergence rule;
- the generator's sensor noise is not the likelihood's AR(1) process, so sigma and rho
  have no true value and only the physical parameters are ranked; nor is it the
  harmonic likelihood's discrepancy, so tau and alpha are not ranked either. Its
  ``gain`` is: each replicate's acceleration channel is scaled by a gain drawn from its
  prior, so the calibration covers the sensors' too;
- ``single``: each replicate is one record, at ``frequencies[k % len(frequencies)]``,
  fitted by :func:`inference.fit.fit_record` as ``bayes-inerter fit`` runs it, instead of
  the joint fit; ``steps`` None runs each chain to the convergence rule (``Convergence``,
  capped at ``max_steps``).

:class:`Config` and :func:`run` are the study as ``studies/study_calibration.py`` runs
it (through ``cli.study_script``): a run, a cap raised, a folder summarised, or one
replicate inspected.
"""

from __future__ import annotations

import dataclasses
import json
import math
from dataclasses import dataclass, field
from typing import ClassVar
from pathlib import Path

import numpy as np
from scipy.optimize import minimize

from ..device import TABLE_I, paper_parameters
from ..inference.sampling import optimize
from ..inference.sampling.convergence import Convergence
from ..inference.sampling.coordinates import default_coordinates
from ..inference.sampling.adaptation import Adaptation
from ..inference.sampling.moves.block import PARTNERS
from ..inference.sampling.tempering import Tempering
from ..inference.fit import ALL_DRAWS_FILE, fit_joint, fit_record
from ..inference.posterior.likelihood import LikelihoodSettings
from ..inference.summaries.model_form import ModelFormError
from ..inference.posterior.model import PosteriorModel
from ..inference.posterior.motion import deviation_sd, motion_variance, predicted_force
from ..inference.posterior.priors import LogUniform, Uniform, tau_floor_prior
from ..inference.summaries.results import hdi
from ..records.generator import GeneratorSettings, generate_record
from ..records.reactance import drive_impedance
from ..records.record import Record
from ..simulate import SimulationError
from . import stop_rule
from .calibration import fit_folder
from .replicate_store import finished, is_packed

__all__ = ["STUDY_SBC_PRIORS", "LEVELS", "StudyCalibration", "ReplicateDevice", "replicate_device", "study_replicate", "raise_cap",
           "coverage_rows", "chains_long_enough", "write_study_calibration", "run_study_calibration", "inspect_replicate",
           "finished_replicates", "coverage_so_far", "coverage_by_frequency", "write_coverage_so_far", "rank_correlations",
           "RANK_CORRELATION", "IDENTIFIED", "INTERVAL_DRAWS", "in_domain", "fitted_priors", "gain_draws",
           "drawn_deviations", "likelihood_force", "MOTION_DEVICES", "Config", "run"]

_F0 = TABLE_I["f1_0"] + TABLE_I["f2_0"]
_CF = TABLE_I["c_f1"] + TABLE_I["c_f2"]


def _decade(x: float) -> LogUniform:
    return LogUniform(x / 10.0, x * 10.0)


#: The prior every replicate draws from and is fitted under (see module docstring).
STUDY_SBC_PRIORS = {
    "b": LogUniform(300.0, 3.0e4),
    "f_0": _decade(_F0),
    "f_share": Uniform(0.0, 1.0),
    "c_f": _decade(_CF),
    "c_share": Uniform(0.0, 1.0),
    "c_n": _decade(TABLE_I["c_n"]),
    "k_n": _decade(TABLE_I["k_n"]),
    "c_B": _decade(TABLE_I["c_B"]),
    "k_B": _decade(TABLE_I["k_B"]),
}

#: The interval levels checked: the study's 94 % and the 50 %.
LEVELS = (0.94, 0.5)

#: Where a single-record replicate's intervals are taken from (``StudyCalibration.interval_draws``).
INTERVAL_DRAWS = ("simulated", "kept")

#: Which device makes a replicate's motion (``StudyCalibration.motion_device``).
MOTION_DEVICES = ("truth", "independent")


@dataclass(frozen=True)
class StudyCalibration:
    """One calibration run in the study's configuration.

    Attributes
    ----------
    setting : flywheel setting whose masses the devices have (b is drawn).
    frequencies : drive frequencies of each replicate's records, Hz.
    generator : how records are made (default: the study's, 10 s with a 2 s ramp).
    steps : steps of each chain; None: to the convergence rule, at most ``max_steps``.
    draws : L, the posterior draws each truth is ranked among.
    seed : replicate k uses the seed sequence (seed, k).
    single : one record per replicate, fitted alone (see module docstring).
    likelihood : the fits' likelihood settings (default: the time-domain AR(1) one that
        the committed results/study-calibration replicates were made with, so that a
        folder saved before this option existed is continued under its own likelihood).
    max_steps : the cap of a chain run to the convergence rule.
    tempering : the fits' parallel tempering (``sampler.Tempering``; None: none).
    tau_floor : the floor of the discrepancy tau's log-uniform prior, N, in the fits
        (None: the package's, ``priors.MOTION_DISCREPANCY_PRIORS``); a probe of the
        likelihood (results/noise-free-tau-floor), not the package's prior.
    tau_rtol : the convergence rule's tolerance of tau's growth between checks
        (``Convergence.tau_rtol``; default: the 0.05 its committed folders were stopped
        with, ``stop_rule.TAU_RTOL_BEFORE``, so that a folder saved before this option
        existed is continued under its own rule).
    replica_rule : a tempered chain's tau is also read on its replicas
        (``Convergence.replicas``; default False, the rule the committed folders were
        stopped with).
    draw_deviations : add to each record's force the deviations the motion-in likelihood
        marginalises and the generator's device lacks (the reversals' and the friction
        law's), drawn from their prior (:func:`drawn_deviations`): the likelihood's own
        generative model, so that the calibration checks the computation of the posterior
        it defines (default False: the records of the model's physics alone, as the
        folders saved before this option were made).
    likelihood_force : replace each record's force harmonics by a draw from the motion-in
        likelihood itself at the truth (:func:`likelihood_force`): a calibration of the
        posterior's computation alone, the likelihood's approximations of the simulator
        left out (default False).
    interval_draws : where a single-record replicate's intervals (and ranks) are taken
        from (:data:`INTERVAL_DRAWS`): "simulated", the at most
        ``summaries.results.MAX_DRAWS`` (600) draws of the fit's InferenceData, the
        default, so that a folder saved before this option existed is continued as it was
        made; or "kept", the chain's kept draws thinned to at most
        ``fit.JOINT_DRAWS_KEPT`` (4,000), as the joint fit's always are and as near as a
        file keeps them to the draws summary.csv's intervals come from. An interval's
        ends estimated from fewer draws hold a fresh draw less often than its level
        (results/hdi-from-draws).
    domain : draw the devices from the prior restricted to the impedance coordinates'
        domain (``posterior.impedance``), the prior a fit in those coordinates assumes:
        a device outside is drawn again (default False: the whole prior box, as the
        folders saved before this option were made; a fit can then never cover a truth
        outside the domain unless its start lies outside too and it walks the
        unconstrained coordinates). A joint calibration reads the joint fit's own
        coordinates.
    motion_device : which device makes the records' motion (:data:`MOTION_DEVICES`):
        "truth", the default, the drawn device itself; or "independent", a second device
        drawn from the same prior, independently of the truth, whose records' motion (and
        period scatter) the truth's force is then drawn on (with ``likelihood_force``
        only). The motion-in likelihood conditions on the measured motion and leaves out
        what the motion itself says of the device (the servo yields to the device's
        force). With the motion independent of the truth there is almost nothing left
        out: the acceleration channel is still read through the truth's sensor gain (the
        gain is the truth's, as it is a sensor's), which the motion's amplitude then
        tells; and the truth is still one the generator simulates (a refused one is
        drawn again, as with its own motion). Apart from those two, the fits' posterior
        is the exact one, and its coverage nominal if the sampler, its rule and the
        intervals are right. ``ReplicateDevice.redraws`` counts the truth's redraws
        only.
    min_ratio : a replicate any of whose records reads an inertial-to-dissipative force
        ratio at its drive (``records.reactance.drive_impedance``, read from the record
        the fit sees) below this is drawn again, device and records (default None: every
        record). A joint replicate is kept only where every one of its records reads at
        least this. The selection reads the records alone, and each replicate's ranks
        are uniform given its records, so they stay uniform: the calibration then speaks
        for records at or above that ratio. Where the ratio is small the chains stop at
        their cap (results/capped-by-force-ratio).
    block_partners : how the fits' adaptive block moves pick their coordinates
        (``Adaptation.block_partners``; default its default, "random"). A run saved
        before the setting existed was fitted with "random" blocks and is continued
        with them (``calibration.LATER_SETTINGS``).
    """

    setting: str = "A3"
    frequencies: tuple = (0.5, 1.5)
    generator: GeneratorSettings = field(default_factory=GeneratorSettings)
    steps: int | None = 600
    draws: int = 99
    seed: int = 0
    single: bool = False
    likelihood: LikelihoodSettings = field(default_factory=lambda: LikelihoodSettings(residual="ar1"))
    max_steps: int = 6000
    tempering: Tempering | None = None
    tau_floor: float | None = None
    tau_rtol: float = stop_rule.TAU_RTOL_BEFORE
    replica_rule: bool = False
    draw_deviations: bool = False
    likelihood_force: bool = False
    interval_draws: str = "simulated"
    domain: bool = False
    motion_device: str = "truth"
    min_ratio: float | None = None
    block_partners: str = Adaptation().block_partners

    def __post_init__(self) -> None:
        object.__setattr__(self, "frequencies", tuple(float(f) for f in self.frequencies))
        if self.motion_device not in MOTION_DEVICES:
            raise ValueError(f"motion_device must be one of {', '.join(MOTION_DEVICES)}, got {self.motion_device!r}")
        if self.motion_device != "truth" and not self.likelihood_force:
            raise ValueError("an independent motion device needs the force drawn from the likelihood: "
                             "use motion_device with likelihood_force")
        if self.min_ratio is not None:
            if isinstance(self.min_ratio, bool) or not isinstance(self.min_ratio, (int, float)) \
                    or not math.isfinite(self.min_ratio) or self.min_ratio <= 0:
                raise ValueError(f"min_ratio must be a positive number, got {self.min_ratio!r}")
        if self.block_partners not in PARTNERS:
            raise ValueError(f"block_partners must be one of {', '.join(PARTNERS)}, got {self.block_partners!r}")
        if self.interval_draws not in INTERVAL_DRAWS:
            raise ValueError(f"interval_draws must be one of {', '.join(INTERVAL_DRAWS)}, got {self.interval_draws!r}")
        if self.draw_deviations and self.likelihood.residual != "motion":
            raise ValueError("draw_deviations draws the motion-in likelihood's deviations: use it with residual 'motion'")
        if self.likelihood_force and self.likelihood.residual != "motion":
            raise ValueError("likelihood_force draws from the motion-in likelihood: use it with residual 'motion'")
        if self.likelihood_force and self.draw_deviations:
            raise ValueError("likelihood_force draws the deviations itself: leave draw_deviations off")
        if len(self.frequencies) < 2 and not self.single:
            raise ValueError("the joint model needs at least two drive frequencies")
        if not (self.steps is None or (isinstance(self.steps, int) and self.steps >= 20)):
            raise ValueError(f"steps must be None or a whole number of at least 20, got {self.steps!r}")
        if not (isinstance(self.draws, int) and self.draws >= 9):
            raise ValueError(f"draws must be a whole number of at least 9, got {self.draws!r}")
        if self.tau_floor is not None:
            if self.likelihood.residual != "motion":
                raise ValueError("tau_floor is the motion-in likelihood's discrepancy floor: use it with residual 'motion'")
            tau_floor_prior(self.tau_floor)  # its own check

    def priors(self) -> dict:
        """The fits' priors: :data:`STUDY_SBC_PRIORS`, with tau's floor raised where asked."""
        if self.tau_floor is None:
            return STUDY_SBC_PRIORS
        return {**STUDY_SBC_PRIORS, "tau": tau_floor_prior(self.tau_floor)}

    #: Its replicates' fits continue from a checkpoint kept in a work folder
    #: (``calibration.run_replicates``'s ``work`` gives each one): a chain of tens of
    #: thousands of steps stopped by a session's end goes on where it stopped.
    resumes: ClassVar[bool] = True

    def replicate(self, k: int, folder=None) -> dict:
        return study_replicate(self, k, folder)

    def describe(self) -> str:
        steps = (f"{self.steps} steps per chain" if self.steps else
                 f"each chain to the convergence rule (at most {self.max_steps} steps)")
        what = ("single-record fits, one record each at" if self.single else
                f"joint fits of {len(self.frequencies)} records,")
        return (f"{what} {', '.join(f'{f:g}' for f in self.frequencies)} Hz ({self.generator.duration:g} s, masses "
                f"of {self.setting}, the {self.likelihood.residual} likelihood), {steps}, ranks among {self.draws} "
                f"draws, seed {self.seed}" + ("" if self.tempering is None else f", {self.tempering.describe()}")
                + ("" if self.tau_floor is None else f", tau's prior floor {self.tau_floor:g} N")
                + (", the likelihood's deviations drawn into the force" if self.draw_deviations else "")
                + (", the force's harmonics drawn from the likelihood itself" if self.likelihood_force else "")
                + (", the motion made by an independent device" if self.motion_device == "independent" else "")
                + (f", {self.block_partners} block moves" if self.block_partners != Adaptation().block_partners
                   else ""))


@dataclass(frozen=True)
class ReplicateDevice:
    """Replicate k's device as the study draws it: its network's parameters, the true
    values of the ranked parameters (the sensors' gain among them), its records (the
    acceleration channel scaled by the gain), the prior draws the simulator refused, and
    the whole drawn vector in the fits' sampled coordinates (``theta``: the likelihood's
    own parameters too, the channels' delay that drew the records among them, and tau's
    draw, which the records do not use: they carry no discrepancy)."""

    params: object
    truth: dict
    records: list
    redraws: int
    theta: tuple = ()


def replicate_device(cs: StudyCalibration, k: int) -> ReplicateDevice:
    """Replicate ``k``'s device and records, the same as :func:`study_replicate` fits
    (to record the same device again, with other noise or none)."""
    return _draw_device(cs, np.random.default_rng([cs.seed, k]), k)


def _draw_device(cs: StudyCalibration, rng: np.random.Generator, k: int = 0) -> ReplicateDevice:
    """A device from the prior and its records (a draw the simulator refuses is drawn
    again: the posterior gives it zero density too; so is one outside the impedance
    coordinates' domain where ``cs.domain`` asks). A draw kept is the same whether or
    not ``cs.domain`` is set: the check draws nothing."""
    base = _base_model(cs, STUDY_SBC_PRIORS)
    ranked = base.names[: base.n_phys] + [n for n in base.names[base.n_phys:] if n == "gain"]
    freqs = cs.frequencies if not cs.single else (cs.frequencies[k % len(cs.frequencies)],)
    for redraws in range(100):
        drawn = _simulated_draw(cs, base, freqs, rng)
        if drawn is None:
            continue
        theta, params, records = drawn
        if cs.motion_device == "independent":
            records = _independent_motion(cs, base, freqs, rng)
        if cs.domain and not (in_domain(cs, records[0], theta) if cs.single else _in_joint_domain(cs, records, theta)):
            continue
        truth = base.values(theta)
        gain = truth.get("gain", 1.0)
        records = [dataclasses.replace(r, accel=r.accel * gain) for r in records]
        if cs.draw_deviations:
            records = [drawn_deviations(r, params, cs.likelihood, rng) for r in records]
        if cs.likelihood_force:
            records = [likelihood_force(r, theta, cs.likelihood, rng) for r in records]
        if cs.min_ratio is not None and not all(drive_impedance(r).ratio >= cs.min_ratio for r in records):
            continue
        return ReplicateDevice(params, {n: float(truth[n]) for n in ranked}, records, redraws,
                               tuple(float(v) for v in theta))
    raise RuntimeError("100 prior draws in a row could not be simulated")


def _simulated_draw(cs: StudyCalibration, base: PosteriorModel, freqs, rng: np.random.Generator):
    """(theta, parameters, records) of one draw from ``base``'s prior recorded at
    ``freqs``, or None where the generator refuses it. Where the likelihood marginalises
    a model-form error of b (``LikelihoodSettings.form_sd`` s, ``form_friction`` rho),
    each record is made with b e^eps, drawn after theta and anew for each record (each
    record's likelihood has its own): eps normal with sd sqrt(s^2 + (rho f_0 / (b w^2 X))^2)
    (``summaries.model_form.ModelFormError``'s law; the Coulomb forces over the inertial
    force's amplitude at the drive's amplitude X). The device's b is the truth the
    posterior is held against, as the likelihood assumes."""
    theta = np.array([base.all_priors[n].sample(rng) for n in base.names])
    try:
        params = base.parameters(theta)
        s, rho = cs.likelihood.form_sd, cs.likelihood.form_friction
        records = []
        for f in freqs:
            recorded = params
            if s or rho:  # the model-form errors the likelihood marginalises: the record's b is b e^eps
                accel = (2.0 * math.pi * f) ** 2 * cs.generator.amplitude
                b = ModelFormError(sd=s, friction=rho).draws(params.b, params.f1_0 + params.f2_0, accel, rng)
                recorded = dataclasses.replace(params, b=float(b))
            records.append(generate_record(recorded, f, settings=cs.generator, rng=rng, setting_name=cs.setting))
        return theta, params, records
    except (SimulationError, ValueError):
        return None


def _independent_motion(cs: StudyCalibration, base: PosteriorModel, freqs, rng: np.random.Generator) -> list:
    """Records of a second device drawn from ``base``'s prior (drawn again until the
    generator simulates it), whose motion a truth's force is drawn on
    (``StudyCalibration.motion_device`` "independent")."""
    for _ in range(100):
        drawn = _simulated_draw(cs, base, freqs, rng)
        if drawn is not None:
            return drawn[2]
    raise RuntimeError("100 prior draws in a row could not be simulated")


def _base_model(cs: StudyCalibration, priors: dict) -> PosteriorModel:
    """The model of a record of the paper's ``cs.setting`` at the first frequency under
    ``priors``: the parameters a replicate's fit samples, and their priors."""
    template = generate_record(paper_parameters(cs.setting), cs.frequencies[0], settings=cs.generator,
                               rng=np.random.default_rng([cs.seed, 10**6]), setting_name=cs.setting)
    return PosteriorModel(template, priors=priors, likelihood=cs.likelihood)


def fitted_priors(cs: StudyCalibration) -> dict:
    """The priors of the physical parameters the fits sample, by name, as the model
    takes them from ``cs.priors()`` (the bearing's damper as the plate mode's damping
    ratio zeta_B where the model samples it so, in place of the c_B the prior dict
    also holds)."""
    base = _base_model(cs, cs.priors())
    return {n: base.all_priors[n] for n in base.names[: base.n_phys]}


def in_domain(cs: StudyCalibration, record: Record, theta) -> bool:
    """Whether ``theta`` lies in the domain of the impedance coordinates a fit of
    ``record`` walks (``posterior.impedance``: the prior restricted to it). Read under
    :data:`STUDY_SBC_PRIORS`, the box ``theta`` is drawn from: a raised floor of tau's
    prior (``cs.tau_floor``) says nothing of the impedance map's domain."""
    model = PosteriorModel(record, priors=STUDY_SBC_PRIORS, likelihood=cs.likelihood)
    return default_coordinates(model, "impedance").contains(theta)


def _in_joint_domain(cs: StudyCalibration, records, theta) -> bool:
    """Whether ``theta`` (a single record's, every record's own part of the truth) lies in
    the domain of the impedance coordinates the joint fit of ``records`` walks, read as
    :func:`in_domain` reads a single record's."""
    from ..inference.posterior.joint import JointModel

    jm = JointModel(tuple(records), priors=STUDY_SBC_PRIORS, likelihood=cs.likelihood)
    values = PosteriorModel(records[0], priors=STUDY_SBC_PRIORS, likelihood=cs.likelihood).values(
        np.asarray(theta, dtype=float))
    joint = jm.start([values] * len(records))
    return default_coordinates(jm, "impedance").contains(joint)


#: Which of the motion-in likelihood's deviations :func:`drawn_deviations` draws.
DEVIATION_GROUPS = ("all", "reversals", "law")


def drawn_deviations(record: Record, params, likelihood: LikelihoodSettings, rng: np.random.Generator,
                     envelope: float | None = None, groups: str = "all") -> Record:
    """``record`` with the motion-in likelihood's marginalised deviations added to its
    force: the reversals' and the friction law's (``MotionData.basis`` before the input
    noise's shapes, which stand for noise the record already has), each coefficient drawn
    normal with the prior sd the likelihood gives it at ``params``' Coulomb forces, as the
    periodic signal sum_k Re(X_k exp(i k w t)) whose harmonics X = U beta are the ones
    the likelihood compares (``drive`` from t = 0); ``groups`` (:data:`DEVIATION_GROUPS`)
    draws only the reversals' or only the law's, the others left at zero (the same draws
    of the kept ones as "all" gives, so that a group's share can be told apart). It rises
    with a raised cosine over ``envelope`` s (None: the generator's ramp, from the
    record's metadata) so that the start-up stays smooth; the steady periods the
    likelihood takes hold it whole.

    What it leaves out: the discrepancy tau k^(-alpha) (its log-uniform prior spans
    1e-3 to 1e5 N, and draws from it would swamp most records) and the sampled
    scale of the law's (``law_sampled``): the deviations are drawn at the fixed
    ``friction_law.SD``."""
    if likelihood.law_sampled:
        raise ValueError("drawn_deviations draws at the fixed friction_law.SD; law_sampled samples that scale")
    if groups not in DEVIATION_GROUPS:
        raise ValueError(f"groups must be one of {', '.join(DEVIATION_GROUPS)}, got {groups!r}")
    model = PosteriorModel(record, priors=STUDY_SBC_PRIORS, likelihood=likelihood)
    motion = model.motion
    K = motion.omega.shape[0]
    s = motion.scale @ np.array([params.f1_0, params.f2_0, 1.0])
    beta = rng.normal(size=s.shape[0]) * s
    if groups != "all":
        law = np.zeros(s.shape[0], dtype=bool) if motion.law_columns is None else np.asarray(motion.law_columns)
        beta = np.where(law if groups == "law" else ~law, beta, 0.0)
    X = motion.basis @ beta
    return _with_periodic_force(record, X[:K] + 1j * X[K:], motion.omega, envelope)


def _with_periodic_force(record: Record, X: np.ndarray, omega: np.ndarray, envelope: float | None) -> Record:
    """``record`` with sum_k Re(X_k exp(i w_k t)) added to its force (t from the record's
    first sample, as the harmonic data's phases are), rising with a raised cosine over
    ``envelope`` s (None: the generator's ramp, from the record's metadata)."""
    t = np.asarray(record.time, dtype=float)
    delta = np.real(np.exp(1j * np.outer(t, omega)) @ X)
    rise = float(record.metadata.get("generator", {}).get("ramp", 0.0)) if envelope is None else float(envelope)
    if rise > 0.0:
        u = np.clip((t - t[0]) / rise, 0.0, 1.0)
        delta = delta * 0.5 * (1.0 - np.cos(np.pi * u))
    return dataclasses.replace(record, force=record.force + delta)


def likelihood_force(record: Record, theta, likelihood: LikelihoodSettings, rng: np.random.Generator,
                     envelope: float | None = None) -> Record:
    """``record`` with its force's harmonics replaced by a draw from the motion-in
    likelihood itself at ``theta`` (the truth, in the sampled coordinates of
    :data:`STUDY_SBC_PRIORS`' model): the model's force given the record's measured
    motion, F^_k(theta), plus complex normal noise of the likelihood's variance V_k
    (both channels' noise as the record's period scatter gives it, no discrepancy: tau
    0) and every deviation the likelihood marginalises (the reversals', the friction
    law's and the measured motion's noise shapes, each drawn normal with the prior sd
    the likelihood gives it at ``theta``, whose point is also the shapes' reference).

    Only the force's mean harmonics 1..K change (a periodic signal is added, see
    :func:`_with_periodic_force`): the motion, the period scatter and so everything
    else the likelihood reads stay the record's. A calibration on such records checks
    the computation of the posterior the likelihood defines (the sampler, its stopping
    rule, the intervals), apart from how far the likelihood is from the simulator."""
    if likelihood.law_sampled:
        raise ValueError("likelihood_force draws at the fixed friction_law.SD; law_sampled samples that scale")
    theta = np.asarray(theta, dtype=float)
    model = PosteriorModel(record, priors=STUDY_SBC_PRIORS, likelihood=likelihood).with_reference(theta)
    motion = model.motion
    K = motion.omega.shape[0]
    x, h = model.field_vector(theta), model.hyper(theta)
    F, _ = predicted_force(motion, x, h["gain"], h["delay"], effects=model.effects(theta))
    V, _ = motion_variance(motion, x, 0.0, 0.0, h["gain"], h["delay"])
    noise = (rng.normal(size=K) + 1j * rng.normal(size=K)) * np.sqrt(V / 2.0)
    s = deviation_sd(motion, x)
    beta = rng.normal(size=s.shape[0]) * s
    X = motion.basis @ beta
    target = F + noise + X[:K] + 1j * X[K:]
    return _with_periodic_force(record, target - motion.harmonic.force, motion.omega, envelope)


def _fit_replicate(cs: StudyCalibration, k: int, out: Path):
    """Replicate ``k``'s device, drawn and fitted into ``out``: (its generator, the
    device's true values, its records, the redraws, the fit, every kept draw by name).
    The same ``k`` gives the same device, records, start and chain."""
    rng = np.random.default_rng([cs.seed, k])
    device = _draw_device(cs, rng, k)
    truth, records, redraws = device.truth, device.records, device.redraws
    convergence = stop_rule.convergence(cs.max_steps, cs.tau_rtol, replicas=cs.replica_rule)
    adaptation = Adaptation(block_partners=cs.block_partners)
    if cs.single:
        kept_draws = cs.interval_draws == "kept"
        res = fit_record(records[0], out, steps=cs.steps, seed=int(rng.integers(2**31)), priors=cs.priors(),
                         plots=False, likelihood=cs.likelihood, convergence=convergence, interval="posterior",
                         tempering=cs.tempering, all_draws=kept_draws, adaptation=adaptation)
        if kept_draws:
            with np.load(out / ALL_DRAWS_FILE) as f:
                kept = {n: f[n].ravel() for n in f.files}
        else:
            post = res.idata.posterior
            kept = {n: np.asarray(post[n]).ravel() for n in post.data_vars}
        kept[f"b_{cs.setting}"] = kept.pop("b")
    else:
        res = fit_joint(records, out, steps=cs.steps, seed=int(rng.integers(2**31)), priors=cs.priors(),
                        plots=False, all_draws=True, likelihood=cs.likelihood, convergence=convergence,
                        tempering=cs.tempering, adaptation=adaptation)
        with np.load(out / ALL_DRAWS_FILE) as f:
            kept = {n: f[n].ravel() for n in f.files}
    return rng, truth, records, redraws, res, kept


def study_replicate(cs: StudyCalibration, k: int, folder=None) -> dict:
    """Replicate ``k``: the truth's rank among ``cs.draws`` posterior draws per physical
    parameter, whether each of the :data:`LEVELS` intervals (highest-density and
    equal-tailed) holds it, and the chain's diagnostics. ``folder``: where its fit runs,
    continued from the checkpoint there if an earlier run left one (the caller removes it
    once the replicate is written: ``calibration.run_replicates``; None: a temporary
    folder, nothing kept if stopped)."""
    with fit_folder(folder) as where:
        rng, truth, _, redraws, res, kept = _fit_replicate(cs, k, where)
    kept["b"] = kept.pop(f"b_{cs.setting}")
    n_kept = len(kept["b"])
    if n_kept < cs.draws:
        raise RuntimeError(f"only {n_kept} posterior draws kept, fewer than the {cs.draws} to rank among")
    pick = rng.choice(n_kept, cs.draws, replace=False)
    tau = np.asarray(res.tau, dtype=float)
    out = {"replicate": k, "redraws": redraws, "iterations": int(res.iterations), "converged": bool(res.converged),
           "tau_max": float(np.nanmax(tau)) if np.any(np.isfinite(tau)) else None, "L": cs.draws,
           "kept": n_kept, "truth": truth, "ranks": {}, "hdi": {}, "central": {},
           # which chains are slow and why, readable later without running them again
           "coordinates": res.coordinates, "tau_by_parameter": res.tau_by_parameter}
    for name, t in truth.items():
        got = _held(kept[name], t, pick)
        out["ranks"][name] = got["rank"]
        for form in ("hdi", "central"):
            for key, inside in got[form].items():
                out[form].setdefault(key, {})[name] = inside
    if "gain" in truth:
        out["identified"] = {IDENTIFIED: _held(kept["b"] / kept["gain"], truth["b"] / truth["gain"], pick)}
    return out


#: The combination a record identifies where the sensors' gain is sampled: the predicted
#: force scales the measured acceleration by b / gain, so b's interval is b / gain's
#: (the data's) widened by the gain's prior (which the data leave as it is). Its rank and
#: intervals are kept beside the parameters' (``identified`` in a replicate's JSON), so
#: that a shortfall of b's coverage can be told apart from the gain draws' own spread.
IDENTIFIED = "b/gain"


def _held(x: np.ndarray, t: float, pick: np.ndarray) -> dict:
    """The truth ``t``'s rank among the draws ``x[pick]`` and whether each of the
    :data:`LEVELS` intervals of ``x`` (highest-density, equal-tailed) holds it."""
    got = {"truth": float(t), "rank": int(np.sum(x[pick] < t)), "hdi": {}, "central": {}}
    for level in LEVELS:
        key = f"{round(100 * level)}"
        lo, hi = hdi(x, level)
        got["hdi"][key] = bool(lo <= t <= hi)
        lo, hi = np.quantile(x, [0.5 - level / 2, 0.5 + level / 2])
        got["central"][key] = bool(lo <= t <= hi)
    return got


def coverage_rows(results: list[dict]) -> list[dict]:
    """Per physical parameter: the replicates run (failed ones included), the failed,
    and the coverage of each level's highest-density and equal-tailed interval, a failed
    replicate counting as a miss, with the binomial standard error at the nominal level,
    and a chi-square test of uniform ranks (10 bins) over the replicates that ran."""
    from scipy import stats

    ok = [r for r in results if "ranks" in r]
    if not ok:
        return []
    n = len(results)
    failed = n - len(ok)
    L = ok[0]["L"]
    rows = []
    for name in ok[0]["ranks"]:
        row = {"parameter": name, "replicates": n, "failed": failed}
        for level in LEVELS:
            key = f"{round(100 * level)}"
            row[f"hdi_{key}"] = sum(r["hdi"][key][name] for r in ok) / n
            row[f"central_{key}"] = sum(r["central"][key][name] for r in ok) / n
            row[f"se_{key}"] = math.sqrt(level * (1 - level) / n)
        counts = np.histogram([r["ranks"][name] for r in ok], bins=10, range=(0, L + 1))[0]
        row["rank_chi2_p"] = float(stats.chisquare(counts).pvalue)
        rows.append(row)
    return rows


def chains_long_enough(results: list[dict], factor: float = Convergence.n_tau) -> int:
    """How many replicates ran a chain of at least ``factor`` times its longest
    autocorrelation time (the first part of the study's convergence rule,
    ``Convergence.n_tau``)."""
    return sum(1 for r in results if r.get("tau_max") and r["iterations"] >= factor * r["tau_max"])


def raise_cap(out, max_steps: int) -> list[int]:
    """Raise the convergence cap of the run in ``out`` to ``max_steps``: the replicates
    whose chains stopped at the old cap unconverged move to ``out``/capped-<old cap>
    (kept, for the record) and a run into ``out`` with ``max_steps`` fits them again;
    settings.json takes the new cap. Returns the replicates moved.

    The cap enters a chain only where it stops it (``sampler._until_converged``), so a
    chain that converged before the old cap is the same chain under the new one, step
    for step, and its replicate stays as it is."""
    out = Path(out)
    settings_file = out / "settings.json"
    if not settings_file.is_file():
        raise ValueError(f"{out} holds no run (no settings.json); run the study into it first")
    saved = json.loads(settings_file.read_text())
    old = saved.get("max_steps")
    if saved.get("steps") is not None or old is None:
        raise ValueError(f"{out} ran fixed-length chains ({saved.get('steps')} steps), not to the convergence rule: "
                         "there is no cap to raise")
    if not (isinstance(max_steps, int) and max_steps > old):
        raise ValueError(f"the new cap must be a whole number of steps above the folder's {old}, got {max_steps!r}")
    if is_packed(out):
        raise ValueError(f"{out}'s replicates are packed; unpack them first "
                         "(python studies/pack_replicates.py --unpack)")
    moved = []
    keep = out / f"capped-{old}"
    for f in sorted((out / "replicates").glob("[0-9]*.json")):
        r = json.loads(f.read_text())
        if "error" not in r and not r.get("converged") and r.get("iterations", 0) >= old:
            keep.mkdir(exist_ok=True)
            f.replace(keep / f.name)
            moved.append(int(r["replicate"]))
    settings_file.write_text(json.dumps({**saved, "max_steps": max_steps}, indent=2) + "\n")
    return moved


def finished_replicates(out) -> list[dict]:
    """The replicates a run into ``out`` has finished so far (``out``/replicates, one
    JSON each, or packed: :mod:`.replicate_store`), in the order of their number: the
    state of a run that spans sessions."""
    return finished(out)


def coverage_so_far(results: list[dict]) -> list[dict]:
    """The coverage of the replicates finished so far, counted, over every chain and
    again over the converged ones alone (``chains``: "all" or "converged"): per physical
    parameter how many replicates' 94 % and 50 % highest-density intervals held the truth,
    and a row ``all parameters`` pooling them, each beside the count nominal coverage
    expects and its binomial standard error (parameters of one replicate are not
    independent, so the pooled se is a lower bound). A failed replicate is a miss.
    Replicates that rank an :data:`IDENTIFIED` combination add a row ``<name>
    (identified)`` counted over them alone (the pooled row leaves it out)."""
    rows = []
    for chains, group in (("all", results), ("converged", [r for r in results if r.get("converged")])):
        ok = [r for r in group if "ranks" in r]
        if not ok:
            continue
        names = list(ok[0]["ranks"])
        for name in [*names, "all parameters"]:
            keys = names if name == "all parameters" else [name]
            n = len(group) * len(keys)
            row = {"chains": chains, "parameter": name, "replicates": len(group), "intervals": n}
            for level in LEVELS:
                q = f"{round(100 * level)}"
                row[f"held_{q}"] = sum(bool(r["hdi"][q][k]) for r in ok for k in keys)
                row.update(_nominal(level, n))
            rows.append(row)
        carrying = [r for r in ok if "identified" in r]
        for name in dict.fromkeys(n for r in carrying for n in r["identified"]):
            held = [r["identified"][name] for r in carrying if name in r["identified"]]
            row = {"chains": chains, "parameter": f"{name} (identified)", "replicates": len(held),
                   "intervals": len(held)}
            for level in LEVELS:
                q = f"{round(100 * level)}"
                row[f"held_{q}"] = sum(bool(h["hdi"][q]) for h in held)
                row.update(_nominal(level, len(held)))
            rows.append(row)
    return rows


#: Truths' ranks correlated at least this much (in absolute value) across replicates are
#: listed by :func:`rank_correlations`: two such parameters' coverage counts are not
#: independent tests.
RANK_CORRELATION = 0.5
_RANK_FIELDS = ("parameter", "with", "r", "replicates")


def rank_correlations(results: list[dict], threshold: float = RANK_CORRELATION) -> list[dict]:
    """The pairs of parameters whose truths' ranks correlate across the finished
    replicates by at least ``threshold`` in absolute value (Pearson's r of the ranks),
    strongest first: where the records identify a combination of two parameters (b over
    the sensors' gain, say), the truth's rank of one follows the other's, and their
    coverage counts rise and fall together. [] with fewer than 3 replicates."""
    ok = [r for r in results if "ranks" in r]
    if len(ok) < 3:
        return []
    names = list(ok[0]["ranks"])
    ranks = np.array([[float(r["ranks"][n]) for n in names] for r in ok])
    rows = []
    for i, a in enumerate(names):
        for j in range(i + 1, len(names)):
            x, y = ranks[:, i], ranks[:, j]
            if np.std(x) == 0 or np.std(y) == 0:
                continue
            r = float(np.corrcoef(x, y)[0, 1])
            if abs(r) >= threshold:
                rows.append(dict(zip(_RANK_FIELDS, (a, names[j], round(r, 2), len(ok)))))
    return sorted(rows, key=lambda row: -abs(row["r"]))


def coverage_by_frequency(results: list[dict], frequencies) -> list[dict]:
    """:func:`coverage_so_far` of a single-record calibration split by drive frequency
    (replicate k is fitted at ``frequencies[k % len(frequencies)]``): each row of it with
    ``freq_hz`` in front. Where the coverage departs from nominal only at some
    frequencies, the pooled count hides it."""
    frequencies = tuple(float(f) for f in frequencies)
    rows = []
    for i, f in enumerate(frequencies):
        group = [r for r in results if int(r["replicate"]) % len(frequencies) == i]
        rows += [{"freq_hz": f, **row} for row in coverage_so_far(group)]
    return rows


def _nominal(level: float, n: int) -> dict:
    """The count a level's intervals hold in ``n`` tries at nominal coverage and its
    binomial se, keyed as the coverage rows keep them."""
    q = f"{round(100 * level)}"
    return {f"expected_{q}": round(level * n, 1), f"se_{q}": round(math.sqrt(level * (1 - level) * n), 1)}


def gain_draws(results: list[dict], gain_sd: float) -> list[dict]:
    """Where the replicates' true gains fell in their prior (log-normal about 1, log-sd
    ``gain_sd``): how many lay inside its central 94 % and 50 % intervals, beside the
    counts expected and their binomial se. The records leave the gain's posterior at its
    prior, so its coverage, and through b / gain b's, moves with these draws' own spread
    (the draws, not the likelihood). [] where no replicate drew a gain."""
    from scipy import stats

    z = [abs(math.log(r["truth"]["gain"])) / gain_sd for r in results if "gain" in r.get("truth", {})]
    if not z:
        return []
    row = {"parameter": "gain", "replicates": len(z)}
    for level in LEVELS:
        q = f"{round(100 * level)}"
        edge = stats.norm.ppf(0.5 + level / 2)  # the interval's half-width in prior sds
        row[f"inside_{q}"] = sum(v <= edge for v in z)
        row.update(_nominal(level, len(z)))
    return [row]


def write_coverage_so_far(out) -> list[dict]:
    """``out``/coverage_so_far.csv from :func:`coverage_so_far` of the replicates
    finished in ``out``, and ``out``/rank_correlations.csv from
    :func:`rank_correlations`; for a single-record calibration (its settings.json says
    ``single``) also ``out``/coverage_by_frequency.csv (:func:`coverage_by_frequency`);
    where the fits sampled a gain (settings.json's ``gain_sd``), ``out``/gain_draws.csv
    (:func:`gain_draws`). Returns the coverage rows."""
    from .analysis import write_csv

    finished = finished_replicates(out)
    rows = coverage_so_far(finished)
    write_csv(Path(out) / "coverage_so_far.csv", rows)
    write_csv(Path(out) / "rank_correlations.csv", rank_correlations(finished), fields=_RANK_FIELDS)
    settings_file = Path(out) / "settings.json"
    saved = json.loads(settings_file.read_text()) if settings_file.exists() else {}
    if saved.get("single") and saved.get("frequencies"):
        write_csv(Path(out) / "coverage_by_frequency.csv", coverage_by_frequency(finished, saved["frequencies"]))
    gain_sd = (saved.get("likelihood") or {}).get("gain_sd")
    drawn = gain_draws(finished, gain_sd) if gain_sd else []
    if drawn:
        write_csv(Path(out) / "gain_draws.csv", drawn)
    return rows


def write_study_calibration(out, cs: StudyCalibration, results: list[dict], versions: dict) -> dict:
    """``out``/coverage.csv, ranks.csv, coverage.png, ranks.png, REPORT.md and
    SECTION.md (the report's summary for results/full/REPORT.md) from the replicates."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from .analysis import write_csv
    from .calibration_report import study_calibration_report
    from .plots import plot_coverage, plot_ranks

    out = Path(out)
    ok = [r for r in results if "ranks" in r]
    rows = coverage_rows(results)
    write_csv(out / "coverage.csv", rows)
    write_csv(out / "ranks.csv", [{"replicate": r["replicate"], **r["ranks"], "iterations": r["iterations"],
                                    "tau_max": r["tau_max"], "redraws": r["redraws"]} for r in ok])
    if ok:
        names = list(ok[0]["ranks"])
        fig = plot_ranks({n: [r["ranks"][n] for r in ok] for n in names}, ok[0]["L"],
                         title=f"SBC in the study's configuration: rank histograms, {len(ok)} replicates")
        fig.savefig(out / "ranks.png", dpi=90)
        plt.close(fig)
        levels = [round(100 * q) for q in LEVELS]
        cases = {kind: [{"parameter": r["parameter"], "replicates": r["replicates"],
                         **{f"coverage_{q}": r[f"{key}_{q}"] for q in levels},
                         **{f"se_{q}": r[f"se_{q}"] for q in levels}} for r in rows]
                 for kind, key in (("highest density", "hdi"), ("equal-tailed", "central"))}
        fig = plot_coverage(cases, levels=levels, interval="")  # the legend names the two kinds
        fig.savefig(out / "coverage.png", dpi=90)
        plt.close(fig)
    report, section = study_calibration_report(out, cs, rows, results, versions,
                                               long_enough=chains_long_enough(results), levels=LEVELS,
                                               priors=fitted_priors(cs))
    return {"coverage": rows, "replicates": len(results), "failed": [r for r in results if "error" in r],
            "report": report, "section": section}


def run_study_calibration(cs: StudyCalibration, out, replicates: int, *, processes: int = 1, progress=None,
                          work=None, executor=None) -> dict:
    """Run ``replicates`` replicates into ``out`` (one JSON each; those already there are
    reused) and write the tables, figures and reports (:func:`write_study_calibration`).
    ``work``: where each replicate's fit runs until done (``calibration.run_replicates``)."""
    from ..inference.fit import versions
    from .calibration import run_replicates

    results = run_replicates(cs, out, replicates, processes=processes, progress=progress, work=work, executor=executor)
    return write_study_calibration(out, cs, results, versions())


def inspect_replicate(cs: StudyCalibration, k: int, out) -> dict:
    """Replicate ``k`` again with its fit kept in ``out``, to tell a wrong basin from a
    posterior that excludes the truth: the joint log posterior at the truth (the
    likelihood's own parameters, having no true value, at their posterior medians) and
    at the posterior medians, and every sampled parameter's truth beside its median and
    94 % equal-tailed interval, under the likelihood the chain sampled (its reference
    point, where it takes one, read from the checkpoint), and the log posterior of
    :data:`INSPECT_DRAWS` kept draws beside the truth's with the likelihood's own
    parameters maximised there (``log_posterior_truth_profiled``; ``draws_below_truth``:
    the share of the draws below it). A truth above most draws lies where the chain
    should have gone and did not. The same seed
    gives the same device, records and start as :func:`study_replicate`; a single-record
    calibration (``cs.single``) is inspected under its one record's model."""
    from ..inference.sampling.checkpoint import stored_identity
    from ..inference.posterior.joint import JointModel

    _, truth, records, _, res, kept = _fit_replicate(cs, k, Path(out))
    if cs.single:
        jm = PosteriorModel(records[0], priors=cs.priors(), likelihood=cs.likelihood)
        kept = {("b" if n == f"b_{cs.setting}" else n): x for n, x in kept.items()}
        known = {n: truth[n] for n in jm.names if n in truth}  # drawn with the device, gain included
    else:
        jm = JointModel(tuple(records), priors=cs.priors(), likelihood=cs.likelihood)
        known = {f"b_{cs.setting}": truth["b"], **{n: truth[n] for n in jm.shared},
                 **{n: truth[n] for n in jm.names if n == "gain"}}  # drawn with the device
    reference = (stored_identity(Path(out) / "chain.h5") or {}).get("reference")
    if reference is not None:  # the likelihood the chain sampled, with its reference point
        jm = jm.with_reference(reference)
    median = {n: float(np.median(kept[n])) for n in jm.names}
    # the likelihood's own parameters (rho or tau and alpha, the channels' delay) have
    # no true value: at the truth they sit at their posterior medians
    unknown = {n for n in jm.names if n not in known}
    at_truth = {**known, **{n: median[n] for n in unknown}}

    def theta_of(values) -> np.ndarray:  # sampled parameters by name, in the sampler's coordinates
        return np.array([math.log(values[n]) if jm.all_priors[n].log_scale else values[n] for n in jm.names])

    def log_post(values):
        return float(jm.log_prob(theta_of(values))[0])

    rows = [{"parameter": n, "truth": at_truth[n] if n not in unknown else None, "median": median[n],
             "q3": float(np.quantile(kept[n], 0.03)), "q97": float(np.quantile(kept[n], 0.97))} for n in jm.names]
    # the kept draws' own log posterior: a truth whose log posterior lies above most
    # draws' sits where the chain should have been and was not (a missed mode or ridge);
    # one below nearly all lies where the posterior gives little mass (too narrow)
    n_kept = len(kept[jm.names[0]])
    pick = np.random.default_rng([cs.seed, k, 1]).choice(n_kept, min(INSPECT_DRAWS, n_kept), replace=False)
    drawn = np.array([log_post({n: float(kept[n][i]) for n in jm.names}) for i in pick])
    # ... beside the truth's with the likelihood's own parameters maximised there (from
    # their medians and from the best draws' values): the medians of a curved posterior
    # (the channels' delay against b / gain) can lie tens of nats below every draw, so
    # the truth beside them says nothing of where the chain went
    free = [i for i, n in enumerate(jm.names) if n in unknown]
    base = theta_of(at_truth)
    starts = [base[free]] + [theta_of({n: kept[n][i] for n in jm.names})[free]
                             for i in pick[np.argsort(-drawn)[:PROFILE_STARTS]]]

    def neg(u):
        theta = base.copy()
        theta[free] = u
        lp = float(jm.log_prob(theta)[0])
        return -lp if math.isfinite(lp) else math.inf
    options = {"xatol": optimize.NM_XATOL, "fatol": optimize.NM_FATOL, "maxiter": optimize.NM_MAXITER}
    truth_lp = (max(-float(minimize(neg, x0, method="Nelder-Mead", options=options).fun) for x0 in starts)
                if free else log_post(at_truth))
    return {"replicate": k, "steps": int(res.iterations), "tau_max": float(np.nanmax(res.tau)),
            "log_posterior_truth": log_post(at_truth), "log_posterior_median": log_post(median),
            "log_posterior_truth_profiled": truth_lp,
            "log_posterior_draws": {f"q{q}": float(np.quantile(drawn, q / 100)) for q in (5, 50, 95)},
            "draws_below_truth": float(np.mean(drawn < truth_lp)), "parameters": rows}


#: How many kept draws :func:`inspect_replicate` evaluates the log posterior at.
INSPECT_DRAWS = 400
#: Starts of :func:`inspect_replicate`'s maximisation of the likelihood's own parameters
#: at the truth besides their medians: the best draws' values.
PROFILE_STARTS = 3


@dataclass(frozen=True)
class Config:
    """What ``studies/study_calibration.py`` is asked (see the module docstring).

    Attributes
    ----------
    replicates : how many replicates (0 to replicates - 1).
    steps : steps of each chain, unless ``converge``.
    seed : the design seed (replicate k: the seed sequence (seed, k)).
    single : one record per replicate, fitted alone (else the joint fit).
    residual : the likelihood (``LikelihoodSettings.residual``; None: the study's).
    input_noise : draws of the drivetrain's input noise (0: off; None: the library's).
    law_sampled : sample the friction law's deviations' scale
        (``LikelihoodSettings.law_sampled``; the motion-in likelihood).
    law : marginalise the friction law's deviations (``LikelihoodSettings.law``;
        default True, the library's).
    reversals : marginalise the friction's deviations at the plate's reversals
        (``LikelihoodSettings.reversals``; default True, the library's).
    normaliser : the motion-in likelihood's normaliser (``LikelihoodSettings.normaliser``;
        None: the library's).
    deviation_scale : where the motion-in likelihood takes its deviations' prior sd
        (``LikelihoodSettings.deviation_scale``; None: the library's).
    converge : each chain to the convergence rule, at most ``max_steps``.
    max_steps : the cap of a chain run to the rule.
    tempering : parallel tempering with this many temperatures, to beta 0.1 (None: none).
    tau_floor : the floor of tau's prior, N (``StudyCalibration.tau_floor``; None: the package's).
    tau_rtol : the convergence rule's tolerance of tau's growth (``StudyCalibration.tau_rtol``;
        None: its default).
    replica_rule : a tempered chain's tau read on its replicas too
        (``StudyCalibration.replica_rule``).
    adapt_hot : each hot ensemble's moves fitted to its own walkers
        (``Tempering.adapt_hot``; with ``tempering``).
    freqs : the drive frequencies, Hz (None: the study's).
    draw_deviations : the likelihood's marginalised deviations drawn into each record's
        force (``StudyCalibration.draw_deviations``; with ``residual`` "motion").
    likelihood_force : each record's force harmonics drawn from the likelihood itself
        (``StudyCalibration.likelihood_force``; with ``residual`` "motion").
    domain : devices from the prior restricted to the impedance coordinates' domain
        (``StudyCalibration.domain``).
    interval_draws : where a single record's intervals come from
        (``StudyCalibration.interval_draws``; None: its default).
    motion_device : which device makes the records' motion
        (``StudyCalibration.motion_device``; None: its default; with ``likelihood_force``).
    work : where each replicate's fit runs until done, continued by the next run
        (None: the output folder's ``.running``).
    raise_cap : raise the folder's cap to ``max_steps`` first (:func:`raise_cap`).
    summarise : only write coverage_so_far.csv (and its companions) from the replicates
        finished there (:func:`write_coverage_so_far`); run nothing.
    inspect : run this replicate again with its fit kept (:func:`inspect_replicate`).
    """

    replicates: int = field(default=200, metadata={"help": "how many replicates"})
    steps: int = field(default=StudyCalibration.steps, metadata={"help": "steps of each chain, unless --converge"})
    seed: int = field(default=0, metadata={"help": "the design seed"})
    single: bool = field(default=False, metadata={"help": "one record per replicate, fitted alone"})
    residual: str | None = field(default=None, metadata={"help": "the likelihood (LikelihoodSettings.residual)"})
    input_noise: int | None = field(default=None, metadata={
        "help": "draws of the drivetrain's input noise (0: off; default: the library's)"})
    law_sampled: bool = field(default=False, metadata={
        "help": "sample the friction law's deviations' scale (LikelihoodSettings.law_sampled)"})
    law: bool = field(default=True, metadata={
        "help": "marginalise the friction law's deviations (LikelihoodSettings.law; --no-law leaves them out of "
                "the fits, and of the force --likelihood-force draws)"})
    reversals: bool = field(default=True, metadata={
        "help": "marginalise the friction's deviations at the plate's reversals (LikelihoodSettings.reversals; "
                "--no-reversals leaves them out of the fits, and of the force --likelihood-force draws)"})
    normaliser: str | None = field(default=None, metadata={
        "help": "the motion-in likelihood's normaliser (LikelihoodSettings.normaliser; default: the library's)"})
    deviation_scale: str | None = field(default=None, metadata={
        "help": "where the motion-in likelihood takes its deviations' prior sd (LikelihoodSettings."
                "deviation_scale; default: the library's)"})
    form_sd: float | None = field(default=None, metadata={
        "help": "the motion-in likelihood's model-form sd of b (LikelihoodSettings.form_sd; default: the "
                "library's, 0: none)"})
    form_friction: float | None = field(default=None, metadata={
        "help": "the motion-in likelihood's model-form error scaled by the friction (LikelihoodSettings."
                "form_friction; default: the library's, 0: none)"})
    converge: bool = field(default=False, metadata={"help": "each chain to the convergence rule"})
    max_steps: int = field(default=StudyCalibration.max_steps, metadata={"help": "the cap of a chain run to the rule"})
    tempering: int | None = field(default=None, metadata={
        "help": "fit with parallel tempering of this many temperatures (default: none)"})
    tau_floor: float | None = field(default=None, metadata={
        "help": "the discrepancy tau's prior floor, N, with --residual motion (default: the package's)"})
    tau_rtol: float | None = field(default=None, metadata={
        "help": "the convergence rule's tolerance of tau's growth between checks (default: 0.05, the one "
                "the committed folders were stopped with; the package's is Convergence.tau_rtol)"})
    replica_rule: bool = field(default=False, metadata={
        "help": "with --tempering, read each chain's tau on its replicas too (Convergence.replicas)"})
    adapt_hot: bool = field(default=False, metadata={
        "help": "with --tempering, fit each hot ensemble's moves to its own walkers (Tempering.adapt_hot)"})
    freqs: tuple[float, ...] | None = field(default=None, metadata={"help": "drive frequencies, Hz"})
    draw_deviations: bool = field(default=False, metadata={
        "help": "draw the motion-in likelihood's marginalised deviations into each record's force"})
    likelihood_force: bool = field(default=False, metadata={
        "help": "draw each record's force harmonics from the motion-in likelihood itself (calibrates the "
                "posterior's computation alone)"})
    domain: bool = field(default=False, metadata={
        "help": "draw the devices from the prior restricted to the impedance coordinates' domain"})
    interval_draws: str | None = field(default=None, metadata={
        "help": "a single record's intervals from the fit's 600 'simulated' draws (the default) or its 'kept' "
                "draws (up to 4,000)"})
    min_ratio: float | None = field(default=None, metadata={
        "help": "draw a replicate again while any of its records' own inertial-to-dissipative force ratio "
                "at its drive (records.reactance) is below this (default: every record)"})
    motion_device: str | None = field(default=None, metadata={
        "help": "which device makes the records' motion: the 'truth' (default) or an 'independent' draw "
                "(with --likelihood-force)"})
    block_partners: str | None = field(default=None, metadata={
        "choices": PARTNERS, "help": "how the fits' block moves pick their coordinates (default: the package's, "
                                     "Adaptation.block_partners); a folder keeps one"})
    work: str | None = field(default=None, metadata={
        "help": "where each replicate's fit runs until done (default: OUT/.running)"})
    raise_cap: bool = field(default=False, metadata={"help": "raise the folder's cap to --max-steps first"})
    summarise: bool = field(default=False, metadata={
        "help": "write coverage_so_far.csv from the replicates finished there, run nothing"})
    inspect: int | None = field(default=None, metadata={"help": "run replicate K again, its fit kept"})

    def __post_init__(self) -> None:
        if not (isinstance(self.replicates, int) and self.replicates >= 1):
            raise ValueError(f"replicates must be a whole number of at least 1, got {self.replicates!r}")
        if (self.replica_rule or self.adapt_hot) and self.tempering is None:
            raise ValueError("--replica-rule and --adapt-hot act on a tempering ladder: give --tempering TEMPS too")
        self.settings()  # a bad likelihood or frequency fails here, before anything runs

    def settings(self) -> StudyCalibration:
        """The calibration's own settings."""
        extra = {}
        # the likelihood's settings the command line gave (the others at the library's)
        given = {"residual": self.residual or None, "input_noise": self.input_noise,
                 "law_sampled": True if self.law_sampled else None, "law": None if self.law else False,
                 "reversals": None if self.reversals else False,
                 "normaliser": self.normaliser or None,
                 "deviation_scale": self.deviation_scale or None,
                 "form_sd": self.form_sd, "form_friction": self.form_friction}
        changes = {k: v for k, v in given.items() if v is not None}
        if changes:
            extra["likelihood"] = LikelihoodSettings(**changes)
        if self.freqs:
            extra["frequencies"] = tuple(self.freqs)
        if self.tempering is not None:
            extra["tempering"] = Tempering(self.tempering, adapt_hot=self.adapt_hot)
        if self.tau_floor is not None:
            extra["tau_floor"] = self.tau_floor
        if self.tau_rtol is not None:
            extra["tau_rtol"] = self.tau_rtol
        if self.replica_rule:
            extra["replica_rule"] = True
        if self.draw_deviations:
            extra["draw_deviations"] = True
        if self.likelihood_force:
            extra["likelihood_force"] = True
        if self.interval_draws:
            extra["interval_draws"] = self.interval_draws
        if self.domain:
            extra["domain"] = True
        if self.motion_device:
            extra["motion_device"] = self.motion_device
        if self.min_ratio is not None:
            extra["min_ratio"] = self.min_ratio
        if self.block_partners is not None:
            extra["block_partners"] = self.block_partners
        return dataclasses.replace(StudyCalibration(), steps=None if self.converge else self.steps, seed=self.seed,
                                   single=self.single, max_steps=self.max_steps, **extra)


def _summary_lines(out) -> tuple[str, ...]:
    rows = write_coverage_so_far(out)
    if not rows:
        raise ValueError(f"{out} holds no finished replicate; run the study into it first")
    lines = [f"{r['chains']:>9} {r['parameter']:>14}: of {r['intervals']:4d} the 94 % held {r['held_94']:4d} "
             f"(expected {r['expected_94']}, se {r['se_94']}), the 50 % {r['held_50']:4d} "
             f"(expected {r['expected_50']}, se {r['se_50']})" for r in rows]
    lines += [f"ranks of {pair['parameter']} and {pair['with']} move together (r {pair['r']:+.2f}): "
              "their counts are not independent tests" for pair in rank_correlations(finished_replicates(out))]
    return tuple(lines)


def run(config: Config, out, executor, *, progress=None):
    """The calibration into ``out`` (replicates not yet there run on ``executor``, each in
    a process of its own), then its tables, figures and reports; or, as ``config``
    asks, a folder summarised, its cap raised first, or one replicate inspected
    (``values["inspect"]``: :func:`inspect_replicate`'s dict, in ``work``)."""
    from .calibration import RUNNING, failed_items
    from .output import StudyOutput

    out = Path(out)
    if config.summarise:
        written = [out / n for n in ("coverage_so_far.csv", "rank_correlations.csv", "coverage_by_frequency.csv")]
        lines = _summary_lines(out)
        return StudyOutput(written=tuple(p for p in written if p.exists()), lines=lines)
    cs = config.settings()
    lines = []
    if config.raise_cap:
        moved = raise_cap(out, config.max_steps)
        lines.append(f"cap raised to {config.max_steps} steps; replicates to fit again: {moved or 'none'}")
    if config.inspect is not None:
        kind = "single" if cs.single else "joint"
        folder = ((Path(config.work) if config.work else out / RUNNING)
                  / f"inspect_{kind}_seed{cs.seed}_{config.inspect}_{cs.steps}")
        got = inspect_replicate(cs, config.inspect, folder)
        return StudyOutput(lines=(*lines, json.dumps(got, indent=1)), values={"inspect": got})
    got = run_study_calibration(cs, out, config.replicates, progress=progress, work=config.work, executor=executor)
    lines.append(f"{got['replicates']} replicates, {len(got['failed'])} failed")
    return StudyOutput(written=(got["report"], got["section"]), lines=tuple(lines),
                       failed=failed_items(got["failed"]),
                       values=got)
