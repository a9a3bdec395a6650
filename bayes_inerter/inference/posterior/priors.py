"""Priors on the physical parameters, in the log space where they are sampled.

Every parameter of the network is positive and may lie anywhere across orders of
magnitude, so each is sampled as theta = log(value) with a prior that is uniform in
theta between two bounds (log-uniform in the value) or normal in theta (log-normal).
The defaults (:data:`DEFAULT_PRIORS`) are **assumptions** of this package, wide enough
to hold the paper's values with orders of magnitude to spare; a user passes others.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["LogUniform", "LogNormal", "Uniform", "Normal", "delay_prior", "DEFAULT_PRIORS", "SPLIT_PRIORS",
           "NOISE_PRIORS", "DISCREPANCY_PRIORS", "MOTION_DISCREPANCY_PRIORS", "tau_floor_prior", "MODAL_PRIORS",
           "gain_prior", "TRUNCATIONS", "nut_damping_ratio", "NUT_DAMPING_FLOOR"]


@dataclass(frozen=True)
class LogUniform:
    """log(value) uniform on [log(low), log(high)]; value in the units of its parameter."""

    low: float
    high: float
    log_scale = True

    def __post_init__(self) -> None:
        if not (0 < self.low < self.high < math.inf):
            raise ValueError(f"LogUniform needs 0 < low < high < inf, got {self.low}, {self.high}")

    @property
    def bounds(self) -> tuple[float, float]:
        """Bounds in log space."""
        return math.log(self.low), math.log(self.high)

    def logpdf(self, theta: float) -> float:
        lo, hi = self.bounds
        return -math.log(hi - lo) if lo <= theta <= hi else -math.inf

    def sample(self, rng: np.random.Generator, size=None):
        lo, hi = self.bounds
        return rng.uniform(lo, hi, size)

    def describe(self) -> str:
        return f"log-uniform on [{self.low:g}, {self.high:g}]"


@dataclass(frozen=True)
class Uniform:
    """Uniform on [low, high], sampled as is (fractions, the AR(1) coefficient)."""

    low: float
    high: float
    log_scale = False

    def __post_init__(self) -> None:
        if not (-math.inf < self.low < self.high < math.inf):
            raise ValueError(f"Uniform needs finite low < high, got {self.low}, {self.high}")

    @property
    def bounds(self) -> tuple[float, float]:
        return self.low, self.high

    def logpdf(self, theta: float) -> float:
        return -math.log(self.high - self.low) if self.low <= theta <= self.high else -math.inf

    def sample(self, rng: np.random.Generator, size=None):
        return rng.uniform(self.low, self.high, size)

    def describe(self) -> str:
        return f"uniform on [{self.low:g}, {self.high:g}]"


@dataclass(frozen=True)
class LogNormal:
    """log(value) normal with median ``median`` and log-space sd ``sigma``, truncated to
    +- ``width`` sd (so the sampler and optimiser have bounds)."""

    median: float
    sigma: float
    width: float = 5.0
    log_scale = True

    def __post_init__(self) -> None:
        if not (self.median > 0 and self.sigma > 0 and self.width > 0):
            raise ValueError("LogNormal needs positive median, sigma and width")

    @property
    def bounds(self) -> tuple[float, float]:
        mu = math.log(self.median)
        return mu - self.width * self.sigma, mu + self.width * self.sigma

    def logpdf(self, theta: float) -> float:
        lo, hi = self.bounds
        if not lo <= theta <= hi:
            return -math.inf
        z = (theta - math.log(self.median)) / self.sigma
        return -0.5 * z * z - math.log(self.sigma * math.sqrt(2 * math.pi))

    def sample(self, rng: np.random.Generator, size=None):
        lo, hi = self.bounds
        x = rng.normal(math.log(self.median), self.sigma, size)
        return np.clip(x, lo, hi)

    def describe(self) -> str:
        return f"log-normal, median {self.median:g}, log-sd {self.sigma:g}"


@dataclass(frozen=True)
class Normal:
    """Normal with mean ``mean`` and sd ``sd``, sampled as is and truncated to +- ``width``
    sd (so the sampler and optimiser have bounds): a quantity of either sign."""

    mean: float
    sd: float
    width: float = 4.0
    log_scale = False

    def __post_init__(self) -> None:
        if not (math.isfinite(self.mean) and self.sd > 0 and self.width > 0):
            raise ValueError("Normal needs a finite mean and positive sd and width")

    @property
    def bounds(self) -> tuple[float, float]:
        return self.mean - self.width * self.sd, self.mean + self.width * self.sd

    def logpdf(self, theta: float) -> float:
        lo, hi = self.bounds
        if not lo <= theta <= hi:
            return -math.inf
        z = (theta - self.mean) / self.sd
        return -0.5 * z * z - math.log(self.sd * math.sqrt(2 * math.pi))

    def sample(self, rng: np.random.Generator, size=None):
        lo, hi = self.bounds
        return np.clip(rng.normal(self.mean, self.sd, size), lo, hi)

    def describe(self) -> str:
        return f"normal, mean {self.mean:g}, sd {self.sd:g}"


#: Default priors (SI units). Each spans at least three orders of magnitude around the
#: paper's value (Table I; b across all nine flywheel settings).
DEFAULT_PRIORS = {
    "b": LogUniform(100.0, 1e5),  # kg
    "f1_0": LogUniform(1.0, 1e4),  # N
    "c_f1": LogUniform(1e-3, 1e5),  # N s/m
    "f2_0": LogUniform(1e-2, 1e4),  # N
    "c_f2": LogUniform(1e-1, 1e5),  # N s/m
    "c_n": LogUniform(1e3, 1e8),  # N s/m
    "k_n": LogUniform(1e3, 1e9),  # N/m
    "c_B": LogUniform(1e-3, 1e6),  # N s/m
    "k_B": LogUniform(1e5, 1e10),  # N/m
}

#: Priors of the sampled sums and fractions of the two frictions (the default
#: parametrisation, see ``model``): the sums log-uniform over the ranges of the
#: parts' sums, the plate's share uniform on [0, 1].
SPLIT_PRIORS = {
    "f_0": LogUniform(1.0, 2e4),  # N, f1_0 + f2_0
    "f_share": Uniform(0.0, 1.0),  # f1_0 / (f1_0 + f2_0)
    "c_f": LogUniform(0.1, 2e5),  # N s/m, c_f1 + c_f2
    "c_share": Uniform(0.0, 1.0),  # c_f1 / (c_f1 + c_f2)
}

#: Prior of the plate mode's damping ratio, zeta_B = c_B / (2 sqrt(k_B m_B)) (the
#: default ``modal`` parametrisation, ``parameters``): log-uniform over 0.5 to 10 %, the
#: range of real structures' modal damping. **Assumption**: Table I's c_B of about
#: 1 N s/m (a ratio of 8e-6) is a tuning artefact the records do not identify.
MODAL_PRIORS = {
    "zeta_B": LogUniform(0.005, 0.10),
}

def nut_damping_ratio(b, k_n, c_n):
    """The damping ratio of the flywheel's mode on the nut, c_n / (2 sqrt(k_n b)) (the
    flywheel's inertance b on the nut's spring k_n and damper c_n); works on arrays."""
    return c_n / (2.0 * np.sqrt(k_n * b))


#: Truncations of the prior by a derived quantity, by name: given in ``priors`` (as a
#: prior of that name, ``PosteriorModel(priors={"zeta_n": LogUniform(0.005, 1e9)})``),
#: the prior is restricted to where the quantity lies within that prior's bounds; the
#: truncation adds no density of its own. None is applied by default. "zeta_n": the nut's
#: damping ratio (:func:`nut_damping_ratio`), a function of the sampled b, k_n and c_n.
TRUNCATIONS = {"zeta_n": (("b", "k_n", "c_n"), nut_damping_ratio)}

#: A floor on the nut's damping ratio at the plate mode's lower bound (0.5 %, real
#: structures' least modal damping): the candidate truncation measured in
#: ``studies/prior_tails.py`` (variant ``nut-damping``), not a default. Table I's nut has
#: a ratio near 28 at setting A3, overdamped, so the floor keeps it.
NUT_DAMPING_FLOOR = {"zeta_n": LogUniform(0.005, 1e12)}

RHO_BOUNDS = (-0.99, 0.99)

#: Priors of the residual model: scale (m/s^2, log-uniform) and AR(1) coefficient.
NOISE_PRIORS = {
    "sigma": LogUniform(1e-5, 10.0),
    "rho": Uniform(*RHO_BOUNDS),
}

#: Priors of the harmonic likelihood's discrepancy (``harmonic``): its scale tau, m/s^2,
#: log-uniform from far below any record's noise to far above any acceleration's, and
#: its spectral decay alpha (variance tau^2 k^(-2 alpha) at harmonic k), uniform from
#: white (0) to a discrepancy that lives at the first harmonics (2). **Assumptions**.
DISCREPANCY_PRIORS = {
    "tau": LogUniform(1e-7, 10.0),
    "alpha": Uniform(0.0, 2.0),
}

#: The same for the motion-in likelihood (``motion``), whose discrepancy is a force: tau
#: in N, from far below a load cell's noise to above any test's force. Its alpha is
#: sampled only with ``LikelihoodSettings(decay=True)``; by default it is 0 (white).
#: ``law``, sampled only with ``LikelihoodSettings(law_sampled=True)``: the friction
#: law's deviations' prior sd as a share of the Coulomb forces (``friction_law``),
#: log-uniform from a deviation no record could show to one as large as the Coulomb
#: force itself (**assumption**).
MOTION_DISCREPANCY_PRIORS = {
    "tau": LogUniform(1e-3, 1e5),
    "alpha": Uniform(0.0, 2.0),
    "law": LogUniform(1e-3, 1.0),
}


def tau_floor_prior(floor: float) -> LogUniform:
    """The motion-in discrepancy tau's prior with its floor raised to ``floor`` (N), its
    top the package's: a probe of the likelihood (results/noise-free-tau-floor), passed as
    ``priors={"tau": ...}``; ValueError outside (0, top)."""
    top = MOTION_DISCREPANCY_PRIORS["tau"].high
    if not 0.0 < floor < top:
        raise ValueError(f"tau_floor must lie between 0 and the prior's top ({top:g} N), got {floor}")
    return LogUniform(floor, top)


def delay_prior(sd: float) -> Normal:
    """Prior of ``delay``, the force channel's delay behind the acceleration channel's, s:
    normal about 0 with sd ``sd`` (``LikelihoodSettings.delay_sd``), truncated at 4 sd."""
    return Normal(0.0, sd, width=4.0)


def gain_prior(sd: float) -> LogNormal:
    """Prior of ``gain``, the acceleration channel's gain relative to the force
    channel's: log-normal about 1 with log-sd ``sd`` (``LikelihoodSettings.gain_sd``),
    truncated at 4 sd."""
    return LogNormal(1.0, sd, width=4.0)
