"""Which convergence rule a study's chains were stopped by (``study.stop_rule``)."""

import pytest

from bayes_inerter.inference import Convergence
from bayes_inerter.study import stop_rule


def test_a_row_without_a_tolerance_was_stopped_with_the_old_default():
    assert stop_rule.recorded({}) == stop_rule.TAU_RTOL_BEFORE == 0.05
    assert stop_rule.recorded({"tau_rtol": 0.2}) == 0.2
    assert stop_rule.resolved(None) == Convergence().tau_rtol
    assert stop_rule.resolved(0.05) == 0.05


def test_the_rule_asked_keeps_the_package_rule_but_the_cap_and_tolerance():
    got = stop_rule.convergence(1234, 0.3)
    assert (got.max_steps, got.tau_rtol) == (1234, 0.3)
    assert got.n_tau == Convergence().n_tau and got.growth == Convergence().growth
    assert stop_rule.convergence(500, None).tau_rtol == Convergence().tau_rtol


def test_a_folder_keeps_one_tolerance_and_the_refusal_names_the_option():
    old = [{"replicate": 0}, {"replicate": 1}]  # written before rows named their tolerance
    stop_rule.check_folder(old, 0.05, "F")
    stop_rule.check_folder([], None, "F")
    with pytest.raises(ValueError, match="F holds chains stopped with tau_rtol 0.05, not 0.2: continue it "
                                         "with --tau-rtol 0.05"):
        stop_rule.check_folder(old, 0.2, "F")
    with pytest.raises(ValueError, match="tau_rtol 0.05, 0.3, not 0.1"):
        stop_rule.check_folder([*old, {"tau_rtol": 0.3}, {"tau_rtol": 0.1}], 0.1, "F")
