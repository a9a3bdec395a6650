"""b with a model-form error: the device's inertance as the fitted model's times e^eps.

A richer device's b differs from the two-port model's effective one by a factor that no
record of it shows (docs/inference.md, "The richer device puts b low"). Where the
likelihood marginalises that error (``LikelihoodSettings.form_sd``, ``form_friction``) it
also changes which features of the record pin b, and on paper-like records it moved b's
centre where the friction dwarfs the inertia. Here the error enters after the likelihood
instead: eps is a parameter the records do not inform, normal about 0 with sd

    sqrt(sd^2 + (friction f_0 / (b A_1))^2)

(``sd`` a relative error of b, ``friction`` a share of the Coulomb forces f_0 = f1_0 + f2_0
over the inertial force b A_1 at the fundamental, A_1 the measured acceleration's
amplitude there), so the posterior of the device's b is each draw of the model's b times
e^eps, eps drawn from that law: an exact draw of the posterior of the model with eps
added, whose centre stays where the record puts b. **Assumption** (a candidate, not the
default): the sizes are the stand-in's choice on the even paper-like replicates
(results/form-sd-standin).
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

import numpy as np

from ...records.checks import fundamental
from ...records.drive import resolve_drive, steady_periods
from ...records.record import Record

__all__ = ["ModelFormError", "accel_amplitude"]


@dataclass(frozen=True)
class ModelFormError:
    """The model-form error of b: a relative sd ``sd`` and a share ``friction`` of the
    Coulomb forces at the fundamental (module docstring)."""

    sd: float = 0.0025
    friction: float = 0.005

    def __post_init__(self) -> None:
        for name in ("sd", "friction"):
            value = getattr(self, name)
            if not (isinstance(value, numbers.Real) and not isinstance(value, bool) and 0 <= value < 1):
                raise ValueError(f"the model-form error's {name} must be a share in [0, 1), such as 0.005, "
                                 f"got {value!r}")

    def relative_sd(self, b, f_0, accel_amplitude: float) -> np.ndarray:
        """The sd of eps at each draw of b (kg) and f_0 (N), for the measured
        acceleration's amplitude at the fundamental (m/s^2)."""
        if not accel_amplitude > 0:
            raise ValueError(f"the acceleration's amplitude at the drive must be positive, got {accel_amplitude!r}")
        b, f_0 = np.asarray(b, dtype=float), np.asarray(f_0, dtype=float)
        return np.hypot(self.sd, self.friction * f_0 / (b * accel_amplitude))

    def draws(self, b, f_0, accel_amplitude: float, rng: np.random.Generator) -> np.ndarray:
        """The device's b at each posterior draw: b e^eps, eps drawn from its law."""
        b = np.asarray(b, dtype=float)
        return b * np.exp(self.relative_sd(b, f_0, accel_amplitude) * rng.standard_normal(b.shape))


def accel_amplitude(record: Record, freq: float | None = None) -> float:
    """The measured acceleration's amplitude at the drive frequency (m/s^2), over the
    record's steady periods (``drive.steady_periods``; None: the drive ``resolve_drive``
    finds)."""
    hz = resolve_drive(record, freq).hz
    start, count = steady_periods(record, hz)
    n = int(round(record.fs / hz))
    part = slice(start, start + max(count, 1) * n)
    return abs(fundamental(np.asarray(record.time)[part], np.asarray(record.accel)[part], hz))
