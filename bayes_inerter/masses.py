"""Which masses a fit uses, and where each came from.

Precedence, highest first: the caller's option (``--m-s``, ``--m-b``), the record's
metadata (``m_s``, ``m_B``, or ``setting``, whose Table 2 gives m_s), the device file,
and for m_B only the paper's Table I (57.2 kg), an **assumption** for a device that is
not the paper's. The source of each is kept, printed by ``fit`` and stored in fit.json.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .device import SETTINGS, TABLE_I
from .records.record import Record

__all__ = ["Masses", "resolve_masses"]


@dataclass(frozen=True)
class Masses:
    """m_s and m_B (kg) and a few words on where each came from."""

    m_s: float
    m_B: float
    m_s_source: str
    m_B_source: str

    def describe(self) -> str:
        return (f"m_s = {self.m_s:g} kg ({self.m_s_source}), m_B = {self.m_B:g} kg ({self.m_B_source})")

    def as_dict(self) -> dict:
        return {"m_s": {"kg": self.m_s, "source": self.m_s_source},
                "m_B": {"kg": self.m_B, "source": self.m_B_source}}


def _check(name: str, value) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
        raise ValueError(f"{name} must be a positive number of kg, got {value!r}")
    return float(value)


def resolve_masses(record: Record, *, m_s: float | None = None, m_B: float | None = None,
                   device=None) -> Masses:
    """The masses for ``record`` (see module docstring); ``device``: a
    :class:`.device_file.DeviceFile` or None. ValueError if m_s is found nowhere."""
    meta = record.metadata
    setting = meta.get("setting")
    dev_name = f"device file {device.path}" if device is not None else ""
    if m_s is not None:
        ms, ms_src = m_s, "option --m-s"
    elif meta.get("m_s") is not None:
        ms, ms_src = meta["m_s"], "record metadata m_s"
    elif setting and str(setting).upper() in SETTINGS:
        ms, ms_src = SETTINGS[str(setting).upper()].m_s, f"record metadata: setting {str(setting).upper()}, paper's Table 2"
    elif device is not None and device.m_s is not None:
        ms, ms_src = device.m_s, dev_name
    else:
        raise ValueError("the screw mass m_s is unknown: give --m-s KG, a --device file with m_s, "
                         "or put m_s or setting in the record's metadata")
    if m_B is not None:
        mb, mb_src = m_B, "option --m-b"
    elif meta.get("m_B") is not None:
        mb, mb_src = meta["m_B"], "record metadata m_B"
    elif device is not None and device.m_B is not None:
        mb, mb_src = device.m_B, dev_name
    else:
        mb, mb_src = TABLE_I["m_B"], "the paper's Table I, an assumption: give --m-b for another device"
    return Masses(_check("m_s", ms), _check("m_B", mb), ms_src, mb_src)
