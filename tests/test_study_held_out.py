"""The held-out families' table (``study.held_out``): counts among converged,
identified chains, distances from nominal, b / gain where held, the pool, refusals."""

import math

import pytest

from bayes_inerter.study.held_out import families_table
from bayes_inerter.study.replicate_store import write_replicate


def _replicate(k, family, *, converged=True, identified=True, c94=True, c50=False, over_gain=None):
    r = {"replicate": k, "family": family, "seed": 900 + k, "b_true": 1000.0, "b_median": 1001.0,
         "converged": converged, "identified": identified, "covered94": c94, "covered50": c50, "width94_pct": 2.0}
    if over_gain is not None:  # an interval around b g_F / g_a (here: wide, so held) or far off it
        r["hdi94_b_over_gain"] = [900.0, 1100.0] if over_gain else [1.0, 2.0]
        r["hdi50_b_over_gain"] = [1.0, 2.0]
    return r


def test_rows_count_converged_identified_chains_and_their_pool(tmp_path):
    a, b = tmp_path / "a", tmp_path / "b"
    for k, kw in enumerate([{}, {"c94": False}, {"converged": False, "c94": False}, {"identified": False}]):
        write_replicate(a, k, _replicate(k, "backlash", **kw))
    for k, kw in enumerate([{"over_gain": True, "c50": True}, {"over_gain": False}]):
        write_replicate(b, k, _replicate(k, "delays", **kw))
    backlash, delays, pool = families_table([a, b])
    assert (backlash["family"], backlash["records"], backlash["converged"], backlash["n"]) == ("backlash", 4, 3, 2)
    assert backlash["held94"] == 1 and backlash["z94"] == round((0.5 - 0.94) / math.sqrt(0.94 * 0.06 / 2), 2)
    assert backlash["n_b_over_gain"] == 0 and backlash["rate94_b_over_gain"] == ""
    assert delays["n_b_over_gain"] == 2 and delays["held94_b_over_gain"] == 1 and delays["held50_b_over_gain"] == 0
    assert delays["held50"] == 1 and delays["median_width94_b_over_gain_pct"] > 0
    assert pool["family"] == "all" and pool["records"] == 6 and pool["n"] == 4 and pool["held94"] == 3
    assert pool["mean_error_pct"] == pytest.approx(0.1)


def test_an_empty_folder_and_a_mixed_one_are_refused(tmp_path):
    with pytest.raises(ValueError, match="no finished replicates"):
        families_table([tmp_path / "none"])
    write_replicate(tmp_path / "m", 0, _replicate(0, "backlash"))
    write_replicate(tmp_path / "m", 1, _replicate(1, "delays"))
    with pytest.raises(ValueError, match="mixes the families backlash, delays"):
        families_table([tmp_path / "m"])
