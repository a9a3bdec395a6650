"""What a study fits: its records, models and sampler settings.

A study is a list of fit jobs (one record under one model) plus where its records come
from: the paper's grid of generated records (nine flywheel settings at 0.5, 1 and
1.5 Hz, paper parameters) or a user's folder of CSV records. Two plans are built in:

- :func:`quick_plan`: three settings (A0, A3, B2) at 1 Hz with the two-port model, and
  the rigid-body and linear models on A3, each chain a fixed, short number of steps. It
  runs on one core in minutes and is **not converged**: the report says so. It shows the
  whole pipeline and the order of magnitude of every answer.
- :func:`full_plan`: all 27 records with the two-port model until converged, the
  three nested models on the 1 Hz records for the comparison, the joint model of
  all 27 records (one b per setting, everything else shared), and the paper's
  least-squares fit of every record beside its posterior.
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from pathlib import Path

from ..device import FREQUENCIES_HZ, SETTINGS
from ..inference.posterior.model import MODELS

#: The models the study's comparison fits beside the two-port model: the paper's nested
#: ones (the richer models are a choice: ``compare_models``).
COMPARE_MODELS = ("rigid", "linear")
from ..records.generator import GeneratorSettings
from ..records.sensitivity import SensorCalibration

__all__ = ["FitJob", "StudyPlan", "quick_plan", "full_plan", "record_name"]


def record_name(setting: str, freq: float) -> str:
    """File stem of a generated record, e.g. ``A1_1Hz``."""
    return f"{setting}_{freq:g}Hz"


@dataclass(frozen=True)
class FitJob:
    """One posterior: a record (CSV path) under one model, written into ``out``."""

    record: str
    out: str
    model: str = "two-port"
    steps: int | None = None
    walkers: int | None = None
    seed: int = 0
    #: parallel tempering's temperatures (``sampler.Tempering``, down to its default
    #: hottest beta); None: the ensemble alone
    tempering: int | None = None
    #: the chain's cap when it runs to the convergence rule (``steps`` None); None:
    #: ``fit``'s own (``tempering.default_convergence``)
    max_steps: int | None = None

    @property
    def key(self) -> str:
        return f"{Path(self.record).stem}/{self.model}"


@dataclass(frozen=True)
class StudyPlan:
    """A study's records and fits.

    Attributes
    ----------
    name : the study's name (``runs/<name>/`` by default on the command line).
    settings, frequencies : the grid of generated records (ignored with ``records_dir``).
    records_dir : a folder of the user's CSV records to fit instead of generated ones;
        each needs ``setting`` (or ``m_s``) in its metadata, and its ``drive_frequency_hz``
        or else it is estimated from the record (``records.drive``).
    generator : how generated records are made; ``seed`` seeds their noise.
    steps : steps per chain; None runs each until converged.
    max_steps : the single-record chains' cap when they run until converged (None:
        ``fit``'s, 20,000 steps, 10,000 tempered); not the joint model's.
    comparison : (settings, frequencies) of the records also fitted with the
        ``compare_models``.
    compare_models : the models fitted beside the two-port one in the comparison
        (default :data:`COMPARE_MODELS`, the paper's nested rigid and linear models; any
        of ``inference.posterior.model.MODELS``).
    walkers : walkers per chain (None: the package's default).
    joint : also sample the joint model (shared frictions and deformations, one b per
        setting) on all the two-port records, started from their single-record
        posteriors, into ``<out>/joint``.
    joint_steps : steps of the joint chain; None: until converged.
    calibration : the sensors' calibration uncertainty (**assumption**, see
        ``records.sensitivity``), added to b in the tables' ``b_cal`` columns; it changes
        no fit.
    skip_checks : physical-sense checks (``records.checks.CHECKS``) not run on the
        user's records (``records_dir``).
    figures : each fit draws its own figures as it ends (several seconds a fit); by
        default they are drawn afterwards, for the fits one wants, by
        ``bayes-inerter report`` (``study.redraw``).
    identify : also fit every record by the paper's least squares (eq. 4, about 20 s a 10 s
        record; ``study.least_squares``) and set it beside the posterior in
        ``least_squares.csv``.
    tempering : the single-record fits' parallel tempering, temperatures (None, the
        default: the ensemble alone, as ``fit``'s and results/full's).
        The joint model is not tempered.
    """

    name: str
    settings: tuple = tuple(SETTINGS)
    frequencies: tuple = FREQUENCIES_HZ
    records_dir: str | None = None
    generator: GeneratorSettings = field(default_factory=GeneratorSettings)
    seed: int = 0
    steps: int | None = None
    max_steps: int | None = None
    walkers: int | None = None
    comparison: tuple = ((), ())
    compare_models: tuple = COMPARE_MODELS
    joint: bool = False
    joint_steps: int | None = None
    calibration: SensorCalibration = field(default_factory=SensorCalibration)
    skip_checks: tuple = ()
    figures: bool = False
    identify: bool = False
    tempering: int | None = None

    def __post_init__(self) -> None:
        unknown = [s for s in self.settings if s not in SETTINGS]
        if unknown:
            raise ValueError(f"unknown flywheel settings {unknown}; choose from {', '.join(SETTINGS)}")
        odd = [m for m in self.compare_models if m not in MODELS or m == "two-port"]
        if odd:
            raise ValueError(f"comparison models must be other models of {', '.join(MODELS)}; got {odd}")
        for name in ("steps", "joint_steps", "max_steps"):
            value = getattr(self, name)
            if value is not None and not (isinstance(value, int) and value >= 1):
                raise ValueError(f"{name} must be a positive whole number or None, got {value!r}")
        if self.steps is not None and self.max_steps is not None:
            raise ValueError("steps fixes each chain's length and max_steps caps a chain run until converged: "
                             "give one of them")
        if self.tempering is not None and not (isinstance(self.tempering, int) and self.tempering >= 2):
            raise ValueError(f"tempering needs at least 2 temperatures, got {self.tempering!r}")

    def jobs(self, records: dict, out: Path) -> list[FitJob]:
        """Fit jobs for ``records`` (name -> (CSV path, setting, frequency)): the two-port
        fits first, in the records' order, then the comparison's. The two-port fits take
        longest (more parameters, so more walkers and steps), and processes that take the
        short ones last leave less of the machine idle while the last fit ends."""
        jobs = []
        comp_settings, comp_freqs = self.comparison
        for i, (name, (path, setting, freq)) in enumerate(sorted(records.items())):
            models = ["two-port"]
            if setting in comp_settings and freq in comp_freqs:
                models += list(self.compare_models)
            for model in models:
                jobs.append(FitJob(str(path), str(out / "fits" / model / name), model, self.steps,
                                   self.walkers, self.seed + i, self.tempering, self.max_steps))
        return sorted(jobs, key=lambda job: job.model != "two-port")  # stable: records' order within each


def quick_plan(**changes) -> StudyPlan:
    """The quick study (see module docstring)."""
    plan = StudyPlan(name="quick", settings=("A0", "A3", "B2"), frequencies=(1.0,), steps=400,
                     comparison=(("A3",), (1.0,)))
    return replace(plan, **changes)


def full_plan(**changes) -> StudyPlan:
    """The full study (see module docstring)."""
    plan = StudyPlan(name="full", comparison=(tuple(SETTINGS), (1.0,)), joint=True, identify=True)
    return replace(plan, **changes)
