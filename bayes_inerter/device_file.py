"""A user's own device, described in a TOML file (read with Python's tomllib).

::

    m_B = 57.2            # kg: plate, spline nuts, bearing
    m_s = 21.7            # kg: screw and flywheels (translating)

    [geometry]            # optional: the theoretical inertance follows from it
    lead = 0.01984        # m per revolution
    J_screw = 0.0047      # kg m^2: the screw and what turns with it
    # or, instead of J_screw: screw = { mass = 15.4, diameter = 0.0496 }

    [[geometry.flywheels]]
    diameter = 0.19       # m
    thickness = 0.009     # m
    density = 7850        # kg/m^3 (or mass = 2.094, kg)
    count = 3

Every value is in SI units. Flywheels and the screw are solid discs (J = m r^2 / 2), an
**assumption** of this file format; a hollow part is given by its J_screw instead.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

__all__ = ["Flywheel", "DeviceFile", "read_device", "DeviceFileError"]


class DeviceFileError(ValueError):
    """A device file that cannot be used; the message names the file and the key."""


@dataclass(frozen=True)
class Flywheel:
    """``count`` solid discs of ``mass`` (kg), ``diameter`` (m)."""

    mass: float
    diameter: float
    count: int = 1

    @property
    def inertia(self) -> float:
        """Moment of inertia of all ``count`` discs about the screw's axis, kg m^2."""
        return self.count * 0.5 * self.mass * (self.diameter / 2) ** 2


@dataclass(frozen=True)
class DeviceFile:
    """Masses and (optionally) the geometry of a user's inerter, SI units."""

    path: str
    m_B: float | None = None
    m_s: float | None = None
    lead: float | None = None
    J_screw: float | None = None
    flywheels: tuple = field(default_factory=tuple)

    @property
    def theoretical_inertance(self) -> float | None:
        """b = (2 pi / lead)^2 (J_screw + the flywheels' J), kg; None without a geometry."""
        if self.lead is None or self.J_screw is None:
            return None
        return (2 * math.pi / self.lead) ** 2 * (self.J_screw + sum(f.inertia for f in self.flywheels))


def _positive(table: dict, key: str, where: str, required: bool = False):
    if key not in table:
        if required:
            raise DeviceFileError(f"{where}: key {key!r} is missing")
        return None
    value = table[key]
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
        raise DeviceFileError(f"{where}: {key} must be a positive number in SI units, got {value!r}")
    return float(value)


def _disc_mass(table: dict, where: str) -> float:
    mass = _positive(table, "mass", where)
    if mass is not None:
        return mass
    density, thickness = _positive(table, "density", where), _positive(table, "thickness", where)
    diameter = _positive(table, "diameter", where, required=True)
    if density is None or thickness is None:
        raise DeviceFileError(f"{where}: give mass (kg), or density (kg/m^3) and thickness (m)")
    return density * math.pi * (diameter / 2) ** 2 * thickness


def read_device(path) -> DeviceFile:
    """Read and check a device file; raise DeviceFileError with a one-line message."""
    path = Path(path)
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except FileNotFoundError:
        raise DeviceFileError(f"{path}: no such device file; check the path") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise DeviceFileError(f"{path}: cannot be read ({exc})") from None
    except tomllib.TOMLDecodeError as exc:
        raise DeviceFileError(f"{path}: not valid TOML ({exc})") from None
    known = {"m_B", "m_s", "geometry", "name"}
    unknown = sorted(set(data) - known)
    if unknown:
        raise DeviceFileError(f"{path}: unknown key {unknown[0]!r}; the keys are {', '.join(sorted(known))}")
    m_B, m_s = _positive(data, "m_B", str(path)), _positive(data, "m_s", str(path))
    geo = data.get("geometry")
    if geo is None:
        return DeviceFile(str(path), m_B=m_B, m_s=m_s)
    where = f"{path}: [geometry]"
    if not isinstance(geo, dict):
        raise DeviceFileError(f"{where} must be a table")
    lead = _positive(geo, "lead", where, required=True)
    if "J_screw" in geo:
        J_screw = _positive(geo, "J_screw", where)
    elif isinstance(geo.get("screw"), dict):
        screw = geo["screw"]
        J_screw = Flywheel(_disc_mass(screw, f"{where} screw"),
                           _positive(screw, "diameter", f"{where} screw", required=True)).inertia
    else:
        raise DeviceFileError(f"{where}: give J_screw (kg m^2) or screw = {{ mass = KG, diameter = M }}")
    wheels = []
    for i, fw in enumerate(geo.get("flywheels", [])):
        w = f"{where} flywheel {i + 1}"
        if not isinstance(fw, dict):
            raise DeviceFileError(f"{w} must be a table")
        count = fw.get("count", 1)
        if isinstance(count, bool) or not isinstance(count, int) or count < 0:
            raise DeviceFileError(f"{w}: count must be a whole number >= 0, got {count!r}")
        wheels.append(Flywheel(_disc_mass(fw, w), _positive(fw, "diameter", w, required=True), count))
    return DeviceFile(str(path), m_B=m_B, m_s=m_s, lead=lead, J_screw=J_screw, flywheels=tuple(wheels))
