"""The model-error coverage study (``study.model_error``): its configuration, its
resumable rows, its table, and a rescore that remakes the committed table."""

import csv
from pathlib import Path

import pytest

import bayes_inerter.study.model_error as model_error
from bayes_inerter.executor import Serial
from bayes_inerter.study.model_error import DEFAULT_METHODS, Config, coverage, run

COMMITTED = Path(__file__).resolve().parents[1] / "results" / "model-error"


def test_the_configuration_names_what_it_refuses():
    with pytest.raises(ValueError, match="unknown methods nonsense"):
        Config(methods=("two-port", "nonsense"))
    with pytest.raises(ValueError, match="keep two-port"):
        Config(methods=("setting",), rescore=True)
    with pytest.raises(ValueError, match="replicates must be"):
        Config(replicates=0)


def _rows(k, config):
    return [{"replicate": k, "method": m, "b_true": 100.0, "b_centre": 100.0 + k, "sd_log_b": 0.01,
             "lo50": 99.0, "hi50": 101.0, "lo94": 98.0, "hi94": 102.0 + k, "identified": 1,
             "covered50": int(k == 0), "covered94": 1, "phi": 0.9} for m in config.methods]


def test_a_failed_replicate_is_named_the_others_kept_and_a_rerun_goes_on(tmp_path, monkeypatch):
    calls = []

    def fake(job):
        k, config = job
        calls.append(k)
        if k == 2:
            raise RuntimeError("start search failed")
        return _rows(k, config)

    monkeypatch.setattr(model_error, "replicate", fake)
    config = Config(replicates=3, methods=("two-port", "setting"))
    got = run(config, tmp_path, Serial())
    assert got.failed == (("replicate 2", "start search failed"),)
    table = {r["method"]: r for r in got.values["coverage"]}
    assert table["two-port"]["replicates"] == 2 and table["two-port"]["coverage50"] == 0.5
    calls.clear()
    monkeypatch.setattr(model_error, "replicate", lambda job: _rows(job[0], job[1]))
    again = run(config, tmp_path, Serial())
    assert not again.failed and again.values["coverage"][0]["replicates"] == 3
    assert calls == []  # replicates 0 and 1 were read from the partial rows, not run again
    with open(tmp_path / "replicates.partial.csv") as f:
        assert sorted({int(r["replicate"]) for r in csv.DictReader(f)}) == [0, 1, 2]


def test_coverage_counts_each_method_with_its_binomial_se():
    config = Config(methods=("two-port",))
    rows = [r for k in range(4) for r in _rows(k, config)]
    (row,) = coverage(rows)
    assert row["coverage50"] == 0.25 and row["se50"] == round((0.25 * 0.75 / 4) ** 0.5, 3)
    assert row["coverage94"] == 1.0 and row["se94"] == 0.0


def test_rescore_remakes_the_committed_coverage_of_the_first_replicates(tmp_path):
    """No fitting: the committed rows of replicates 0 to 4 scored again give the same
    counts as those rows themselves."""
    with open(COMMITTED / "replicates.csv") as f:
        rows = [r for r in csv.DictReader(f) if int(r["replicate"]) < 5]
    with open(tmp_path / "replicates.partial.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    got = run(Config(replicates=5, rescore=True), tmp_path, Serial())
    for row in got.values["coverage"]:
        mine = [r for r in rows if r["method"] == row["method"]]
        assert row["replicates"] == len(mine) == 5
        assert row["coverage50"] == round(sum(int(r["covered50"]) for r in mine) / 5, 3)
        assert row["coverage94"] == round(sum(int(r["covered94"]) for r in mine) / 5, 3)
    assert [r["method"] for r in got.values["coverage"]] == list(DEFAULT_METHODS)
