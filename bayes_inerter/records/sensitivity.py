"""The sensors' calibration: what an inertance identified from a record cannot know.

A load cell and an accelerometer are known to their calibration certificates' accuracy,
not exactly. If the force channel reads ``g_F`` times the force and the accelerometer
``g_a`` times the acceleration, the records are reproduced exactly by a device whose
masses, inertance, viscous coefficients, stiffnesses and dampings are ``s = g_F / g_a``
times the true ones and whose Coulomb forces are ``g_F`` times the true ones: its
displacement is then ``g_a`` times the true one, each term of the equations of motion
``g_F`` times its true value (the Coulomb force's sign follows the velocity, which keeps
its sign). The likelihood, which compares the acceleration simulated from the recorded force with
the recorded one, therefore cannot tell ``s`` from 1. The likelihood holds the masses
m_s and m_B at their known values, so the identified inertance absorbs the rest: in the
rigid-body limit ``m + b_id = s (m + b)``, with ``m = m_s + m_B`` the moving mass, and

    b = r (b_id + m) - m,    r = g_a / g_F = 1 / s.

**Assumption** (the paper states no sensor calibration): the two sensitivities are
independent, each with a relative standard uncertainty (:class:`SensorCalibration`;
defaults 0.25 % for the load cell and 0.5 % for the accelerometer, typical of
laboratory calibration certificates, not values any record can check). To first order
``r`` is then normal about 1 with sd ``u = hypot(u_F, u_a)`` and, for a posterior of
b_id with mean ``mu`` and sd ``sd``,

    sd_total^2 = sd^2 + ((mu + m) u)^2

(the GUM's law of propagation: the posterior's sd with a type-B share). The
calibration's share is common to every setting of one study (one pair of sensors); a
difference of two settings' inertances (an increment per flywheel) carries ``u`` times
the difference of ``b + m``: the moving mass differs between settings where m_s holds
the flywheels.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

__all__ = ["SensorCalibration"]


@dataclass(frozen=True)
class SensorCalibration:
    """Relative standard uncertainties of the sensors' sensitivities (see module docstring).

    Attributes
    ----------
    force : load cell, as a fraction (default 0.0025: 0.25 %).
    accel : accelerometer, as a fraction (default 0.005: 0.5 %).

    ``SensorCalibration(0, 0)`` takes the records' sensitivities as exact.
    """

    force: float = 0.0025
    accel: float = 0.005

    def __post_init__(self) -> None:
        for name in ("force", "accel"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and 0 <= value < 0.5):
                raise ValueError(f"the {name} sensor's sensitivity uncertainty must be a fraction from 0 to below 0.5 "
                                 f"(50 %), got {value!r}")

    @property
    def ratio_sd(self) -> float:
        """Relative sd of the ratio of the two sensitivities."""
        return math.hypot(self.force, self.accel)

    def inertance_sd(self, mean: float, sd: float, moving_mass: float = 0.0) -> float:
        """The sd of an inertance identified with posterior ``mean`` and ``sd`` (kg), the
        calibration's share added: sqrt(sd^2 + ((mean + moving_mass) u)^2). For a
        difference of inertances, the difference of the moving masses. A nan in (an
        unknown sd or mass) gives nan out."""
        if sd < 0:
            raise ValueError(f"sd must be non-negative, got {sd!r}")
        return math.hypot(sd, abs(mean + moving_mass) * self.ratio_sd)

    def as_dict(self) -> dict:
        return {"force": self.force, "accel": self.accel}
