"""Symbolic parameters (``network.symbolic``): linear forms that add and scale, refuse
the rest, and compile through the blocks."""

import numpy as np
import pytest

from bayes_inerter.network import Deformation, Friction, Inerter, Mass, cascade, compile_network
from bayes_inerter.network.symbolic import Linear, SymbolicCoulomb, coefficients, symbols


def test_forms_add_scale_and_evaluate():
    x = symbols(("a", "b", "c"))
    form = 2.0 * x["a"] + x["b"] * 0.5 - x["c"] / 4 + 3.0
    assert form((1.0, 2.0, 4.0)) == 2.0 + 1.0 - 1.0 + 3.0
    assert (0 + x["a"]) == x["a"] and sum([x["a"], x["b"]]) == x["a"] + x["b"]
    assert (x["a"] - x["a"]).is_zero() and not x["a"].is_zero()
    assert repr(form) == "2 a + 0.5 b + -0.25 c + 3"


@pytest.mark.parametrize("op", [lambda a, b: a * b, lambda a, b: a / b, lambda a, b: float(a),
                                lambda a, b: a <= 0, lambda a, b: a > b])
def test_what_is_not_linear_or_needs_a_number_is_refused(op):
    x = symbols(("a", "b"))
    with pytest.raises(TypeError):
        op(x["a"], x["b"])


def test_forms_over_other_names_do_not_mix():
    with pytest.raises(TypeError, match="different names"):
        symbols(("a",))["a"] + symbols(("b",))["b"]
    with pytest.raises(ValueError, match="as many coefficients"):
        Linear(("a", "b"), [1.0])


def test_a_network_compiles_into_forms_whose_values_are_the_numeric_compile():
    names = ("m", "b", "c", "k", "f0", "cv")
    x = symbols(names)

    def network(p, law):
        return cascade(Mass(p["m"]), Friction(law(p["f0"], p["cv"])), Deformation(p["c"], p["k"]),
                       Mass(2.0 * p["m"]), Inerter(p["b"]), Friction(law(0.5 * p["f0"], p["cv"])))

    sym = compile_network(network(x, SymbolicCoulomb))
    values = np.array([3.0, 700.0, 50.0, 1e6, 120.0, 40.0])
    from bayes_inerter.friction import Coulomb

    num = compile_network(network(dict(zip(names, values)), Coulomb))
    coef, const = coefficients(sym.masses, names)
    np.testing.assert_array_equal(coef @ values + const, num.masses)
    bounds, _ = coefficients([sum(law.bound for law in node) for node in sym.laws], names)
    np.testing.assert_array_equal(bounds @ values, num.coulomb_bounds)
    assert sym.all_coulomb and num.masses.tolist() == [3.0, 706.0]
