"""The least-squares summary (``study.least_squares_summary``): its table remade from
the committed full study, and its counts of intervals that hold the truth."""

from pathlib import Path

import pytest

from bayes_inerter.study.least_squares_summary import Config, run, summary_row

RESULTS = Path(__file__).resolve().parents[1] / "results"


def test_it_remakes_the_committed_summary(tmp_path):
    got = run(Config(full=str(RESULTS / "full")), tmp_path)
    assert (tmp_path / "summary.csv").read_bytes() == (RESULTS / "least-squares" / "summary.csv").read_bytes()
    assert [r["device"] for r in got.values["summary"]].count("control") == 4  # three frequencies and all


def test_a_row_counts_the_intervals_that_hold_and_skips_those_missing():
    rows = [{"b_truth": 100.0, "covers_ls": True, "b_ls_3%": 99.0, "b_ls_97%": 101.0, "phi_ls": 0.8},
            {"b_truth": 100.0, "covers_ls": False, "b_ls_3%": 90.0, "b_ls_97%": 94.0, "phi_ls": 0.6},
            {"b_truth": 100.0, "covers_ls": None, "b_ls_3%": None, "b_ls_97%": None}]
    row = summary_row("control", rows, "1")
    assert (row["records"], row["ls_intervals"], row["ls_hold"]) == (3, 2, 1)
    assert row["ls_median_width_%"] == pytest.approx(3.0) and row["mean_phi_ls"] == pytest.approx(0.7)
    assert row["post_intervals"] == 0 and row["post_median_width_%"] is None


def test_it_says_which_table_it_needs(tmp_path):
    with pytest.raises(ValueError, match="least_squares.csv is missing; run the full study"):
        run(Config(), tmp_path / "least-squares")
