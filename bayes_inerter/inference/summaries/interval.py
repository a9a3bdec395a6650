"""b's reported interval: the posterior's, widened by what no record can show.

The posterior of b is exact for the model it was sampled under, with the record's
sensitivities taken as exact. A real device is neither: its sensors are known to their
calibration's accuracy, and its physics holds more than any fitted model. Two shares of
uncertainty in b that no amount of sampling reveals are therefore added to the
posterior's, in log b, as independent normal terms (a GUM type-B evaluation):

- **the sensors' calibration** (``records.sensitivity.SensorCalibration``): the ratio of
  the two sensitivities scales the identified b + m (m the moving mass);
- **the model discrepancy** (``inference.posterior.discrepancy``): the misfit the record shows at
  the drive's harmonics, carried to the fundamental, where it would move b.

The reported interval is the equal-tailed one of log b's posterior draws, each with a
draw of those two terms added (their spread is centred: they widen the interval, they
do not move it).

**Not identified.** Where the model reproduces less than ``phi_min`` of the record
(phi, eq. 5 on the filtered record; ``end_state.PHI_WARNING``, 0.5), the misfit is no
longer a small discrepancy beside b's signature: on records of a richer device such fits
put b at 1.8 to 18 times its value, far beyond what the harmonics show
(results/model-error). b is then reported as not identified, its interval the prior's
range.

``INTERVALS`` names the two ways: ``"honest"`` (both terms and the guard; the default)
and ``"posterior"`` (the posterior alone, right only for a record of the model itself
with exact sensors).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import asdict, dataclass, field

import numpy as np

from ...records.sensitivity import SensorCalibration
from ..posterior.discrepancy import DECAY, HARMONICS, harmonic_discrepancy
from .end_state import PHI_WARNING
from ..posterior.motion import FUNDAMENTAL_MAX

__all__ = ["IntervalSettings", "InertanceInterval", "INTERVALS", "DEFAULT_INTERVAL", "inertance_interval",
           "widened_interval", "combined_interval"]

LEVEL = 0.94


@dataclass(frozen=True)
class IntervalSettings:
    """How b's interval is made (see module docstring).

    calibration : the sensors' calibration uncertainties, or None (taken as exact).
    discrepancy : add the harmonic model discrepancy's share.
    decay, harmonics : the discrepancy's assumptions (``inference.posterior.discrepancy``).
    others : "held" (default): the discrepancy is carried to b with the other parameters
        held; "free": by the posterior's linear response (given ``cov``), which is wild
        where the posterior has flat directions (results/model-error).
    level : the interval's probability (0.94).
    phi_min : below this phi, b is not identified (None: always reported).
    fundamental_max : motion-in likelihood only: b is not identified where the fit's
        residual at the fundamental, in phase with the inertial force, exceeds this share
        of it (``motion.FUNDAMENTAL_MAX``, 0.1; None: always reported).
    """

    calibration: SensorCalibration | None = field(default_factory=SensorCalibration)
    discrepancy: bool = True
    decay: float = DECAY
    harmonics: int = HARMONICS
    level: float = LEVEL
    phi_min: float | None = PHI_WARNING
    others: str = "held"
    fundamental_max: float | None = FUNDAMENTAL_MAX

    def __post_init__(self) -> None:
        if self.others not in ("held", "free"):
            raise ValueError(f"others must be 'held' or 'free', got {self.others!r}")
        if not (isinstance(self.level, float) and 0.0 < self.level < 1.0):
            raise ValueError(f"the interval's level must be a probability strictly between 0 and 1, got {self.level!r}")


#: The ways of making b's interval, by name; ``DEFAULT_INTERVAL`` is what fit and study use.
INTERVALS = {
    "honest": IntervalSettings(),
    "posterior": IntervalSettings(calibration=None, discrepancy=False, phi_min=None),
}
DEFAULT_INTERVAL = "honest"


@dataclass(frozen=True)
class InertanceInterval:
    """b's median and interval (kg) at ``level``, and the three shares of its sd in log b;
    ``identified`` False where the record leaves b to the prior (``lo``, ``hi`` are then
    the prior's range); ``phi``: the record's median phi, where known."""

    method: str
    median: float
    lo: float
    hi: float
    level: float
    sd_log_posterior: float
    sd_log_sensors: float
    sd_log_discrepancy: float
    identified: bool = True
    phi: float = math.nan

    @property
    def relative_width(self) -> float:
        return (self.hi - self.lo) / self.median

    def covers(self, b: float) -> bool:
        return self.lo <= b <= self.hi

    def as_dict(self) -> dict:
        return asdict(self)

    def describe(self) -> str:
        """One line: the level, the method and the shares (sd of b, in per cent)."""
        if not self.identified:
            return (f"not identified: the model reproduces {self.phi:.0%} of the record, too little to tell b from "
                    f"what it lacks; the prior's range")
        shares = {"the sensors'": self.sd_log_sensors, "the discrepancy's": self.sd_log_discrepancy}
        added = [f"{k} {100 * v:.2g} %" for k, v in shares.items() if v > 0]
        how = f"the posterior's sd {100 * self.sd_log_posterior:.2g} %"
        how += " widened by " + " and ".join(added) if added else " alone"
        return f"{100 * self.level:g} % equal-tailed interval, {self.method}: {how}"


def widened_interval(log_b: np.ndarray, extra_sd: float, level: float, rng: np.random.Generator,
                     method: str = "", sensors: float = 0.0, discrepancy: float = 0.0) -> InertanceInterval:
    """The interval of draws ``log_b`` (any shape) each with a normal(0, ``extra_sd``) draw
    added, centred on the draws' own median (``sensors``, ``discrepancy``: the shares of
    ``extra_sd``, kept for the record)."""
    x = np.asarray(log_b, dtype=float).ravel()
    if x.size < 2 or not np.all(np.isfinite(x)):
        raise ValueError("b's interval needs at least two finite posterior draws")
    if not (math.isfinite(extra_sd) and extra_sd >= 0):
        raise ValueError(f"the added sd must be finite and non-negative, got {extra_sd!r}")
    noise = rng.standard_normal(x.size)
    widened = x + extra_sd * (noise - noise.mean())
    lo, hi = np.quantile(widened, [(1 - level) / 2, (1 + level) / 2])
    return InertanceInterval(method, float(np.exp(np.median(x))), float(np.exp(lo)), float(np.exp(hi)), level,
                             float(np.std(x, ddof=1)), sensors, discrepancy)


def inertance_interval(model, b_draws, theta, *, cov=None, phi: float = math.nan,
                       settings: IntervalSettings | None = None, method: str = "", rng: np.random.Generator,
                       b_name: str = "b") -> InertanceInterval:
    """b's interval for a single-record posterior ``model`` with kept draws ``b_draws``
    (kg, any shape) and ``theta``, the point the discrepancy is measured at (the draw of
    highest posterior, say); ``cov``, the posterior covariance of theta, lets the other
    parameters take up their share of the discrepancy where ``settings.others`` is
    "free" (``discrepancy.harmonic_discrepancy``); ``phi``: the posterior's median phi, for
    ``settings.phi_min``. ``settings`` default to ``INTERVALS[DEFAULT_INTERVAL]``."""
    settings = settings or INTERVALS[DEFAULT_INTERVAL]
    b = np.asarray(b_draws, dtype=float)
    if np.any(b <= 0):
        raise ValueError("b's draws must be positive")
    median = float(np.median(b))
    name = method or _name_of(settings)
    if settings.phi_min is not None and not phi >= settings.phi_min:
        if math.isnan(phi):
            raise ValueError("phi is needed to tell whether b is identified (or set phi_min=None)")
        prior = model.all_priors[b_name]
        lo, hi = np.exp(prior.bounds) if prior.log_scale else prior.bounds
        return InertanceInterval(name, median, float(lo), float(hi), settings.level, float(np.std(np.log(b), ddof=1)),
                                 0.0, 0.0, identified=False, phi=float(phi))
    if getattr(model, "motion", None) is not None and settings.fundamental_max is not None:
        misfit = model.fundamental_misfit(theta)
        if not misfit <= settings.fundamental_max:
            prior = model.all_priors[b_name]
            lo, hi = np.exp(prior.bounds) if prior.log_scale else prior.bounds
            return InertanceInterval(name, median, float(lo), float(hi), settings.level,
                                     float(np.std(np.log(b), ddof=1)), 0.0, 0.0, identified=False, phi=float(phi))
    sensors = 0.0
    if settings.calibration is not None:
        sensors = settings.calibration.inertance_sd(median, 0.0, model.m_s + model.m_B) / median
    discrepancy = 0.0
    if settings.discrepancy:
        if settings.others == "free" and cov is None:
            raise ValueError("others='free' needs the posterior covariance cov")
        discrepancy = harmonic_discrepancy(model, theta, cov=cov if settings.others == "free" else None,
                                           harmonics=settings.harmonics,
                                           decay=settings.decay, b_name=b_name).sd_log_b
    got = widened_interval(np.log(b), math.hypot(sensors, discrepancy), settings.level, rng, name, sensors,
                           discrepancy)
    return dataclasses.replace(got, phi=float(phi))


def combined_interval(parts, *, calibration: SensorCalibration | None, moving_mass: float, level: float = LEVEL,
                      method: str = "honest") -> InertanceInterval:
    """One inertance from several records' intervals of it (``InertanceInterval``: a
    setting's records at several frequencies), in log b: each a normal about its median
    with the posterior's and the discrepancy's sds, combined as a product; its sd
    multiplied by the Birge ratio sqrt(chi2 / (n - 1)) where the records disagree beyond
    their sds (their discrepancies then differ from one frequency to the next more than
    the harmonics showed); then the sensors' share, added once (one pair of sensors
    made every record). ``moving_mass``: m_s + m_B, kg. Records whose b is not
    identified are left out; where none is left, neither is the combination."""
    every = list(parts)
    if not every:
        raise ValueError("no records to combine")
    parts = [p for p in every if p.identified]
    if not parts:
        worst = min(every, key=lambda p: p.phi if not math.isnan(p.phi) else math.inf)
        return dataclasses.replace(worst, method=method)
    mu = np.array([math.log(p.median) for p in parts])
    sd = np.array([math.hypot(p.sd_log_posterior, p.sd_log_discrepancy) for p in parts])
    if np.any(sd <= 0):
        raise ValueError("every record's interval must have a positive sd to be combined")
    w = 1.0 / sd ** 2
    mean = float(np.sum(w * mu) / np.sum(w))
    chi2 = float(np.sum(w * (mu - mean) ** 2))
    birge = math.sqrt(chi2 / (len(parts) - 1)) if len(parts) > 1 and chi2 > len(parts) - 1 else 1.0
    spread = birge / math.sqrt(float(np.sum(w)))
    b = math.exp(mean)
    sensors = calibration.inertance_sd(b, 0.0, moving_mass) / b if calibration is not None else 0.0
    total = math.hypot(spread, sensors)
    z = float(_normal_quantile((1 + level) / 2))
    posterior = 1.0 / math.sqrt(float(np.sum(1.0 / np.array([p.sd_log_posterior for p in parts]) ** 2)))
    return InertanceInterval(method, b, math.exp(mean - z * total), math.exp(mean + z * total), level, posterior,
                             sensors, math.sqrt(max(spread ** 2 - posterior ** 2, 0.0)))


def _normal_quantile(p: float) -> float:
    from scipy.stats import norm

    return float(norm.ppf(p))


def _name_of(settings: IntervalSettings) -> str:
    for name, known in INTERVALS.items():
        if known == settings:
            return name
    return "custom"
