"""Reading a DAQ export: --columns, --units, delimiters, metadata keys, normalising."""

import json

import numpy as np
import pytest

from bayes_inerter.records import RecordError, read_record, write_record
from bayes_inerter.records.units import ColumnMap, UnitError, parse_assignments

T = np.arange(300) / 1000.0


def _export(path, delimiter=",", decimal=".", pre=(), header=("Zeit", "Kraft", "Beschl", "Temp"),
            scale=(1000.0, 1e-3, 1 / 9.80665)):
    rows = []
    for t in T:
        fields = [f"{t * scale[0]:.6f}", f"{np.sin(t) * 1000 * scale[1]:.9f}", f"{np.cos(t) * scale[2]:.9f}", "20.5"]
        rows.append(delimiter.join(f.replace(".", decimal) for f in fields))
    path.write_text("\n".join([*pre, delimiter.join(header), *rows]) + "\n")
    return path


@pytest.mark.parametrize("delimiter, decimal", [(",", "."), (";", "."), ("\t", "."), (";", ",")])
def test_export_read_in_si_with_any_delimiter(tmp_path, delimiter, decimal):
    p = _export(tmp_path / "daq.csv", delimiter, decimal)
    rec = read_record(p, columns="time=Zeit,force=Kraft,accel=Beschl", units="time=ms,force=kN,accel=g")
    np.testing.assert_allclose(rec.time, T, atol=1e-9)
    np.testing.assert_allclose(rec.force, np.sin(T) * 1000, rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(rec.accel, np.cos(T), rtol=1e-6)
    assert rec.metadata["source_columns"]["force"] == {"column": "Kraft", "unit": "kN"}


def test_metadata_keys_do_the_same_and_options_win(tmp_path):
    pre = ["# columns: time=Zeit,force=Kraft,accel=Beschl", "# units: time=ms,force=kN,accel=g"]
    p = _export(tmp_path / "daq.csv", pre=pre)
    rec = read_record(p)
    np.testing.assert_allclose(rec.force, np.sin(T) * 1000, rtol=1e-6, atol=1e-6)
    assert "columns" not in rec.metadata and "units" not in rec.metadata
    # the command line overrides the metadata: force read as N
    rec = read_record(p, units="force=N")
    np.testing.assert_allclose(rec.force, np.sin(T), rtol=1e-6, atol=1e-9)
    # JSON metadata may give them as objects
    q = _export(tmp_path / "daq2.csv")
    (tmp_path / "daq2.json").write_text(json.dumps({"columns": {"time": "Zeit", "force": "Kraft", "accel": "Beschl"},
                                                    "units": {"time": "ms", "force": "kN", "accel": "g"}}))
    np.testing.assert_allclose(read_record(q).accel, np.cos(T), rtol=1e-6)


@pytest.mark.parametrize("columns, units, message", [
    (None, None, r"missing column 'time_s' .*--columns time=NAME"),
    ("time=Zeit,force=Kraft,accel=Besch", None, r"missing column 'Besch'.*correct accel=Besch"),
    ("time=Zeit,force=Kraft,velocity=V", None, r"--columns: unknown quantity 'velocity'"),
    ("time=Zeit,force=Kraft,accel=Beschl", "force=MN", r"--units: force in 'MN' is not known; use one of N, kN, lbf"),
    ("time=Zeit,force=Kraft,accel=Beschl", "force", r"--units: 'force' is not QUANTITY=VALUE"),
    ("time=Zeit,time=Kraft,accel=Beschl", None, r"'time' is given twice"),
])
def test_bad_maps_refused_with_one_line(tmp_path, columns, units, message):
    p = _export(tmp_path / "daq.csv")
    with pytest.raises(RecordError, match=message) as info:
        read_record(p, columns=columns, units=units)
    assert "\n" not in str(info.value)


def test_unknown_column_without_a_map_names_the_option(tmp_path):
    p = tmp_path / "r.csv"
    p.write_text("time_s,force_N,accel_m_s2,temp\n" + "\n".join(f"{float(t)!r},1.0,2.0,3" for t in T) + "\n")
    with pytest.raises(RecordError, match="unknown column 'temp'.*--columns"):
        read_record(p)


def test_normalised_record_reads_back_the_same(tmp_path):
    p = _export(tmp_path / "daq.csv")
    rec = read_record(p, columns="time=Zeit,force=Kraft,accel=Beschl", units="time=ms,force=kN,accel=g")
    out, _ = write_record(tmp_path / "si.csv", rec)
    back = read_record(out)
    for name in ("time", "force", "accel"):
        np.testing.assert_array_equal(getattr(back, name), getattr(rec, name))
    assert back.metadata["source_columns"] == rec.metadata["source_columns"]


def test_column_map_units_and_aliases():
    m = ColumnMap.from_options("force=F", "accel=m/s2,disp=mm,force=lbf")
    assert m.factor("accel") == 1.0 and m.factor("disp") == 1e-3
    assert m.factor("force") == pytest.approx(4.4482216152605)
    assert m.column("force") == "F" and m.column("time") == "time_s"
    assert ColumnMap().is_identity()
    with pytest.raises(UnitError):
        parse_assignments("=x", "--units")
