"""The device: flywheel settings, the paper's parameters, the theoretical inertance.

Everything here is data from Lin et al. (Table I, Table 2 and the text) or derived from it
in code. SI units throughout (kg, m, s, N).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

__all__ = [
    "InerterParameters",
    "FlywheelSetting",
    "Geometry",
    "SETTINGS",
    "TABLE_I",
    "FREQUENCIES_HZ",
    "setting",
    "setting_and_frequency",
    "grid_case",
    "paper_parameters",
    "theoretical_inertance",
    "apparent_inertance",
    "validate_parameters",
]

#: Drive frequencies of the paper's experiments, Hz.
FREQUENCIES_HZ = (0.5, 1.0, 1.5)

#: Table I of the paper: one parameter set for every flywheel setting (SI units).
TABLE_I = {
    "c_n": 2_165_100.0,  # N s/m, nut deformation damping (includes cos^2 theta, assumption)
    "k_n": 434_960.0,  # N/m, nut deformation stiffness
    "c_B": 1.0026,  # N s/m, bearing deformation damping
    "k_B": 64_015_000.0,  # N/m, bearing deformation stiffness
    "f1_0": 731.66,  # N, plate Coulomb friction
    "c_f1": 0.027520,  # N s/m, plate viscous friction
    "f2_0": 2.7780,  # N, rotational Coulomb friction (bearing + nut, axial part)
    "c_f2": 1574.7,  # N s/m, rotational viscous friction
    "m_B": 57.200,  # kg, plate + bearing + two ball-spline nuts
}

SMALL_FLYWHEEL = {"mass": 2.09418, "diameter": 0.19, "thickness": 0.009}  # kg, m, m
BIG_FLYWHEEL = {"mass": 7.41836, "diameter": 0.35, "thickness": 0.009}  # kg, m, m
SCREW_MASS = 15.406  # kg

#: The paper's theoretical inertance of the lightest and heaviest settings (text, Sec. III).
PAPER_THEORY_A0 = 474.7  # kg
PAPER_THEORY_B2 = 23261.4  # kg


@dataclass(frozen=True)
class InerterParameters:
    """Parameters of the reduced two-port network (SI units).

    Attributes
    ----------
    b : inertance, kg.
    m_s : screw translation mass (screw + flywheels), kg.
    m_B : plate mass (plate + bearing + spline nuts), kg.
    c_n, k_n : nut deformation damping (N s/m) and stiffness (N/m).
    c_B, k_B : bearing deformation damping (N s/m) and stiffness (N/m).
    f1_0, c_f1 : plate Coulomb (N) and viscous (N s/m) friction.
    f2_0, c_f2 : rotational Coulomb (N) and viscous (N s/m) friction, on the linear
        coordinate x_th = p theta / (2 pi).
    """

    b: float
    m_s: float
    m_B: float
    c_n: float
    k_n: float
    c_B: float
    k_B: float
    f1_0: float
    c_f1: float
    f2_0: float
    c_f2: float

    def __post_init__(self) -> None:
        validate_parameters(self)

    def as_dict(self) -> dict[str, float]:
        return dataclasses.asdict(self)


_POSITIVE = ("b", "m_s", "m_B")
_NON_NEGATIVE = ("c_n", "k_n", "c_B", "k_B", "f1_0", "c_f1", "f2_0", "c_f2")


def validate_parameters(params: InerterParameters) -> None:
    """Raise ValueError naming the first parameter that is not finite or out of range."""
    for name in _POSITIVE + _NON_NEGATIVE:
        value = getattr(params, name)
        try:
            value = float(value)
        except (TypeError, ValueError):
            raise ValueError(f"parameter {name} must be a number, got {value!r}") from None
        if not math.isfinite(value):
            raise ValueError(f"parameter {name} must be finite, got {value}")
        if name in _POSITIVE and value <= 0:
            raise ValueError(f"parameter {name} must be positive, got {value}")
        if name in _NON_NEGATIVE and value < 0:
            raise ValueError(f"parameter {name} must be non-negative, got {value}")


@dataclass(frozen=True)
class FlywheelSetting:
    """One flywheel setting of Table 2."""

    name: str
    n_small: int
    n_big: int
    m_s: float  # kg, Table 2
    b_paper: float  # kg, identified inertance, Table 2
    fit_paper: dict  # drive frequency (Hz) -> fit accuracy phi (fraction), Table 2


def _table2() -> dict[str, FlywheelSetting]:
    names = ("A0", "A1", "A2", "A3", "A4", "A5", "A6", "B1", "B2")
    n_small = (0, 1, 2, 3, 4, 5, 6, 0, 0)
    n_big = (0, 0, 0, 0, 0, 0, 0, 1, 2)
    m_s = (15.406, 17.500, 19.594, 21.688, 23.782, 25.877, 27.971, 22.8, 30.2)
    b = (753.34, 1668.9, 2619.6, 3531.6, 4493.1, 5461.5, 6404.6, 10468.0, 20287.0)
    fit = {
        0.5: (6.6, 58.7, 66.4, 66.9, 69.7, 64.4, 68.3, 69.4, 68.2),
        1.0: (52.3, 77.4, 82.9, 83.9, 85.8, 82.3, 81.8, 82.7, 77.6),
        1.5: (74.3, 88.6, 90.3, 89.2, 89.2, 88.8, 88.0, 85.8, 84.5),
    }
    return {
        name: FlywheelSetting(
            name, n_small[i], n_big[i], m_s[i], b[i], {f: fit[f][i] / 100 for f in fit}
        )
        for i, name in enumerate(names)
    }


#: The nine flywheel settings A0..A6, B1, B2 (Table 2), by name.
SETTINGS: dict[str, FlywheelSetting] = _table2()


def setting(name: str) -> FlywheelSetting:
    """The flywheel setting called ``name`` (A0..A6, B1, B2); ValueError if unknown."""
    try:
        return SETTINGS[str(name).upper()]
    except KeyError:
        known = ", ".join(SETTINGS)
        raise ValueError(f"unknown flywheel setting {name!r}; known settings: {known}") from None


def setting_and_frequency(text: str) -> tuple[str, float]:
    """(setting, drive frequency in Hz) from ``SETTING:FREQUENCY`` ("A3:1"), the form the
    studies' and benchmarks' ``--record`` take (an argparse ``type``: its ValueError is
    a usage error there). The setting is upper-cased, not looked up."""
    try:
        name, freq = text.split(":")
        value = float(freq)
    except ValueError:
        raise ValueError(f"expected SETTING:FREQUENCY such as A3:1, got {text!r}") from None
    if not name or not value > 0:
        raise ValueError(f"expected SETTING:FREQUENCY with a positive frequency in Hz, got {text!r}")
    return name.upper(), value


def grid_case(k: int) -> tuple[str, float]:
    """The k-th record of the paper's grid in the coverage studies' order: setting
    ``SETTINGS[k % 9]`` at ``FREQUENCIES_HZ[(k + k // 9) % 3]``, so that every 27 hold
    each setting at each frequency once, the frequencies interleaved."""
    names = list(SETTINGS)
    return names[k % len(names)], FREQUENCIES_HZ[(k + k // len(names)) % len(FREQUENCIES_HZ)]


def _disc_inertia(mass: float, diameter: float) -> float:
    """Moment of inertia of a solid disc about its axis, kg m^2."""
    return 0.5 * mass * (diameter / 2) ** 2


@dataclass(frozen=True)
class Geometry:
    """Rotating parts of the inerter: b = (J_screw + sum of flywheel J) (2 pi / lead)^2.

    Attributes
    ----------
    lead : screw lead p, m per revolution.
    J_screw : moment of inertia of the bare screw (and anything turning with it), kg m^2.
    J_small, J_big : moment of inertia of one small / big flywheel, kg m^2.
    """

    lead: float
    J_screw: float
    J_small: float = _disc_inertia(SMALL_FLYWHEEL["mass"], SMALL_FLYWHEEL["diameter"])
    J_big: float = _disc_inertia(BIG_FLYWHEEL["mass"], BIG_FLYWHEEL["diameter"])

    @property
    def gain(self) -> float:
        """(2 pi / lead)^2, 1/m^2: inertance per unit moment of inertia."""
        return (2 * math.pi / self.lead) ** 2

    def inertance(self, n_small: int, n_big: int) -> float:
        """Theoretical inertance with ``n_small`` small and ``n_big`` big flywheels, kg."""
        J = self.J_screw + n_small * self.J_small + n_big * self.J_big
        return J * self.gain

    @classmethod
    def from_paper(cls) -> Geometry:
        """The geometry implied by the paper's two theoretical figures.

        **Assumption**: the paper gives neither the lead nor the screw's own inertia, only
        b = 474.7 kg (A0, bare screw) and 23261.4 kg (B2, two big flywheels). With
        solid-disc flywheels, these two numbers fix both: (2 pi / p)^2 from the B2 - A0
        difference (two big flywheels), then J_screw from A0. The result (p = 19.84 mm,
        J_screw of a solid 15.4 kg screw of radius 24.8 mm) is physically plausible,
        which is the check that the reading is right.
        """
        J_big = _disc_inertia(BIG_FLYWHEEL["mass"], BIG_FLYWHEEL["diameter"])
        gain = (PAPER_THEORY_B2 - PAPER_THEORY_A0) / (2 * J_big)
        lead = 2 * math.pi / math.sqrt(gain)
        return cls(lead=lead, J_screw=PAPER_THEORY_A0 / gain)

    def screw_radius(self, screw_mass: float = SCREW_MASS) -> float:
        """Radius of a solid cylinder of ``screw_mass`` with inertia J_screw, m."""
        return math.sqrt(2 * self.J_screw / screw_mass)


DEFAULT_GEOMETRY = Geometry.from_paper()


def theoretical_inertance(name: str, geometry: Geometry | None = None) -> float:
    """Theoretical inertance of a flywheel setting from the geometry, kg."""
    s = setting(name)
    return (geometry or DEFAULT_GEOMETRY).inertance(s.n_small, s.n_big)


def paper_parameters(name: str) -> InerterParameters:
    """The paper's parameters for a flywheel setting: Table I, and Table 2's b and m_s."""
    s = setting(name)
    return InerterParameters(b=s.b_paper, m_s=s.m_s, **TABLE_I)


def apparent_inertance(b, k_n, c_n):
    """The inertance the drive sees through the nut, kg: b (1 + b k_n / c_n^2).

    The nut's deformation (c_n + k_n / s) sits in series with the inertance b s, so the
    admittance of the pair is 1 / (c_n + k_n / s) + 1 / (b s). Where the nut's spring is
    small beside its damper at the drive frequency (k_n / (omega c_n) << 1; 0.03 at
    1 Hz for Table I's values) this is 1 / c_n + (1 / s)(1 / b - k_n / c_n^2): a damper
    in series with an inerter of 1 / (1 / b - k_n / c_n^2), to first order
    b (1 + b k_n / c_n^2), the same at every drive frequency. Records therefore fix this
    combination more tightly than b: a stiffer nut with a smaller b looks the same
    (measured: the full study's joint model, ``README``). Works on arrays.
    """
    return b * (1.0 + b * k_n / (c_n * c_n))
