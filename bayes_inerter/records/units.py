"""Which column of a measured file holds which quantity, and in which unit.

A DAQ export rarely has the project's header (``time_s,force_N,accel_m_s2[,disp_m]``,
SI units). A :class:`ColumnMap` says which of the file's columns is the time, force,
acceleration and (optionally) displacement, and the unit of each; the reader converts to
SI. Both come from the command line (``--columns time=Zeit,force=Kraft,accel=Beschl
--units time=ms,force=kN,accel=g``) or from the record's metadata keys ``columns`` and
``units`` in the same form (a string, or a JSON object); the command line wins.
"""

from __future__ import annotations

from dataclasses import dataclass, field

__all__ = ["QUANTITIES", "UNITS", "SI_COLUMNS", "ColumnMap", "UnitError", "parse_assignments"]

#: The quantities a record holds; ``disp`` is optional.
QUANTITIES = ("time", "force", "accel", "disp")

#: The project's own column names (SI units), used where no map names others.
SI_COLUMNS = {"time": "time_s", "force": "force_N", "accel": "accel_m_s2", "disp": "disp_m"}

#: Units each quantity may be given in, as factors to SI (s, N, m/s^2, m). g is the
#: standard gravity; lbf the pound-force (both exact by definition).
UNITS = {
    "time": {"s": 1.0, "ms": 1e-3},
    "force": {"N": 1.0, "kN": 1e3, "lbf": 4.4482216152605},
    "accel": {"m/s^2": 1.0, "g": 9.80665, "mm/s^2": 1e-3},
    "disp": {"m": 1.0, "mm": 1e-3},
}

#: Other spellings of the same units.
_ALIASES = {"m/s2": "m/s^2", "m_s2": "m/s^2", "mm/s2": "mm/s^2", "mm_s2": "mm/s^2", "n": "N", "kn": "kN"}


class UnitError(ValueError):
    """A column map or unit that cannot be used; the message says what to write instead."""


def parse_assignments(text, what: str) -> dict:
    """``"time=Zeit,force=Kraft"`` (or a dict) -> ``{"time": "Zeit", "force": "Kraft"}``,
    keys checked against :data:`QUANTITIES`. ``what`` names the source in errors."""
    if isinstance(text, dict):
        pairs = [(str(k), str(v)) for k, v in text.items()]
    else:
        pairs = []
        for part in str(text).split(","):
            if not part.strip():
                continue
            if "=" not in part:
                raise UnitError(f"{what}: {part.strip()!r} is not QUANTITY=VALUE; write e.g. time=ms,force=kN")
            key, value = (s.strip() for s in part.split("=", 1))
            pairs.append((key, value))
    out: dict = {}
    for key, value in pairs:
        if key not in QUANTITIES:
            raise UnitError(f"{what}: unknown quantity {key!r}; use {', '.join(QUANTITIES)}")
        if key in out:
            raise UnitError(f"{what}: {key!r} is given twice")
        if not value:
            raise UnitError(f"{what}: {key!r} has no value")
        out[key] = value
    return out


def _unit(quantity: str, name: str, what: str) -> str:
    name = _ALIASES.get(name, _ALIASES.get(name.lower(), name))
    if name not in UNITS[quantity]:
        raise UnitError(f"{what}: {quantity} in {name!r} is not known; use one of {', '.join(UNITS[quantity])}")
    return name


@dataclass(frozen=True)
class ColumnMap:
    """The file's column for each quantity and its unit (default: the SI names and units).

    ``names``: quantity -> column name in the file; quantities not named keep their SI
    column name. ``units``: quantity -> a unit of :data:`UNITS`; quantities not named are
    in SI. ``explicit``: whether any column was named (then other columns in the file are
    ignored, as a DAQ export has many; otherwise an unknown column is refused).
    """

    names: dict = field(default_factory=dict)
    units: dict = field(default_factory=dict)

    @classmethod
    def from_options(cls, columns=None, units=None, where: str = "") -> "ColumnMap":
        """Build from the ``--columns`` and ``--units`` texts (or dicts), checked;
        ``where`` names another source (a file's metadata) in errors."""
        what_c, what_u = (f"{where} key 'columns'", f"{where} key 'units'") if where else ("--columns", "--units")
        names = parse_assignments(columns, what_c) if columns else {}
        given = parse_assignments(units, what_u) if units else {}
        return cls(names, {q: _unit(q, u, what_u) for q, u in given.items()})

    def overriding(self, other: "ColumnMap") -> "ColumnMap":
        """This map with ``other``'s entries taking precedence."""
        return ColumnMap({**self.names, **other.names}, {**self.units, **other.units})

    @property
    def explicit(self) -> bool:
        return bool(self.names)

    def column(self, quantity: str) -> str:
        return self.names.get(quantity, SI_COLUMNS[quantity])

    def factor(self, quantity: str) -> float:
        return UNITS[quantity][self.units.get(quantity, next(iter(UNITS[quantity])))]

    def is_identity(self) -> bool:
        return not self.names and all(self.factor(q) == 1.0 for q in self.units)

    def describe(self) -> dict:
        """Column and unit of each quantity, for metadata and messages."""
        return {q: {"column": self.column(q), "unit": self.units.get(q, next(iter(UNITS[q])))} for q in QUANTITIES}
