"""The CSV format for records, generated and measured alike, and its validating reader.

A record is a CSV file with the header ``time_s,force_N,accel_m_s2`` (optionally a fourth
column ``disp_m``), one sample a row, SI units; or any delimited text file (comma,
semicolon or tab) whose columns and units a :class:`.units.ColumnMap` names. Its metadata sits either in a JSON file of
the same name beside it (``run1.csv`` -> ``run1.json``) or in ``# key: value`` lines
before the header (values that read as numbers become numbers). Known keys:
``setting`` (A0..B2) or ``m_s`` (kg), ``m_B`` (kg), ``drive_frequency_hz``,
``sampling_rate_hz``, ``columns`` and ``units`` (:mod:`.units`); generated records also carry ``true_parameters`` and ``generator``.

The reader drops, interpolates and reorders nothing: any problem is a
:class:`RecordError` (a ValueError) with a one-line message naming the file, the line
or column, and what to do.
"""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path

import numpy as np

from ..device import SETTINGS
from ..simulate import UNIFORM_RTOL
from .record import Record
from .units import QUANTITIES, ColumnMap, UnitError

__all__ = ["RecordError", "read_record", "write_record", "metadata_path", "COLUMNS", "MIN_SAMPLES"]

COLUMNS = ("time_s", "force_N", "accel_m_s2")
OPTIONAL_COLUMNS = ("disp_m",)
#: Fewest samples a record may have (a tenth of a second at 1 kHz).
MIN_SAMPLES = 100
#: Largest relative mismatch between metadata's sampling rate and the time column.
RATE_RTOL = 1e-3


class RecordError(ValueError):
    """A record that cannot be used as it is; the message says where and what to do."""


def metadata_path(path) -> Path:
    """The JSON metadata file beside a record: same name, suffix .json."""
    return Path(path).with_suffix(".json")


def _number(text: str):
    try:
        value = float(text)
    except ValueError:
        return text
    return int(value) if value.is_integer() and "." not in text and "e" not in text.lower() else value


def _check_metadata(path, meta: dict, time: np.ndarray) -> None:
    where = f"{path}: metadata"
    name = meta.get("setting")
    if name is not None and str(name).upper() not in SETTINGS:
        raise RecordError(f"{where} names an unknown setting {name!r}; use one of {', '.join(SETTINGS)}")
    for key in ("m_s", "m_B", "drive_frequency_hz", "sampling_rate_hz"):
        if key in meta and meta[key] is not None:
            value = meta[key]
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value) or value <= 0:
                raise RecordError(f"{where} key {key!r} must be a positive number, got {value!r}")
    rate = meta.get("sampling_rate_hz")
    if rate is not None:
        actual = (len(time) - 1) / (time[-1] - time[0])
        if abs(actual - rate) > RATE_RTOL * rate:
            raise RecordError(
                f"{where} says sampling_rate_hz = {rate:g} but the time column is sampled at "
                f"{actual:g} Hz; correct one of them"
                + (" (a time column in ms reads 1000 times too slow: give --units time=ms)"
                   if abs(actual * 1000 - rate) < 0.01 * rate else "")
            )


def _read_metadata(path: Path, header_meta: dict) -> dict:
    side = metadata_path(path)
    meta: dict = {}
    if side.exists():
        try:
            meta = json.loads(side.read_text())
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
            raise RecordError(f"{side}: not valid JSON ({exc}); fix or remove the metadata file") from None
        if not isinstance(meta, dict):
            raise RecordError(f"{side}: metadata must be a JSON object of key: value pairs")
    for key, value in header_meta.items():
        if key in meta and meta[key] != value:
            raise RecordError(
                f"{path}: header line '# {key}: {value}' contradicts {side.name} ({meta[key]!r}); "
                "keep one source of metadata"
            )
        meta[key] = value
    return meta


def _delimiter(header: str) -> str:
    """The field separator of a header line: comma, semicolon or tab, whichever splits
    it into the most fields (comma when none does)."""
    counts = {d: header.count(d) for d in (",", ";", "\t")}
    best = max(counts, key=lambda d: counts[d])
    return best if counts[best] else ","


def _column_map(path, meta: dict, given: ColumnMap | None) -> ColumnMap:
    """The metadata's ``columns`` and ``units``, overridden by the caller's map."""
    try:
        own = ColumnMap.from_options(meta.get("columns"), meta.get("units"), where=f"{path}: metadata")
    except UnitError as exc:
        raise RecordError(str(exc)) from None
    return own if given is None else own.overriding(given)


def read_record(path, *, columns=None, units=None) -> Record:
    """Read and validate a record CSV (and its metadata); raise RecordError if unusable.

    ``columns`` and ``units``: which of the file's columns is which quantity and in which
    unit (:class:`.units.ColumnMap`; texts as on the command line, ``"time=Zeit,
    force=Kraft"`` and ``"time=ms,force=kN"``, or dicts); they override the metadata's
    ``columns`` and ``units`` keys. The record returned is in SI units, its metadata
    without those two keys but with ``source_columns`` saying what was read from where.
    The field separator (comma, semicolon or tab) is found from the header line.
    """
    try:
        given = None if columns is None and units is None else ColumnMap.from_options(columns, units)
    except UnitError as exc:
        raise RecordError(str(exc)) from None
    path = Path(path)
    lines = _read_lines(path)
    header_meta, i = _header_metadata(path, lines)
    meta = _read_metadata(path, header_meta)
    cmap = _column_map(path, meta, given)
    header_line = i + 1
    delimiter = _delimiter(lines[i])
    wanted = {q: cmap.column(q) for q in QUANTITIES}
    header = _header(path, lines[i], header_line, delimiter, cmap, wanted)
    used = [(q, header.index(wanted[q])) for q in QUANTITIES if wanted[q] in header]
    data = _samples(path, lines[i + 1 :], header_line, delimiter, header, used)
    col = {q: data[:, j] * cmap.factor(q) if cmap.factor(q) != 1.0 else data[:, j] for j, (q, _) in enumerate(used)}
    t = col["time"]
    _check_time(path, t, data[:, 0], header_line)
    _check_metadata(path, meta, t)
    meta = {k: v for k, v in meta.items() if k not in ("columns", "units")}
    if not cmap.is_identity():
        meta["source_columns"] = {q: d for q, d in cmap.describe().items() if q in col}
    return Record(time=t, force=col["force"], accel=col["accel"], disp=col.get("disp"), metadata=meta)


def _read_lines(path: Path) -> list[str]:
    """The lines of a record's file, refused if it is missing, a folder, not UTF-8 text,
    empty, or binary."""
    if not path.exists():
        raise RecordError(f"{path}: no such file; check the path")
    if path.is_dir():
        raise RecordError(f"{path}: is a folder, not a record file")
    try:
        text = path.read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise RecordError(f"{path}: not a text file (byte {exc.start} is not UTF-8); export the record as CSV text") from None
    except OSError as exc:
        raise RecordError(f"{path}: cannot be read ({exc.strerror})") from None
    if not text.strip():
        raise RecordError(f"{path}: the file is empty; expected a header {','.join(COLUMNS)} and samples")
    if "\x00" in text:
        raise RecordError(f"{path}: contains NUL bytes; this is not a CSV text file")
    return text.splitlines()


def _header_metadata(path: Path, lines: list[str]) -> tuple[dict, int]:
    """The ``# key: value`` lines before the header (blank lines skipped), and the index
    of the header line."""
    header_meta: dict = {}
    i = 0
    while i < len(lines) and (lines[i].startswith("#") or not lines[i].strip()):
        line = lines[i][1:].strip() if lines[i].startswith("#") else ""
        if line:
            if ":" not in line:
                raise RecordError(f"{path}: line {i + 1}: metadata lines read '# key: value'; got {lines[i]!r}")
            key, value = (part.strip() for part in line.split(":", 1))
            header_meta[key] = _number(value)
        i += 1
    if i == len(lines):
        raise RecordError(f"{path}: no header line; expected {','.join(COLUMNS)}")
    return header_meta, i


def _header(path: Path, line: str, header_line: int, delimiter: str, cmap: ColumnMap, wanted: dict) -> list[str]:
    """The header's column names, refused if one repeats, one the map wants is missing, or
    (without a column map) one is not the project's."""
    header = [h.strip() for h in next(csv.reader([line], delimiter=delimiter))]
    dupes = sorted({h for h in header if header.count(h) > 1})
    if dupes:
        raise RecordError(f"{path}: line {header_line}: column {dupes[0]!r} appears more than once")
    for q in QUANTITIES[:3]:
        if wanted[q] not in header:
            hint = (f"correct {q}={wanted[q]} in the column map" if q in cmap.names
                    else f"name the file's {q} column with --columns {q}=NAME")
            raise RecordError(
                f"{path}: line {header_line}: missing column {wanted[q]!r} (found {', '.join(header)}); "
                f"the header must read {','.join(COLUMNS)}[,disp_m] in SI units, or {hint}"
            )
    if "disp" in cmap.names and wanted["disp"] not in header:
        raise RecordError(f"{path}: line {header_line}: missing column {wanted['disp']!r} named for disp "
                          f"(found {', '.join(header)}); check --columns")
    if not cmap.explicit:
        unknown = [h for h in header if h not in COLUMNS + OPTIONAL_COLUMNS]
        if unknown:
            raise RecordError(
                f"{path}: line {header_line}: unknown column {unknown[0]!r}; allowed columns are "
                f"{', '.join(COLUMNS + OPTIONAL_COLUMNS)} (SI units), or map a DAQ export's columns "
                "with --columns time=NAME,force=NAME,accel=NAME[,disp=NAME] (others are then ignored)"
            )
    return header


def _samples(path: Path, rows: list[str], header_line: int, delimiter: str, header: list[str], used) -> np.ndarray:
    """The ``used`` columns (quantity, index in the header) of the data lines, as numbers
    in the file's units; a blank line, a wrong number of fields, a field that is not a
    finite number, or fewer than MIN_SAMPLES rows is refused."""
    # a semicolon-separated export may write decimal commas ("0,5;12,3")
    decimal_comma = delimiter != "," and any("," in f for f in rows[0].split(delimiter)) if rows else False
    ncol = len(header)
    data = np.empty((len(rows), len(used)))
    nrow = 0
    for lineno, row in enumerate(csv.reader(rows, delimiter=delimiter), start=header_line + 1):
        if not row or (len(row) == 1 and not row[0].strip()):
            raise RecordError(f"{path}: line {lineno} is blank; remove blank lines inside the data")
        if len(row) != ncol:
            raise RecordError(f"{path}: line {lineno} has {len(row)} fields, expected {ncol} ({','.join(header)})")
        for j, (_, k) in enumerate(used):
            field = row[k].replace(",", ".") if decimal_comma else row[k]
            try:
                value = float(field)
            except ValueError:
                raise RecordError(
                    f"{path}: line {lineno}, column {header[k]}: {row[k].strip()!r} is not a number"
                ) from None
            if not math.isfinite(value):
                raise RecordError(
                    f"{path}: line {lineno}, column {header[k]}: {row[k].strip()} is not a finite "
                    "number; repair the sample (the reader interpolates nothing)"
                )
            data[nrow, j] = value
        nrow += 1
    data = data[:nrow]
    if nrow < MIN_SAMPLES:
        raise RecordError(f"{path}: {nrow} samples; a record needs at least {MIN_SAMPLES}")
    return data


def _check_time(path: Path, t: np.ndarray, read: np.ndarray, header_line: int) -> None:
    """Refuse a time column ``t`` (s; ``read``: as in the file) that is not strictly
    increasing or not uniformly sampled."""
    dt = np.diff(t)
    if np.any(dt <= 0):
        k = int(np.argmax(dt <= 0))
        raise RecordError(
            f"{path}: line {header_line + k + 2}: time {read[k + 1]!r} is not after {read[k]!r}; "
            "samples must be in strictly increasing time order"
        )
    h = (t[-1] - t[0]) / (len(t) - 1)
    dev = np.abs(dt - h) / h
    if dev.max() > UNIFORM_RTOL:
        k = int(np.argmax(dev))
        raise RecordError(
            f"{path}: line {header_line + k + 2}: sample interval {dt[k]:.6g} s differs from the "
            f"mean {h:.6g} s by {dev[k]:.2%}; resample the record uniformly"
        )


def write_record(path, record: Record, *, overwrite: bool = True) -> tuple[Path, Path]:
    """Write a record as CSV plus its JSON metadata beside it; return both paths.

    Numbers are written with 17 significant digits, so reading gives the same arrays.
    """
    path = Path(path)
    if path.suffix.lower() != ".csv":
        raise ValueError(f"{path}: a record file must end in .csv")
    side = metadata_path(path)
    if not overwrite and (path.exists() or side.exists()):
        raise FileExistsError(f"{path} exists; choose another name")
    path.parent.mkdir(parents=True, exist_ok=True)
    cols = [record.time, record.force, record.accel]
    header = list(COLUMNS)
    if record.disp is not None:
        cols.append(record.disp)
        header.append("disp_m")
    data = np.column_stack(cols)
    tmp = path.with_suffix(".csv.tmp")
    np.savetxt(tmp, data, fmt="%.17g", delimiter=",", header=",".join(header), comments="")
    tmp.replace(path)
    side.write_text(json.dumps(record.metadata, indent=2, sort_keys=True) + "\n")
    return path, side
