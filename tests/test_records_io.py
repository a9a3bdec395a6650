import json

import numpy as np
import pytest

from bayes_inerter.records import GeneratorSettings, RecordError, generate_record, read_record, write_record
from bayes_inerter import paper_parameters


@pytest.fixture(scope="module")
def record():
    return generate_record(
        paper_parameters("A2"), 1.0, settings=GeneratorSettings(duration=1.0, ramp=0.3), rng=5, setting_name="A2"
    )


def test_round_trip(tmp_path, record):
    path, side = write_record(tmp_path / "r.csv", record)
    assert side == tmp_path / "r.json"
    back = read_record(path)
    for name in ("time", "force", "accel", "disp"):
        np.testing.assert_array_equal(getattr(back, name), getattr(record, name))
    assert back.metadata == json.loads(json.dumps(record.metadata))


def test_header_metadata_and_no_disp(tmp_path):
    t = np.arange(200) / 1000.0
    lines = ["# setting: A1", "# drive_frequency_hz: 1.5", "# operator: lab 2", "time_s,force_N,accel_m_s2"]
    lines += [f"{float(ti)!r},{float(np.sin(ti))!r},{float(np.cos(ti))!r}" for ti in t]
    p = tmp_path / "m.csv"
    p.write_text("\n".join(lines) + "\n")
    rec = read_record(p)
    assert rec.disp is None
    assert rec.metadata == {"setting": "A1", "drive_frequency_hz": 1.5, "operator": "lab 2"}
    np.testing.assert_array_equal(rec.time, t)


def _write(tmp_path, header, rows, name="bad.csv", pre=()):
    p = tmp_path / name
    p.write_text("\n".join([*pre, header, *rows]) + "\n")
    return p


def good_rows(n=150, fs=1000.0):
    return [f"{i / fs!r},{float(i)},{0.5 * i}" for i in range(n)]


H = "time_s,force_N,accel_m_s2"


@pytest.mark.parametrize(
    "make, message",
    [
        (lambda d: d / "missing.csv", r"missing.csv: no such file; check the path"),
        (lambda d: _write(d, "", []), "the file is empty"),
        (lambda d: _write(d, "time_s,force_N,acc", good_rows()), "line 1: missing column 'accel_m_s2'"),
        (lambda d: _write(d, "time_s,force_kN,accel_m_s2", good_rows()), "missing column 'force_N'"),
        (lambda d: _write(d, H + ",temp_C", [r + ",20" for r in good_rows()]), "unknown column 'temp_C'"),
        (lambda d: _write(d, "time_s,force_N,force_N,accel_m_s2", good_rows()), "column 'force_N' appears more than once"),
        (lambda d: _write(d, H, good_rows()[:5] + ["0.005,abc,1.0"] + good_rows()[6:]), r"line 7, column force_N: 'abc' is not a number"),
        (lambda d: _write(d, H, good_rows()[:9] + ["0.009,nan,1.0"] + good_rows()[10:]), "line 11, column force_N: nan is not a finite number"),
        (lambda d: _write(d, H, good_rows()[:9] + ["0.009,1.0,inf"] + good_rows()[10:]), "column accel_m_s2: inf is not a finite"),
        (lambda d: _write(d, H, good_rows()[:3] + ["0.003,1.0"] + good_rows()[4:]), "line 5 has 2 fields, expected 3"),
        (lambda d: _write(d, H, good_rows()[:20] + good_rows()[19:]), r"line 22: time .* is not after .*strictly increasing"),
        (lambda d: _write(d, H, good_rows()[:20] + good_rows()[21:]), r"line 22: sample interval .* resample the record uniformly"),
        (lambda d: _write(d, H, good_rows(50)), "50 samples; a record needs at least 100"),
        (lambda d: _write(d, H, good_rows(), pre=["# m_s: -3"]), "key 'm_s' must be a positive number"),
        (lambda d: _write(d, H, good_rows(), pre=["# setting: Z9"]), "unknown setting 'Z9'"),
        (lambda d: _write(d, H, good_rows(), pre=["# sampling_rate_hz: 500"]), "sampling_rate_hz = 500 but the time column is sampled at 1000"),
        (lambda d: _write(d, H, good_rows(), pre=["# just words"]), "metadata lines read"),
        (lambda d: _write(d, H, good_rows()[:10] + [""] + good_rows()[10:]), "line 12 is blank"),
    ],
)
def test_bad_records_are_refused_with_one_line(tmp_path, make, message):
    path = make(tmp_path)
    before = sorted(p.name for p in tmp_path.iterdir())
    with pytest.raises(RecordError, match=message) as info:
        read_record(path)
    text = str(info.value)
    assert "\n" not in text and str(path.name) in text
    assert sorted(p.name for p in tmp_path.iterdir()) == before  # nothing written


def test_binary_file(tmp_path):
    p = tmp_path / "b.csv"
    p.write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\xff\xfe")
    with pytest.raises(RecordError, match="not a text file|NUL bytes"):
        read_record(p)


def test_sidecar_contradicting_header(tmp_path):
    p = _write(tmp_path, H, good_rows(), name="c.csv", pre=["# setting: A1"])
    (tmp_path / "c.json").write_text(json.dumps({"setting": "A2"}))
    with pytest.raises(RecordError, match="contradicts c.json"):
        read_record(p)


def test_invalid_sidecar(tmp_path):
    p = _write(tmp_path, H, good_rows(), name="d.csv")
    (tmp_path / "d.json").write_text("{not json")
    with pytest.raises(RecordError, match="d.json: not valid JSON"):
        read_record(p)


def test_write_refuses_non_csv_name(tmp_path, record):
    with pytest.raises(ValueError, match="must end in .csv"):
        write_record(tmp_path / "r.txt", record)
    assert not any(tmp_path.iterdir())
