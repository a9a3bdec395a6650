"""What an unconverged fit says: b's own mixing, the rows it flags, and advice that
changes the outcome (never a command that repeats the same result)."""

import math

from bayes_inerter.inference.sampling.convergence import Convergence
from bayes_inerter.inference.summaries.end_state import CAP_FACTOR, NOT_CONVERGED, convergence_warning

CONV = Convergence()


def _rows(**diag):
    return [{"name": n, "r_hat": r, "ess_bulk": e} for n, (r, e) in diag.items()]


def _warn(iteration, tau, rows, steps=None, identified=True):
    return convergence_warning(converged=False, reason="not converged: (the rule's reason)", iteration=iteration,
                               tau=tau, rows=rows, conv=CONV, steps=steps, b_identified=identified)


def test_converged_has_no_warning():
    assert convergence_warning(converged=True, reason="converged", iteration=5000, tau={"b": 30.0}, rows=[],
                               conv=CONV, steps=None) is None


def test_at_the_cap_a_higher_cap_is_advised_where_tau_says_it_is_enough():
    tau = {"b": 40.0, "c_n": 500.0, "k_n": 120.0}
    w = _warn(CONV.max_steps, tau, _rows(b=(1.01, 900.0), c_n=(1.06, 337.0), k_n=(1.01, 800.0)))
    assert w.flag == NOT_CONVERGED and set(w.names) == {"c_n"}  # b and k_n pass their own diagnostics
    needed = math.ceil(CONV.n_tau * 500.0 / (1 - CONV.warmup))
    assert f"about {needed} steps" in w.message and "--max-steps" in w.message
    higher = int(w.message.split("--max-steps ")[1].split()[0])
    assert higher > CONV.max_steps and higher >= needed  # a run that changes the outcome
    assert "b's own chain has mixed (R-hat 1.010, bulk ESS 900): its interval can be quoted" in w.message
    assert "without --steps" not in w.message


def test_far_beyond_the_cap_the_advice_is_about_the_record():
    tau = {"b": 60.0, "c_n": 2000.0}
    w = _warn(CONV.max_steps, tau, _rows(b=(1.2, 100.0), c_n=(1.3, 50.0)))
    assert math.ceil(CONV.n_tau * 2000.0 / (1 - CONV.warmup)) > CAP_FACTOR * CONV.max_steps
    assert "--max-steps" not in w.message and "a longer record" in w.message
    assert "trust no interval yet" in w.message and set(w.names) == {"b", "c_n"}


def test_steps_below_the_cap_advise_running_until_converged():
    w = _warn(600, {"b": 30.0}, _rows(b=(1.2, 50.0)), steps=600)
    assert "run again without --steps" in w.message


def test_steps_at_the_cap_do_not_advise_running_without_steps():
    w = _warn(CONV.max_steps, {"b": 100.0}, _rows(b=(1.1, 200.0)), steps=CONV.max_steps)
    assert "without --steps" not in w.message and "--max-steps" in w.message


def test_an_unidentified_b_is_said():
    w = _warn(CONV.max_steps, {"b": 100.0}, _rows(b=(1.1, 200.0)), identified=False)
    assert "does not identify b" in w.message
