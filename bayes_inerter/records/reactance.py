"""How much of a record's force is inertial: its reactance over its resistance at the drive.

From the record's own channels, on its steady drive periods (``drive.steady_periods``),
the fundamental's complex amplitudes of the acceleration A_1 and the force F_1 by least
squares (an offset, a drift and :data:`drive.HARMONICS` harmonics, as the drive's
estimate fits them), and the driving-point impedance Z_1 = F_1 / V_1 with V_1 = A_1 / (i w):

    M = Im Z_1 / w   (kg, the apparent mass),   C = Re Z_1   (N s/m, the apparent damping),
    ratio = w M / C  (the fundamental's inertial force over its dissipative one).

An inerter's record has a large ratio; a record whose friction outweighs its inertial
force (a small inertance, a slow drive, a large Coulomb force) a ratio below 1. The
ratio is read from the record, not from any fit, so a study may select records by it
without spoiling a simulation-based calibration's ranks, which are uniform given the
record. Where it is small, the posterior is a thin sheet that turns with the friction,
and the default sampler's chains have stopped at their cap (results/capped-by-force-ratio).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from .drive import HARMONICS, harmonic_basis, resolve_drive, steady_periods
from .record import Record

__all__ = ["DriveImpedance", "drive_impedance"]


@dataclass(frozen=True)
class DriveImpedance:
    """A record's driving-point impedance at its drive's fundamental (module docstring):
    the drive frequency ``freq`` (Hz), the apparent ``mass`` (kg) and ``damping`` (N s/m)."""

    freq: float
    mass: float
    damping: float

    @property
    def ratio(self) -> float:
        """The fundamental's inertial force over its dissipative one, w M / C (inf where C
        is not positive)."""
        w = 2.0 * math.pi * self.freq
        return w * self.mass / self.damping if self.damping > 0 else math.inf

    def as_dict(self) -> dict:
        return {**dataclasses.asdict(self), "ratio": self.ratio}


def drive_impedance(record: Record, freq: float | None = None) -> DriveImpedance:
    """The record's :class:`DriveImpedance` at ``freq`` Hz (None: ``drive.resolve_drive``'s).
    ValueError where the record holds fewer than two steady drive periods."""
    hz = resolve_drive(record, freq).hz
    start, count = steady_periods(record, hz)
    n = int(round(record.fs / hz))
    if count < 2:
        raise ValueError(f"the record holds {count} steady drive periods at {hz:g} Hz; the impedance "
                         "at the drive needs at least two")
    part = slice(start, start + count * n)
    t = np.asarray(record.time[part], dtype=float)
    basis = harmonic_basis(t - t[0], hz, HARMONICS)
    channels = np.column_stack([np.asarray(x, dtype=float)[part] for x in (record.accel, record.force)])
    (a_cos, f_cos), (a_sin, f_sin) = np.linalg.lstsq(basis, channels, rcond=None)[0][2:4]
    w = 2.0 * math.pi * hz
    z = (f_cos - 1j * f_sin) / ((a_cos - 1j * a_sin) / (1j * w))  # x = Re(X exp(i w t)), X = cos - i sin
    return DriveImpedance(hz, float(z.imag / w), float(z.real))
