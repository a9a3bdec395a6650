"""Physical-sense checks of a record, before any sampling.

A file can be a valid table and still not be what it claims: columns swapped, a force
in kN or an acceleration in g read as SI, a dead or clipped channel. Such a record
samples to a wrong answer (or fails far from the cause). Each check here compares the
record with what any device the fit could describe would give, at the drive frequency,
and names the likely cause and the fix in one line:

- ``time-unit``: a sampling rate below :data:`MIN_RATE_HZ`, or a drive frequency
  1000 times below the metadata's: a time column in ms read as seconds.
- ``flat``: a channel that is constant, or carries almost nothing at the drive
  frequency (its fundamental's amplitude below :data:`MIN_DRIVE_SHARE` of its spread,
  the interquartile range over 1.349, which a few spikes do not move): a dead channel
  or the wrong column.
- ``clipped``: a channel that sits at its largest or smallest value for at least
  :data:`CLIP_SHARE` of the samples, :data:`CLIP_PILE` times as many as at the
  quantisation level beside it: clipped at a sensor's or the DAQ's range.
- ``accel-vs-disp`` (where the displacement is given): the acceleration's fundamental
  against the second derivative of the displacement's, ``-omega^2 d``: the amplitude
  ratio must lie within :data:`ACCEL_DISP_RATIO` and the phase within
  :data:`ACCEL_DISP_PHASE_DEG`.
- ``apparent-mass``: the in-phase (inertial) part of F / a at the drive frequency, M
  (kg), must be one that a device within the priors gives:
  ``m_B + (m_s + b_lo) / 2 <= M <= m_B + 3 (m_s + b_hi) / 2``. **Assumption** (the
  impedance coordinates' domain, :mod:`..inference.sampling.coordinates`): the nut and bearing
  pass the inertance on to the drive within a factor 1/2 to 3/2. Coulomb friction's
  fundamental is in phase with the velocity, so it does not enter M. Where b is
  expected (the record names one of the paper's settings, or a device file gives a
  geometry), [b_lo, b_hi] is within :data:`EXPECTED_B_FACTOR` of it (:func:`b_range_for`);
  else the default prior's.

Where a check fails, candidate causes (a unit, a swap, a sign) are tried in turn and the
ones that make the record pass are named. An acceleration in g without a displacement
column passes when 9.81 M still lies in the range: no check can see it then.

Every threshold is a module constant, an assumption of these checks; a user who knows
the record is right skips a check by name (``--skip-check NAME``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .drive import resolve_drive, spectral_peak
from .io import RecordError
from .record import Record
from .units import UNITS

__all__ = ["CHECKS", "Finding", "RecordCheckError", "check_record", "require_physical", "fundamental",
           "drive_frequency", "MIN_RATE_HZ", "MIN_DRIVE_SHARE", "CLIP_SHARE", "CLIP_PILE", "ACCEL_DISP_RATIO",
           "ACCEL_DISP_PHASE_DEG", "B_RANGE", "DISP_RANGE", "EXPECTED_B_FACTOR", "b_range_for"]

#: The checks, in the order they run (each named for ``skip``).
CHECKS = ("time-unit", "flat", "clipped", "accel-vs-disp", "apparent-mass")

#: Slowest sampling rate taken as given, Hz (a 1 kHz record timed in ms reads as 1 Hz).
MIN_RATE_HZ = 50.0
#: Smallest amplitude of a channel's drive-frequency component, as a share of its spread.
MIN_DRIVE_SHARE = 0.1
#: Largest share of samples a channel may spend at its extreme value ...
CLIP_SHARE = 0.002
#: ... unless the level beside it holds at least this fraction as many (a quantised but
#: unclipped peak).
CLIP_PILE = 4
#: Accepted range of |a| / |omega^2 d| at the drive frequency.
ACCEL_DISP_RATIO = (0.5, 2.0)
#: Accepted phase between a and -omega^2 d, degrees.
ACCEL_DISP_PHASE_DEG = 30.0
#: The default prior's bounds on b, kg (``inference.posterior.priors.DEFAULT_PRIORS["b"]``; a test
#: keeps them equal, without the records importing the inference package).
B_RANGE = (100.0, 1e5)
#: Where the inertance is expected (the paper's Table 2 for a record that names one of
#: its settings, or a device file's geometry), b is looked for within this factor of
#: it, inside :data:`B_RANGE`: the paper's identified b lies within 1.6 of its theory.
EXPECTED_B_FACTOR = 2.0
#: Plausible displacement amplitudes of a test rig, m, used to tell an acceleration's
#: unit from a force's when only their ratio is wrong.
DISP_RANGE = (1e-5, 0.5)


@dataclass(frozen=True)
class Finding:
    """One failed check: its name (one of :data:`CHECKS`) and a one-line message that
    names the likely cause and the fix."""

    check: str
    message: str


class RecordCheckError(RecordError):
    """A record that fails a physical-sense check (``finding`` says which)."""

    def __init__(self, finding: Finding):
        super().__init__(finding.message)
        self.finding = finding


def fundamental(time, x, freq: float) -> complex:
    """The phasor X of ``x``'s component at ``freq`` (Hz): x ~ Re(X exp(i omega t)) plus
    an offset and a drift, by least squares over the whole record."""
    t = np.asarray(time, dtype=float) - float(np.mean(time))
    w = 2 * math.pi * freq
    basis = np.column_stack([np.cos(w * t), np.sin(w * t), np.ones_like(t), t])
    coef, *_ = np.linalg.lstsq(basis, np.asarray(x, dtype=float), rcond=None)
    return complex(coef[0], -coef[1])


def drive_frequency(record: Record) -> float:
    """The drive frequency, Hz: the metadata's, or else the record's own estimate
    (:func:`.drive.resolve_drive`, the one every step of a fit uses)."""
    return resolve_drive(record).hz


def _rms(x) -> float:
    return float(np.std(x))


def _channels(record: Record):
    yield "force", record.force, "N"
    yield "accel", record.accel, "m/s^2"
    if record.disp is not None:
        yield "disp", record.disp, "m"


_NAMES = {"force": "force", "accel": "acceleration", "disp": "displacement"}


def _time_unit(record: Record, freq: float):
    fs = record.fs
    meta_f = record.drive_frequency
    if fs < MIN_RATE_HZ:
        return (f"the record is sampled at {fs:.3g} Hz, below {MIN_RATE_HZ:g} Hz: a time column in ms "
                "reads 1000 times too slow; give --units time=ms (or check the time column)")
    if meta_f is not None:
        seen = spectral_peak(record.time, record.accel)[0]
        if seen > 0 and abs(seen * 1000 / meta_f - 1) < 0.1:
            return (f"the acceleration peaks at {seen:.3g} Hz but the metadata's drive frequency is "
                    f"{meta_f:g} Hz: a time column in ms? give --units time=ms")
    return None


def _flat(record: Record, freq: float):
    for name, x, unit in _channels(record):
        rms = _rms(x)
        if rms == 0 or rms <= 1e-12 * float(np.max(np.abs(x))):
            return (f"the {_NAMES[name]} column is constant ({float(x[0]):.6g} {unit}): a dead channel or "
                    "the wrong column; check the file or --columns")
        # the spread of the bulk of the samples (interquartile range / 1.349, the sd of a
        # normal), so that a few spikes (impacts in a backlash) do not hide the drive
        q1, q3 = np.percentile(x, [25, 75])
        spread = (q3 - q1) / 1.349 or rms
        share = abs(fundamental(record.time, x, freq)) / spread
        if share < MIN_DRIVE_SHARE:
            return (f"the {_NAMES[name]} column has almost nothing at the drive frequency {freq:.3g} Hz "
                    f"(its amplitude there is {share:.1%} of its spread): a dead or noisy channel, the wrong "
                    "column, or a wrong drive_frequency_hz; check the file, --columns and the metadata")
    return None


def _clipped(record: Record, freq: float):
    for name, x, unit in _channels(record):
        levels, counts = np.unique(x, return_counts=True)
        if len(levels) < 3:
            continue  # a constant or two-valued channel: the flat check's business
        for side, at, beside in (("largest", -1, -2), ("smallest", 0, 1)):
            share = counts[at] / len(x)
            # a rail piles samples on one value; a quantised peak holds about as many as
            # the level beside it (an unclipped sine's top level about 1.4 times)
            if share >= CLIP_SHARE and counts[at] >= max(CLIP_PILE * counts[beside], 5):
                return (f"the {_NAMES[name]} column sits at its {side} value {float(levels[at]):.6g} {unit} for "
                        f"{share:.1%} of the samples: clipped at the sensor's or the DAQ's range; "
                        "record again with a larger range")
    return None


def _name_causes(causes: list[str]) -> str:
    return causes[0] if len(causes) == 1 else ", ".join(causes[:-1]) + " or " + causes[-1]


def _scaled(record: Record, **factors) -> Record:
    return replace(record, **{k: getattr(record, k) * f for k, f in factors.items()})


def _declared(record: Record, quantity: str) -> float:
    """The factor to SI of the unit the file's ``quantity`` column was read in
    (``source_columns`` in the metadata, :func:`.io.read_record`); 1 for SI."""
    unit = (record.metadata.get("source_columns") or {}).get(quantity, {}).get("unit")
    return UNITS[quantity].get(unit, 1.0) if unit else 1.0


def _swapped(record: Record, a: str, b: str) -> Record | None:
    """The record with the file's columns of ``a`` and ``b`` exchanged: each raw column
    back through its own declared unit, then through the other's."""
    x, y = getattr(record, a), getattr(record, b)
    if x is None or y is None:
        return None
    fa, fb = _declared(record, a), _declared(record, b)
    return replace(record, **{a: y / fb * fa, b: x / fa * fb})


def _in_unit(quantity: str, unit: str):
    """The correction for a column read as SI that was in ``unit``; none where the user
    declared a unit for that column (the advice to declare one would be wrong)."""
    def fix(r: Record):
        if getattr(r, quantity) is None or _declared(r, quantity) != 1.0:
            return None
        return _scaled(r, **{quantity: UNITS[quantity][unit]})
    return fix


#: Mistakes a file commonly holds, each with the record it would be without the mistake.
_CAUSES = (
    ("force and acceleration columns swapped", lambda r: _swapped(r, "force", "accel")),
    ("acceleration and displacement columns swapped", lambda r: _swapped(r, "accel", "disp")),
    ("force and displacement columns swapped", lambda r: _swapped(r, "force", "disp")),
    ("force in kN (--units force=kN)", _in_unit("force", "kN")),
    ("force in lbf (--units force=lbf)", _in_unit("force", "lbf")),
    ("acceleration in g (--units accel=g)", _in_unit("accel", "g")),
    ("acceleration in mm/s^2 (--units accel=mm/s^2)", _in_unit("accel", "mm/s^2")),
    ("displacement in mm (--units disp=mm)", _in_unit("disp", "mm")),
    ("the force's sign reversed", lambda r: _scaled(r, force=-1.0)),
    ("the acceleration's sign reversed", lambda r: _scaled(r, accel=-1.0)),
    ("the displacement's sign reversed", lambda r: None if r.disp is None else _scaled(r, disp=-1.0)),
)


def _likely_causes(record: Record, freq: float, tests) -> list[str]:
    """The mistakes of :data:`_CAUSES` whose correction makes every test in ``tests``
    (functions of a record returning None when it passes) pass."""
    found = []
    for cause, fix in _CAUSES:
        fixed = fix(record)
        if fixed is not None and all(test(fixed) is None for test in tests):
            found.append(cause)
    return found


def _accel_disp(record: Record, freq: float):
    if record.disp is None:
        return None
    w = 2 * math.pi * freq
    a, d = fundamental(record.time, record.accel, freq), fundamental(record.time, record.disp, freq)
    if d == 0:
        return None
    r = a / (-w * w * d)
    if (ACCEL_DISP_RATIO[0] <= abs(r) <= ACCEL_DISP_RATIO[1]
            and abs(math.degrees(np.angle(r))) <= ACCEL_DISP_PHASE_DEG):
        return None
    return (f"the acceleration at {freq:.3g} Hz is {abs(r):.3g} times the displacement's second "
            f"derivative, {math.degrees(np.angle(r)):+.0f} deg out of phase (expected 1 and 0)")


def _apparent_mass(record: Record, freq: float, m_s, m_B, b_range):
    a, f = fundamental(record.time, record.accel, freq), fundamental(record.time, record.force, freq)
    if a == 0:
        return None
    w = 2 * math.pi * freq
    z = f / a  # kg; the real part is the inertial mass, the imaginary part the resistance / omega
    m_s = 0.0 if m_s is None else float(m_s)
    m_B = 0.0 if m_B is None else float(m_B)
    lo, hi = m_B + 0.5 * (m_s + b_range[0]), m_B + 1.5 * (m_s + b_range[1])
    disp_amp = abs(a) / (w * w)  # without a displacement column, it must at least be plausible
    if lo <= z.real <= hi and (record.disp is not None or DISP_RANGE[0] <= disp_amp <= DISP_RANGE[1]):
        return None
    if not lo <= z.real <= hi:
        return (f"the force's inertial part at {freq:.3g} Hz, Re(F/a) = {z.real:.4g} kg, lies outside "
                f"the {lo:.4g} to {hi:.4g} kg that a device with m_s = {m_s:g} kg, m_B = {m_B:g} kg and "
                f"b from {b_range[0]:g} to {b_range[1]:g} kg gives")
    return (f"the acceleration's amplitude at {freq:.3g} Hz means a displacement of {disp_amp:.3g} m, "
            f"outside the {DISP_RANGE[0]:g} to {DISP_RANGE[1]:g} m of a test rig")


def b_range_for(record: Record, device=None) -> tuple[float, float]:
    """The range of b the apparent-mass check allows for ``record``: within
    :data:`EXPECTED_B_FACTOR` of the b expected from its metadata's ``setting`` (the
    paper's Table 2) or else a device file's theoretical inertance, inside
    :data:`B_RANGE`; :data:`B_RANGE` where nothing is expected."""
    from ..device import SETTINGS

    setting = str(record.metadata.get("setting") or "").upper()
    expected = SETTINGS[setting].b_paper if setting in SETTINGS else (
        device.theoretical_inertance if device is not None else None)
    if not expected:
        return B_RANGE
    return (max(B_RANGE[0], expected / EXPECTED_B_FACTOR), min(B_RANGE[1], expected * EXPECTED_B_FACTOR))


def check_record(record: Record, *, m_s: float | None = None, m_B: float | None = None,
                 b_range: tuple[float, float] = B_RANGE, skip=()) -> list[Finding]:
    """Every failed check of :data:`CHECKS` not in ``skip``, in order (empty: all pass).

    ``m_s``, ``m_B`` (kg) and ``b_range`` bound the apparent mass (None counts as 0).
    """
    unknown = [s for s in skip if s not in CHECKS]
    if unknown:
        raise ValueError(f"unknown check {unknown[0]!r}; the checks are {', '.join(CHECKS)}")
    freq = drive_frequency(record)
    found = []
    runs = {"time-unit": lambda: _time_unit(record, freq), "flat": lambda: _flat(record, freq),
            "clipped": lambda: _clipped(record, freq), "accel-vs-disp": lambda: _accel_disp(record, freq),
            "apparent-mass": lambda: _apparent_mass(record, freq, m_s, m_B, b_range)}
    for name in CHECKS:
        if name in skip:
            continue
        if name != "time-unit" and found and found[0].check in ("time-unit", "flat"):
            break  # the drive frequency or a channel is wrong: later checks would only echo it
        message = runs[name]()
        if message is not None:
            found.append(Finding(name, message))
    motion = [t for n, t in (("accel-vs-disp", lambda r: _accel_disp(r, freq)),
                             ("apparent-mass", lambda r: _apparent_mass(r, freq, m_s, m_B, b_range)))
              if n not in skip]
    for i, f in enumerate(found):
        if f.check in ("accel-vs-disp", "apparent-mass"):
            causes = _likely_causes(record, freq, motion)
            fix = (f": likely {_name_causes(causes)}; fix the file, --columns or --units" if causes else
                   ": check the columns and units" + (", the masses (--m-s, --m-b) and that the record is of an "
                                                      "inerter" if f.check == "apparent-mass" else ""))
            found[i] = Finding(f.check, f.message + fix)
    return found


def require_physical(record: Record, *, m_s=None, m_B=None, b_range=B_RANGE, skip=(), where: str = "") -> None:
    """Raise :class:`RecordCheckError` for the first failed check, its message naming the
    override (``--skip-check NAME``)."""
    found = check_record(record, m_s=m_s, m_B=m_B, b_range=b_range, skip=skip)
    if found:
        first = found[0]
        prefix = f"{where}: " if where else ""
        raise RecordCheckError(Finding(first.check, f"{prefix}{first.message} (if the record is right: "
                                                    f"--skip-check {first.check})"))
