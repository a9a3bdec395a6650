"""The map between sampled and physical parameters (``inference.posterior.parameters``)."""

import math

import numpy as np
import pytest

from bayes_inerter import paper_parameters
from bayes_inerter.inference.posterior.parameters import ParameterMap

FREE = ("b", "f1_0", "c_f1", "f2_0", "c_f2", "c_n", "k_n", "c_B", "k_B")


def _physical():
    p = paper_parameters("A3")
    return {n: getattr(p, n) for n in FREE}


@pytest.mark.parametrize("split,modal", [(True, True), (True, False), (False, True), (False, False)])
def test_round_trip(split, modal):
    pm = ParameterMap(split=split, modal=modal, m_B=27.6)
    phys = _physical()
    sampled = pm.sampled(phys)
    names = pm.sampled_names(FREE)
    back = pm.physical({n: sampled[n] for n in names})
    for n in FREE:
        assert back[n] == pytest.approx(phys[n], rel=1e-12)


def test_names_and_the_damping_ratio():
    pm = ParameterMap(split=True, modal=True, m_B=27.6)
    assert pm.sampled_names(FREE) == ["b", "f_0", "f_share", "c_f", "c_share", "c_n", "k_n", "zeta_B", "k_B"]
    phys = {"c_B": 2 * 0.03 * math.sqrt(6.4e7 * 27.6), "k_B": 6.4e7}
    assert pm.sampled(phys)["zeta_B"] == pytest.approx(0.03)


def test_arrays_of_draws():
    pm = ParameterMap(split=True, modal=True, m_B=2.0)
    vals = {"f_0": np.array([10.0, 20.0]), "f_share": np.array([0.25, 0.5]), "c_f": np.array([4.0, 8.0]),
            "c_share": np.array([0.5, 0.75]), "zeta_B": np.array([0.01, 0.02]), "k_B": np.array([8.0, 2.0])}
    out = pm.physical(vals)
    np.testing.assert_allclose(out["f1_0"], [2.5, 10.0])
    np.testing.assert_allclose(out["c_f2"], [2.0, 2.0])
    np.testing.assert_allclose(out["c_B"], [2 * 0.01 * 4.0, 2 * 0.02 * 2.0])
