"""The drive frequency of a record, and where it came from.

Precedence, highest first: the caller's option (``--freq``), the record's metadata
(``drive_frequency_hz``), and else an estimate from the record itself
(:func:`estimate_drive_frequency`). :func:`resolve_drive` settles it once, before a fit
samples, and :func:`with_drive` writes it into the record's metadata, so that every
step that needs it (the sampler's coordinates, the physical-sense checks, the
discrepancy and the interval) reads the same number; ``fit`` prints it with its source
and fit.json keeps both.

The estimate (an **assumption** of this package: the drive is one steady sinusoid):
the spectral peak of the most sinusoidal channel, then, on the record's steady part
(the drive periods whose amplitude is within :data:`STEADY_SHARE` of the typical one,
so that a ramp-in or ramp-out does not pull it), the frequency whose first
:data:`HARMONICS` harmonics, with an offset and a drift, explain most of the channel
by least squares. On the project's generated records (10 s with a 2 s ramp) it is
within 1e-5 of the drive at 0.5, 1 and 1.5 Hz (tests/test_records_drive.py), where the
spectral peak alone is off by up to 0.8 %.

Its :attr:`DriveFrequency.resolution_hz` is the spectrum's: half a bin of the steady
part, 1 / (2 T). Two frequencies closer than that are one drive to this record; a
checkpoint written at one is continued at the other (``inference.sampling.coordinates``).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from .record import Record

__all__ = ["DriveFrequency", "estimate_drive_frequency", "resolve_drive", "with_drive", "spectral_peak", "HARMONICS",
           "STEADY_SHARE", "SOURCE_KEY", "steady_periods", "harmonic_basis"]

#: Harmonics of the drive in the refining least squares (each channel of a device with
#: friction carries odd harmonics; the fit must not take them for a shifted fundamental).
HARMONICS = 9
#: A drive period belongs to the steady part when its amplitude is at least this share
#: of the median period's.
STEADY_SHARE = 0.97
#: The metadata key that names where the drive frequency came from.
SOURCE_KEY = "drive_frequency_source"


@dataclass(frozen=True)
class DriveFrequency:
    """A record's drive frequency ``hz``, a few words on its ``source``, and the
    resolution of the record's spectrum, ``resolution_hz`` (1 / (2 T))."""

    hz: float
    source: str
    resolution_hz: float

    def describe(self) -> str:
        return f"{self.hz:.6g} Hz ({self.source})"

    def as_dict(self) -> dict:
        return dataclasses.asdict(self)


def spectral_peak(time, x) -> tuple[float, float]:
    """(frequency of x's largest spectral peak, Hz, its share of x's power, with the bins
    on either side)."""
    x = np.asarray(x, dtype=float) - np.mean(x)
    spec = np.abs(np.fft.rfft(x)) ** 2
    spec[0] = 0.0
    total = spec.sum()
    k = int(np.argmax(spec))
    fs = (len(time) - 1) / (time[-1] - time[0])
    return k * fs / len(x), (spec[max(k - 1, 0): k + 2].sum() / total if total > 0 else 0.0)


def harmonic_basis(t: np.ndarray, freq: float, harmonics: int) -> np.ndarray:
    """The least-squares basis of a drive at ``freq`` Hz over times ``t``: an offset, a
    drift, then the cosine and sine of each of the first ``harmonics`` harmonics."""
    w = 2.0 * math.pi * freq * t
    cols = [np.ones_like(t), t]
    for k in range(1, harmonics + 1):
        cols += [np.cos(k * w), np.sin(k * w)]
    return np.column_stack(cols)


def _explained(t: np.ndarray, x: np.ndarray, freq: float, harmonics: int) -> float:
    """The squared norm of ``x``'s least-squares fit by ``harmonic_basis``."""
    coef, *_ = np.linalg.lstsq(harmonic_basis(t, freq, harmonics), x, rcond=None)
    return float(np.sum((harmonic_basis(t, freq, harmonics) @ coef) ** 2))


def _steady(time: np.ndarray, x: np.ndarray, freq: float) -> slice:
    """The longest run of whole drive periods whose amplitude (the period's rms about its
    mean) is at least :data:`STEADY_SHARE` of the median period's; the whole record when
    it holds fewer than three periods."""
    fs = (len(time) - 1) / (time[-1] - time[0])
    n = int(round(fs / freq))
    periods = len(x) // n if n > 0 else 0
    if periods < 3:
        return slice(0, len(x))
    amp = np.array([np.std(x[i * n:(i + 1) * n]) for i in range(periods)])
    ok = amp >= STEADY_SHARE * np.median(amp)
    best, run_start, best_span = (0, 0), None, 0
    for i, good in enumerate(list(ok) + [False]):
        if good and run_start is None:
            run_start = i
        elif not good and run_start is not None:
            if i - run_start > best_span:
                best, best_span = (run_start, i), i - run_start
            run_start = None
    return slice(best[0] * n, best[1] * n)


def steady_periods(record: Record, freq: float) -> tuple[int, int]:
    """(first sample, number) of the record's steady drive periods at ``freq`` Hz: the
    longest run of whole periods whose amplitude is within :data:`STEADY_SHARE` of the
    typical one (a ramp-in or ramp-out left out), read from the displacement channel
    where there is one, else the acceleration."""
    x = np.asarray(record.disp if record.disp is not None else record.accel, dtype=float)
    part = _steady(record.time, x, freq)
    n = int(round(record.fs / freq))
    return int(part.start), int((part.stop - part.start) // n) if n > 0 else 0


def estimate_drive_frequency(record: Record) -> DriveFrequency:
    """The drive frequency estimated from the record alone (see the module docstring)."""
    channels = [x for x in (record.disp, record.accel, record.force) if x is not None]
    peaks = [spectral_peak(record.time, x) for x in channels]
    j = int(np.argmax([share for _, share in peaks]))
    f0, x = peaks[j][0], np.asarray(channels[j], dtype=float)
    if not f0 > 0:
        raise ValueError("the record's drive frequency cannot be estimated (its spectrum has no peak above "
                         "zero frequency); give it with --freq or drive_frequency_hz in the metadata")
    part = _steady(record.time, x, f0)
    t = np.asarray(record.time[part], dtype=float)
    t = t - t.mean()
    y = x[part] - np.mean(x[part])
    span = float(t[-1] - t[0])
    fs = record.fs
    harmonics = max(1, min(HARMONICS, int(0.45 * fs / f0)))
    from scipy.optimize import minimize_scalar

    # the spectral peak is within half a bin of the steady part's, 1 / (2 span), of the drive
    half = 1.0 / (2.0 * span)
    grid = np.linspace(max(f0 - half, half / 10), f0 + half, 11)
    k = int(np.argmax([_explained(t, y, f, harmonics) for f in grid]))
    lo, hi = grid[max(k - 1, 0)], grid[min(k + 1, len(grid) - 1)]
    found = minimize_scalar(lambda f: -_explained(t, y, f, harmonics), bounds=(lo, hi), method="bounded",
                            options={"xatol": 1e-9 * f0})
    return DriveFrequency(float(found.x), "estimated from the record's spectrum", 1.0 / (2.0 * record.duration))


def resolve_drive(record: Record, freq: float | None = None) -> DriveFrequency:
    """The drive frequency for ``record``: ``freq`` (the option), else the metadata's,
    else :func:`estimate_drive_frequency`. ValueError for a ``freq`` that is not a
    positive number, or a record whose frequency cannot be estimated."""
    resolution = 1.0 / (2.0 * record.duration)
    if freq is not None:
        if isinstance(freq, bool) or not isinstance(freq, (int, float)) or not math.isfinite(freq) or freq <= 0:
            raise ValueError(f"the drive frequency must be a positive number of Hz, got {freq!r}")
        return DriveFrequency(float(freq), "option --freq", resolution)
    if record.drive_frequency is not None:
        source = record.metadata.get(SOURCE_KEY) or "record metadata drive_frequency_hz"
        return DriveFrequency(record.drive_frequency, str(source), resolution)
    return estimate_drive_frequency(record)


def with_drive(record: Record, drive: DriveFrequency) -> Record:
    """``record`` with ``drive`` in its metadata (``drive_frequency_hz`` and where it came
    from, :data:`SOURCE_KEY`); the record itself when it already says the same."""
    meta = record.metadata
    if meta.get("drive_frequency_hz") == drive.hz and (SOURCE_KEY in meta or drive.source.startswith("record metadata")):
        return record
    return dataclasses.replace(record, metadata={**meta, "drive_frequency_hz": drive.hz, SOURCE_KEY: drive.source})
