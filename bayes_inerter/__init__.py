"""bayes-inerter: Bayesian uncertainty quantification of a ball-screw inerter.

Public names are listed here explicitly; see the README for the API.
"""

from .device import (
    FREQUENCIES_HZ,
    SETTINGS,
    TABLE_I,
    FlywheelSetting,
    Geometry,
    InerterParameters,
    paper_parameters,
    setting,
    theoretical_inertance,
)
from .friction import Coulomb, PiecewiseLinear, Smooth, Stribeck, make_law
from .networks import NETWORKS, build_network
from .simulate import SimulationError, simulate, simulate_network

__version__ = "0.1.0"

__all__ = [
    "FREQUENCIES_HZ",
    "SETTINGS",
    "TABLE_I",
    "FlywheelSetting",
    "Geometry",
    "InerterParameters",
    "paper_parameters",
    "setting",
    "theoretical_inertance",
    "Coulomb",
    "PiecewiseLinear",
    "Smooth",
    "Stribeck",
    "make_law",
    "NETWORKS",
    "build_network",
    "SimulationError",
    "simulate",
    "simulate_network",
]
