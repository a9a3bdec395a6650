"""Tests of the richer models' effects (bayes_inerter.inference.posterior.effects) and their models."""

import math

import pytest

from bayes_inerter.device import paper_parameters
from bayes_inerter.friction import Coulomb, Stribeck
from bayes_inerter.inference.posterior.effects import EFFECT_PRIORS, EFFECTS, effect_network
from bayes_inerter.inference.posterior.likelihood import LikelihoodSettings
from bayes_inerter.inference.posterior.model import MODELS, PosteriorModel
from bayes_inerter.network import Deformation, Friction
from bayes_inerter.records.generator import GeneratorSettings, paper_record


def test_the_command_line_lists_every_model():
    from bayes_inerter.cli.parser import FIT_MODELS

    assert set(FIT_MODELS) == set(MODELS)


def test_effect_network_puts_stribeck_on_both_contacts_and_the_gap_in_the_nut_link():
    p = paper_parameters("A2")
    plain = effect_network("reduced", p, {})
    assert all(isinstance(b.law, Coulomb) for b in plain.blocks if isinstance(b, Friction))
    rich = effect_network("reduced", p, {"r_s": 1.4, "v_s": 3e-3, "gap": 2e-5})
    laws = [b.law for b in rich.blocks if isinstance(b, Friction)]
    assert len(laws) == 2 and all(isinstance(law, Stribeck) for law in laws)
    assert [law.f_s / law.f_c for law in laws] == pytest.approx([1.4, 1.4])
    assert {law.v_s for law in laws} == {3e-3}
    links = [b for b in rich.blocks if isinstance(b, Deformation)]
    assert links[-1].backlash.gap == 2e-5 and links[0].backlash is None  # the nut link only


#: The time-domain likelihood: the tests set sigma and rho and need Table I's c_B inside
#: the prior (the harmonic ones sample the bearing's damping ratio instead), and the 1 s
#: record holds too few drive periods for those.
AR1 = LikelihoodSettings(residual="ar1")


@pytest.fixture(scope="module")
def record():
    return paper_record("A3", 1.0, settings=GeneratorSettings(duration=1.0, ramp=0.3), seed=0)


@pytest.mark.parametrize("name", sorted(EFFECTS))
def test_richer_models_sample_their_effects_with_the_stated_priors(record, name):
    pm = PosteriorModel(record, name, likelihood=AR1)
    assert pm.effect_names == list(EFFECTS[name])
    assert [n for n in pm.names if n in EFFECT_PRIORS] == list(EFFECTS[name])
    theta = pm.to_theta(paper_parameters("A3"), 0.01, 0.2, effects={"r_s": 1.25, "v_s": 0.004, "gap": 3e-5})
    want = {"r_s": 1.25, "v_s": 0.004, "gap": 3e-5}
    assert pm.effects(theta) == pytest.approx({n: want[n] for n in EFFECTS[name]})
    assert pm.parameters(theta).b == pytest.approx(paper_parameters("A3").b)
    assert math.isfinite(pm.log_prior(theta))
    assert EFFECT_PRIORS["r_s"].bounds == (1.0, 2.0) and EFFECT_PRIORS["gap"].bounds == (0.0, 1e-4)
    assert [math.exp(x) for x in EFFECT_PRIORS["v_s"].bounds] == pytest.approx([1e-4, 1e-1])


def test_the_papers_model_has_no_effects(record):
    pm = PosteriorModel(record, likelihood=AR1)
    assert pm.effect_names == [] and pm.effects(pm.to_theta(paper_parameters("A3"), 0.01, 0.2)) == {}
