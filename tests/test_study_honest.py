"""Tests of each setting's honest inertance (bayes_inerter.study.honest)."""

import dataclasses
import math
from pathlib import Path

import pytest

from bayes_inerter.inference.summaries.interval import InertanceInterval, combined_interval
from bayes_inerter.records.sensitivity import SensorCalibration
from bayes_inerter.study.fits import RecordFit
from bayes_inerter.study.honest import honest_columns, record_interval


def _fit(setting, freq, median, sd, identified=True, phi=0.9, with_interval=True):
    iv = InertanceInterval("honest", median, 100.0 if not identified else median * 0.9,
                           1e5 if not identified else median * 1.1, 0.94, sd, 0.005, sd, identified, phi)
    info = {"m_s": 10.0, "m_B": 57.2, **({"b_interval": dataclasses.asdict(iv)} if with_interval else {})}
    return RecordFit(f"{setting}_{freq}", setting, freq, "two-port", Path("."), {}, info)


def test_a_settings_records_combine_and_one_not_identified_is_left_out():
    fits = [_fit("A3", 0.5, 9000.0, 0.05, identified=False, phi=0.3), _fit("A3", 1.0, 3500.0, 0.01),
            _fit("A3", 1.5, 3520.0, 0.01), _fit("B1", 1.0, 10400.0, 0.01)]
    rows = honest_columns([{"setting": "A3", "moving_mass": 67.2}, {"setting": "B1", "moving_mass": 67.2}], fits,
                          SensorCalibration(), {"A3": 3510.0})
    a3 = rows[0]
    want = combined_interval([record_interval(f) for f in fits[:3]], calibration=SensorCalibration(),
                             moving_mass=67.2)
    assert (a3["b_honest_3%"], a3["b_honest_97%"]) == (want.lo, want.hi)
    assert a3["honest_records"] == "2 of 3" and a3["honest_identified"] and a3["covers_truth_honest"]
    # the 0.5 Hz record's 9000 kg did not pull the combination
    assert a3["b_honest_median"] == pytest.approx(math.sqrt(3500.0 * 3520.0), rel=1e-6)
    assert rows[1]["honest_records"] == "1 of 1" and "covers_truth_honest" not in rows[1]


def test_fits_made_before_the_honest_interval_leave_the_columns_out():
    rows = honest_columns([{"setting": "A3", "moving_mass": 67.2}], [_fit("A3", 1.0, 3500.0, 0.01,
                                                                         with_interval=False)], SensorCalibration())
    assert rows == [{"setting": "A3", "moving_mass": 67.2}]


def test_a_setting_no_record_identifies_is_reported_so():
    rows = honest_columns([{"setting": "A0", "moving_mass": 67.2}],
                          [_fit("A0", 0.5, 9000.0, 0.05, identified=False, phi=0.2)], SensorCalibration())
    assert not rows[0]["honest_identified"] and (rows[0]["b_honest_3%"], rows[0]["b_honest_97%"]) == (100.0, 1e5)
