"""A record: uniformly sampled force, acceleration (and displacement) with metadata."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

__all__ = ["Record"]


@dataclass(frozen=True, eq=False)
class Record:
    """One experiment's record (SI units).

    Attributes
    ----------
    time : shape (K,), s, uniformly sampled.
    force : shape (K,), N, on terminal 1 (load cell).
    accel : shape (K,), m/s^2, of terminal 1 (accelerometer).
    disp : shape (K,), m, or None.
    metadata : setting or m_s, m_B, drive frequency, sampling rate; for generated
        records the true parameters and every generator setting.
    """

    time: np.ndarray
    force: np.ndarray
    accel: np.ndarray
    disp: np.ndarray | None = None
    metadata: dict = field(default_factory=dict)

    @property
    def fs(self) -> float:
        """Sampling rate, Hz."""
        return (len(self.time) - 1) / (self.time[-1] - self.time[0])

    @property
    def duration(self) -> float:
        return float(self.time[-1] - self.time[0])

    @property
    def drive_frequency(self) -> float | None:
        f = self.metadata.get("drive_frequency_hz")
        return None if f is None else float(f)
