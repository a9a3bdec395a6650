"""The CSV reader and the command line against random and hostile files (hypothesis):
every file ends in a clear error or a correct record, never a traceback or a silent
change of the data."""

import json
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from bayes_inerter.cli import main
from bayes_inerter.records import Record, RecordError, read_record, write_record

PROFILE = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture])

finite = st.floats(min_value=-1e300, max_value=1e300, allow_nan=False, allow_infinity=False)


def _check_read(path):
    """A record or a one-line RecordError, nothing else."""
    try:
        rec = read_record(path)
    except RecordError as exc:
        assert "\n" not in str(exc) and str(exc)
        return None
    assert isinstance(rec, Record)
    for x in (rec.time, rec.force, rec.accel):
        assert np.all(np.isfinite(x))
    return rec


#: The rows of a record the reader accepts (100 samples at 1 kHz): the explicit example
#: that makes sure a random test's "a record" branch runs too, not only its refusals.
#: The force is 1,000 kg times the acceleration, so that ``inspect``'s physical checks pass.
GOOD_ROWS = "".join(f"{i / 1000.0!r},{1000.0 * math.cos(i / 10.0)!r},{math.cos(i / 10.0)!r}\n" for i in range(100))


def test_random_bytes_are_a_clear_error_or_a_record(tmp_path):
    """Both outcomes happen (the explicit example is a good file): the record's checks
    cannot pass by every file being refused."""
    outcomes = []

    @PROFILE
    @given(data=st.binary(max_size=2000))
    @example(data=("time_s,force_N,accel_m_s2\n" + GOOD_ROWS).encode())
    def error_or_record(data):
        path = tmp_path / "any.csv"
        path.write_bytes(data)
        outcomes.append(_check_read(path) is not None)

    error_or_record()
    assert any(outcomes) and not all(outcomes), outcomes


def test_random_csv_like_text_is_a_clear_error_or_a_record(tmp_path):
    """Both outcomes happen (the explicit example is a good file)."""
    outcomes = []

    @PROFILE
    @given(text=st.text(alphabet=st.sampled_from(list("0123456789.,-e+#: \nabcnaif_sNmtxAj")), max_size=1500))
    @example(text=GOOD_ROWS)
    def error_or_record(text):
        path = tmp_path / "any.csv"
        path.write_text("time_s,force_N,accel_m_s2\n" + text)
        outcomes.append(_check_read(path) is not None)

    error_or_record()
    assert any(outcomes) and not all(outcomes), outcomes


@PROFILE
@given(n=st.integers(min_value=100, max_value=400), fs=st.floats(min_value=10.0, max_value=1e5),
       seed=st.integers(min_value=0, max_value=2**32 - 1), scale=st.sampled_from([1e-300, 1e-6, 1.0, 1e6, 1e300]))
def test_written_records_read_back_bit_for_bit(tmp_path, n, fs, seed, scale):
    """Whatever finite values a record holds, huge or tiny, they come back unchanged."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) / fs
    rec = Record(t, scale * rng.standard_normal(n), scale * rng.standard_normal(n),
                 metadata={"setting": "A1", "drive_frequency_hz": 1.0})
    path, _ = write_record(tmp_path / "r.csv", rec)
    back = read_record(path)
    for name in ("time", "force", "accel"):
        np.testing.assert_array_equal(getattr(back, name), getattr(rec, name))


def test_a_hostile_value_anywhere_is_refused_or_kept_exactly(tmp_path):
    """Each file is refused or read exactly; both happen (the explicit examples make sure
    of it), so the exactness check cannot pass by every file being refused."""
    outcomes = []

    @PROFILE
    @given(values=st.lists(st.one_of(finite, st.just(math.inf), st.just(math.nan)), min_size=3, max_size=3),
           row=st.integers(min_value=0, max_value=99))
    @example(values=[0.0, -12.5, 3.25e-7], row=7)
    @example(values=[0.0, math.inf, 1.0], row=42)
    def refused_or_exact(values, row):
        t = (np.arange(100) / 1000.0).tolist()  # floats: numpy 2 writes np.float64(...) as its repr
        lines = ["time_s,force_N,accel_m_s2"]
        for i, ti in enumerate(t):
            f, a = (values[1], values[2]) if i == row else (0.0, 0.0)
            lines.append(f"{ti!r},{f!r},{a!r}")
        path = tmp_path / "h.csv"
        path.write_text("\n".join(lines) + "\n")
        rec = _check_read(path)
        outcomes.append(rec is not None)
        if rec is not None:  # accepted: then exactly what the file says
            assert rec.force[row] == values[1] and rec.accel[row] == values[2]
            assert np.all(np.isfinite([values[1], values[2]]))

    refused_or_exact()
    assert any(outcomes) and not all(outcomes), outcomes


def test_metadata_values_are_checked(tmp_path):
    """Each record with metadata is refused or keeps positive masses and frequency; both
    happen (the explicit examples make sure of it)."""
    outcomes = []

    @PROFILE
    @given(meta=st.dictionaries(st.sampled_from(["m_s", "m_B", "drive_frequency_hz", "sampling_rate_hz", "setting"]),
                                st.one_of(finite, st.text(max_size=5), st.booleans(), st.none()), max_size=4))
    @example(meta={"m_s": 0.8, "drive_frequency_hz": 1.0})
    @example(meta={"m_s": -1.0})
    def refused_or_positive(meta):
        t = (np.arange(100) / 1000.0).tolist()  # floats: numpy 2 writes np.float64(...) as its repr
        path = tmp_path / "m.csv"
        path.write_text("time_s,force_N,accel_m_s2\n" + "\n".join(f"{x!r},1.0,2.0" for x in t) + "\n")
        (tmp_path / "m.json").write_text(json.dumps(meta))
        rec = _check_read(path)
        outcomes.append(rec is not None)
        if rec is not None:
            for key in ("m_s", "m_B", "drive_frequency_hz"):
                if rec.metadata.get(key) is not None:
                    assert rec.metadata[key] > 0

    refused_or_positive()
    assert any(outcomes) and not all(outcomes), outcomes


def test_the_command_line_never_shows_a_traceback(tmp_path, capsys):
    """Both exits happen (the explicit example is a good file): 0 with no error, 1 with
    a one-line error."""
    codes = []

    @PROFILE
    @given(data=st.binary(max_size=600))
    @example(data=GOOD_ROWS.encode())
    def exits_cleanly(data):
        path = tmp_path / "cli.csv"
        path.write_bytes(b"time_s,force_N,accel_m_s2\n" + data)
        code = main(["inspect", str(path)])
        err = capsys.readouterr().err
        assert code in (0, 1)
        assert "Traceback" not in err
        if code == 1:
            assert err.startswith("error: ") and err.count("\n") == 1
        codes.append(code)

    exits_cleanly()
    assert set(codes) == {0, 1}, codes


@pytest.mark.slow
def test_a_million_rows(tmp_path):
    """A long record reads in bounded time and memory, values unchanged."""
    n = 1_000_000
    rec = Record(np.arange(n) / 1000.0, np.sin(np.arange(n) * 1e-3), np.cos(np.arange(n) * 1e-3))
    path, _ = write_record(tmp_path / "long.csv", rec)
    back = read_record(path)
    np.testing.assert_array_equal(back.force, rec.force)
