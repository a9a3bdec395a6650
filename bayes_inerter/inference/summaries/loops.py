"""Force-displacement and force-velocity loops over one steady drive period.

Damper and inerter tests are read first as loops: the force against the displacement (its
area the energy a cycle dissipates, its tilt the stiffness, its bulge the inertial
force) and against the velocity (its Coulomb step at zero velocity, its slope the
damping, its opening the inertia). :func:`period_loops` gives them for one record of the
motion-in likelihood (``LikelihoodSettings(residual="motion")``, the default) from what
that likelihood compares, the drive's harmonics 1..K averaged over the record's steady
periods:

- measured: the displacement and velocity of terminal 1 from the measured acceleration's
  harmonics, X_k = A_k / (i w_k)^2 and V_k = A_k / (i w_k), and the measured force's F_k;
- predicted: the model's force F^_k(theta) given that measured motion
  (``motion.predicted_force``, with each draw's sensor gain and channel delay), for
  posterior draws theta.

Each is summed back to a period, x(t) = Re sum_k X_k exp(i w_k t). The force's mean (its
zeroth harmonic, a static offset the model does not make) is left out of both. The
predicted force is the **model's** force alone: the deviations the likelihood
marginalises at the reversals and for the friction law's shape (``reversals``,
``friction_law``) are not in it, so a loop shows what the physical model explains and
where it does not. Both curves hold only the harmonics the likelihood compares (up to its
cutoff, 30 Hz by default): the model's Coulomb switch is a step, and its truncated
harmonics ripple after each reversal (Gibbs), where a real contact's smoother switch
rings less.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ...simulate import SimulationError
from ..posterior.harmonic import at_times
from ..posterior.motion import predicted_force

__all__ = ["PeriodLoops", "period_loops", "POINTS"]

#: Points on the period the loops are drawn at.
POINTS = 400


@dataclass(frozen=True)
class PeriodLoops:
    """One record's loops over a steady period (SI units; see the module docstring).

    Attributes
    ----------
    time : (n,) s from the period's start.
    displacement, velocity : (n,) terminal 1's, m and m/s, from the measured acceleration.
    measured : (n,) the measured force, N.
    predicted : (draws, n) the model's force at each posterior draw, N (draws whose
        drivetrain simulation failed are left out).
    """

    time: np.ndarray
    displacement: np.ndarray
    velocity: np.ndarray
    measured: np.ndarray
    predicted: np.ndarray

    def band(self, level: float = 0.94) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(low, median, high) of the predicted force at each point: the central
        ``level`` credible band and the median over the draws."""
        if not 0.0 < level < 1.0:
            raise ValueError(f"a credible level must lie in (0, 1), got {level}")
        lo, mid, hi = np.percentile(self.predicted, [50 * (1 - level), 50, 50 * (1 + level)], axis=0)
        return lo, mid, hi


def period_loops(model, thetas, *, points: int = POINTS) -> PeriodLoops:
    """The loops of ``model`` (a ``PosteriorModel`` of the motion-in likelihood) at the
    posterior draws ``thetas`` (draws x ndim, the model's sampled coordinates).

    ValueError where the model is not the motion-in likelihood's (the time-domain ones
    take the force as an input and predict no force), or where no draw gives a force."""
    data = model.motion
    if data is None:
        raise ValueError("force loops need the motion-in likelihood (LikelihoodSettings(residual='motion')); "
                         f"this model's is {model.likelihood.residual!r}")
    if points < 8:
        raise ValueError(f"a loop needs at least 8 points, got {points}")
    omega = data.omega
    t = np.arange(points) / points * (2.0 * np.pi / omega[0])
    predicted = []
    for theta in np.atleast_2d(np.asarray(thetas, dtype=float)):
        h = model.hyper(theta)
        try:
            F, _ = predicted_force(data, model.field_vector(theta), h["gain"], h["delay"], model.effects(theta))
        except (SimulationError, ValueError):
            continue
        if np.all(np.isfinite(F)):
            predicted.append(at_times(F, omega, t))
    if not predicted:
        raise ValueError("no posterior draw gave a predicted force")
    return PeriodLoops(t, at_times(data.velocity / (1j * omega), omega, t), at_times(data.velocity, omega, t),
                       at_times(data.harmonic.force, omega, t), np.array(predicted))
