"""Tests of the paper's least squares beside the posterior (bayes_inerter.study.least_squares)."""

import dataclasses
import json
import math
from pathlib import Path

from bayes_inerter.device import SETTINGS
from bayes_inerter.inference.summaries.interval import InertanceInterval
from bayes_inerter.study import least_squares as ls_mod
from bayes_inerter.study.fits import RecordFit
from bayes_inerter.study.least_squares import least_squares_section, least_squares_table, run_least_squares


def _fit(setting, freq, mean, lo, hi, honest=None):
    summary = {"b": {"mean": mean, "hdi_3%": lo, "hdi_97%": hi}, "phi": {"mean": 0.9}}
    info = {"converged": True}
    if honest:
        info["b_interval"] = dataclasses.asdict(InertanceInterval("honest", mean, *honest, 0.94, 0.01, 0.0, 0.01))
    return RecordFit(f"{setting}_{freq:g}Hz", setting, freq, "two-port", Path("."), summary, info)


def _ls(b, lo, hi, phi):
    return {"b": b, "b_interval": [lo, hi], "phi": phi}


def test_each_record_sets_least_squares_beside_posterior_honest_and_table_2():
    fits = [_fit("A3", 1.0, 3520.0, 3500.0, 3540.0, honest=(3450.0, 3600.0)), _fit("A3", 0.5, 4600.0, 4200.0, 5000.0)]
    got = {"A3_1Hz": _ls(3540.0, 3535.0, 3545.0, 0.76), "A3_0.5Hz": _ls(4700.0, 2900.0, 7400.0, 0.35),
           "B2_1Hz": {"error": "RuntimeError: gave up"}}
    rows = least_squares_table(got, fits, {"A3": 3531.6})
    assert [r["record"] for r in rows] == ["A3_0.5Hz", "A3_1Hz", "B2_1Hz"]  # setting, then frequency
    half, one, failed = rows
    assert one["b_paper"] == SETTINGS["A3"].b_paper and one["phi_paper"] == SETTINGS["A3"].fit_paper[1.0]
    assert (one["covers_ls"], one["covers_post"], one["covers_honest"]) == (False, True, True)
    assert (half["covers_ls"], half["covers_post"], half["covers_honest"]) == (True, False, None)
    assert failed["ls_error"] == "RuntimeError: gave up" and "b_ls" not in failed


def test_the_section_is_written_from_the_rows():
    fits = [_fit("A3", 1.0, 3500.0, 3490.0, 3510.0), _fit("A3", 1.5, 3500.0, 3480.0, 3520.0)]
    rows = least_squares_table({"A3_1Hz": _ls(3535.0, 3500.0, 3570.0, 0.70),
                                "A3_1.5Hz": _ls(3570.0, 3535.0, 3605.0, 0.80)}, fits, {"A3": 3531.6})
    text = "\n".join(least_squares_section(rows))
    paper = SETTINGS["A3"].fit_paper
    gap = (abs(0.70 - paper[1.0]) + abs(0.80 - paper[1.5])) / 2
    assert f"by {100 * gap:.1f} points on average over 2 records" in text
    assert "median 2.0 %" in text and "largest 2.0 %, A3_1.5Hz" in text  # log(3570/3500) = 1.98 %
    assert "least squares 1 of 2; posterior 0 of 2" in text
    assert "![least squares beside the posterior](least_squares.png)" in text


def _fake_identify(record, out, starts=4, seed=0):
    if "bad" in record:
        raise RuntimeError("the simulation gave up")
    info = {"record": Path(record).name, "starts": starts, "seed": seed, "b": 1.0, "b_interval": None,
            "phi": 0.5, "made": "now"}
    Path(out).write_text(json.dumps(info))
    return info


def test_earlier_fits_are_reused_and_a_failure_does_not_stop_the_others(tmp_path, monkeypatch):
    monkeypatch.setattr(ls_mod, "identify_one", _fake_identify)  # the worker processes are forked from here
    records = {n: (str(tmp_path / f"{n}.csv"), "A3", 1.0) for n in ("a", "b", "bad")}
    folder = tmp_path / "least_squares"
    folder.mkdir()
    # "a" (index 0, seed 0) was fitted before with these settings; "b" (index 1) with another seed
    (folder / "a.json").write_text(json.dumps({"record": "a.csv", "starts": 4, "seed": 0, "made": "before"}))
    (folder / "b.json").write_text(json.dumps({"record": "b.csv", "starts": 4, "seed": 7, "made": "before"}))
    heard = []
    got = run_least_squares(records, tmp_path, seed=0, processes=2, on_done=heard.append)
    assert got["a"]["made"] == "before" and got["b"]["made"] == "now" and got["b"]["seed"] == 1
    assert "the simulation gave up" in got["bad"]["error"]
    assert sorted(heard) == ["b", "bad"]


def test_identify_one_fits_a_record_and_keeps_what_a_rerun_checks(tmp_path):
    from bayes_inerter.records import write_record
    from bayes_inerter.records.generator import GeneratorSettings, paper_record

    path = tmp_path / "A3_1.5Hz.csv"
    write_record(path, paper_record("A3", 1.5, settings=GeneratorSettings(duration=3.0, ramp=0.8), seed=0))
    got = ls_mod.identify_one(str(path), str(tmp_path / "A3.json"), starts=1, seed=3)
    assert json.loads((tmp_path / "A3.json").read_text()) == got
    assert (got["record"], got["starts"], got["seed"], got["interval"]) == ("A3_1.5Hz.csv", 1, 3, "hessian")
    # one start: only what holds wherever it ends (b's accuracy: tests/test_inference_identify.py)
    if got["b_interval"] is None:
        assert got["why_no_interval"]
    else:
        lo, hi = got["b_interval"]
        assert lo < got["b"] < hi
    assert math.isfinite(got["b"]) and got["b"] > 0
    assert ls_mod._earlier(tmp_path / "A3.json", str(path), 1, 3) == got
    assert ls_mod._earlier(tmp_path / "A3.json", str(path), 4, 3) is None
