"""How a fit ends: warnings for b at a prior bound and a poor fit; no start, and so no
draw, outside the prior's support."""

import math

import numpy as np
import pytest

from bayes_inerter.inference.summaries.end_state import (FEW_PERIODS, FRICTION_DOMINATED, FRICTION_RATIO, HONEST_PERIODS,
                                                       PHI_WARNING, end_state_warnings, few_periods_warning,
                                                       friction_dominated_warning)
from bayes_inerter.inference.sampling.optimize import laplace_ensemble
from bayes_inerter.inference.posterior.priors import LogUniform, Uniform
from bayes_inerter.inference.summaries.results import PosteriorSample


class _Model:
    names = ["b", "f_share"]
    all_priors = {"b": LogUniform(100.0, 1e5), "f_share": Uniform(0.0, 1.0)}
    ndim = 2

    def bounds(self):
        return np.array([self.all_priors[n].bounds for n in self.names])


def _sample(log_b, phi, share=0.5):
    theta = np.stack([log_b, np.full_like(log_b, share)], axis=-1)
    return PosteriorSample(_Model.names, np.exp(theta), theta, {}, phi + 0 * log_b, 0 * log_b, 0, 1)


def test_b_piled_against_a_bound_and_a_poor_fit_are_named():
    rng = np.random.default_rng(1)
    lo, hi = math.log(100.0), math.log(1e5)
    inside = rng.normal(math.log(3000.0), 0.01, (8, 200))
    assert end_state_warnings(_Model(), _sample(inside, 0.9)) == []
    walled = lo + np.abs(rng.normal(0.0, 0.05, (8, 200)))
    found = end_state_warnings(_Model(), _sample(walled, 0.9))
    assert [(w.name, w.flag) for w in found] == [("b", "at lower prior bound")]
    assert "100 kg" in found[0].message
    top = hi - np.abs(rng.normal(0.0, 0.05, (8, 200)))
    assert [w.flag for w in end_state_warnings(_Model(), _sample(top, 0.9))] == ["at upper prior bound"]
    poor = end_state_warnings(_Model(), _sample(inside, PHI_WARNING - 0.1))
    assert [(w.name, w.flag) for w in poor] == [("phi", "poor fit")]
    # a nuisance share against its wall is expected, not flagged
    assert end_state_warnings(_Model(), _sample(inside, 0.9, share=0.0)) == []


class _Flat:
    """A model whose posterior is zero everywhere (a record no parameters reproduce)."""

    names = ["b", "f_share"]
    ndim = 2

    def bounds(self):
        return np.array([[math.log(100.0), math.log(1e5)], [0.0, 1.0]])

    def log_prob(self, theta):
        return -math.inf, math.nan


def test_no_walkers_drawn_around_a_start_of_zero_density():
    # before, every draw passed the test f(u) >= -inf, inside the prior or not, and the
    # walkers that started outside stayed there: draws outside the prior's support
    with pytest.raises(ValueError, match="zero posterior density"):
        laplace_ensemble(_Flat(), np.array([math.log(3000.0), 0.5]), 6, np.random.default_rng(0))


def test_a_record_of_three_periods_is_warned_and_b_flagged_and_four_are_not():
    w = few_periods_warning(3)
    assert w is not None and w.flag == FEW_PERIODS and w.names == ("b",)
    assert "3 steady drive periods" in w.message and "results/record-length" in w.message
    assert few_periods_warning(HONEST_PERIODS) is None
    assert few_periods_warning(None) is None  # a time-domain likelihood takes no periods' means


def test_a_friction_dominated_record_is_warned_and_b_flagged_and_an_inertial_one_is_not():
    w = friction_dominated_warning(0.3)
    assert w is not None and w.flag == FRICTION_DOMINATED and w.names == ("b",)
    assert "0.30 times" in w.message and "results/capped-by-force-ratio" in w.message
    assert friction_dominated_warning(FRICTION_RATIO) is None
    assert friction_dominated_warning(None) is None and friction_dominated_warning(float("inf")) is None
    # a joint fit's record: its setting's b flagged, the record named
    named = friction_dominated_warning(0.3, "b_A3", "A3 0.5 Hz")
    assert named.names == ("b_A3",) and named.message.startswith("record A3 0.5 Hz: its inertial force")
