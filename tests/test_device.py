import dataclasses
import math

import numpy as np
import pytest

from bayes_inerter import SETTINGS, Geometry, paper_parameters, theoretical_inertance
from bayes_inerter.device import DEFAULT_GEOMETRY, FREQUENCIES_HZ, SCREW_MASS, TABLE_I, apparent_inertance


def test_theoretical_inertance_matches_paper_end_points():
    assert theoretical_inertance("A0") == pytest.approx(474.7, abs=0.05)
    assert theoretical_inertance("B2") == pytest.approx(23261.4, abs=0.05)


def test_geometry_implied_by_paper_is_physical():
    # the two published figures fix lead and screw inertia; both must be plausible
    assert DEFAULT_GEOMETRY.lead == pytest.approx(0.01984, rel=1e-3)
    assert DEFAULT_GEOMETRY.screw_radius(SCREW_MASS) == pytest.approx(0.0248, rel=2e-3)


def test_flywheel_increments():
    g = DEFAULT_GEOMETRY
    assert g.inertance(1, 0) - g.inertance(0, 0) == pytest.approx(947.8, abs=0.1)
    assert g.inertance(0, 1) - g.inertance(0, 0) == pytest.approx(11393.4, abs=0.1)
    # A_k is linear in the number of small flywheels
    for k in range(1, 7):
        expected = theoretical_inertance("A0") + k * (g.J_small * g.gain)
        assert theoretical_inertance(f"A{k}") == pytest.approx(expected, rel=1e-12)


def test_inertance_scales_with_inverse_square_lead():
    g = Geometry(lead=0.02, J_screw=0.005)
    g2 = dataclasses.replace(g, lead=0.04)
    assert g2.inertance(2, 1) == pytest.approx(g.inertance(2, 1) / 4)
    assert g.inertance(0, 0) == pytest.approx(0.005 * (2 * math.pi / 0.02) ** 2)


def test_paper_parameters_fields():
    p = paper_parameters("A1")
    assert (p.b, p.m_s, p.m_B) == (1668.9, 17.5, 57.2)
    assert (p.c_n, p.k_n, p.c_B, p.k_B) == (2165100.0, 434960.0, 1.0026, 64015000.0)
    assert (p.f1_0, p.c_f1, p.f2_0, p.c_f2) == (731.66, 0.02752, 2.778, 1574.7)
    assert set(SETTINGS) == {"A0", "A1", "A2", "A3", "A4", "A5", "A6", "B1", "B2"}
    assert paper_parameters("b2").b == 20287.0


def test_unknown_setting():
    with pytest.raises(ValueError, match="unknown flywheel setting 'C1'"):
        paper_parameters("C1")
    with pytest.raises(ValueError, match="unknown flywheel setting"):
        theoretical_inertance("A7")


@pytest.mark.parametrize(
    "field, value, message",
    [
        ("b", 0.0, "b must be positive"),
        ("m_B", -1.0, "m_B must be positive"),
        ("m_s", float("nan"), "m_s must be finite"),
        ("k_n", -5.0, "k_n must be non-negative"),
        ("f1_0", -1.0, "f1_0 must be non-negative"),
        ("c_f2", float("inf"), "c_f2 must be finite"),
        ("c_B", "x", "c_B must be a number"),
    ],
)
def test_bad_parameters(field, value, message):
    with pytest.raises(ValueError, match=message):
        dataclasses.replace(paper_parameters("A0"), **{field: value})


def test_parameters_are_frozen():
    p = paper_parameters("A0")
    with pytest.raises(dataclasses.FrozenInstanceError):
        p.b = 1.0


# b_app holds where the nut's spring is small beside its damper, k_n / (omega c_n) << 1:
# 0.06 at 0.5 Hz for Table I's k_n, 0.15 for 1e6 N/m (at 1e7 N/m, 0.7, it does not hold)
@pytest.mark.parametrize("k_n", [TABLE_I["k_n"], 1e6])
@pytest.mark.parametrize("name", ["A0", "A3", "B2"])
def test_apparent_inertance_is_what_the_nut_and_inerter_show_together(name, k_n):
    from bayes_inerter.network import cascade
    from bayes_inerter.network.blocks import Deformation, Inerter
    from bayes_inerter.network.twoport import accel_response

    b, c_n = SETTINGS[name].b_paper, TABLE_I["c_n"]
    omega = 2 * np.pi * np.array(FREQUENCIES_HZ)
    accel = accel_response(cascade(Deformation(c_n, k_n), Inerter(b)), omega)
    mobility = accel / (1j * omega)  # v / F of the nut in series with the inerter
    seen = -1.0 / (omega * mobility.imag)  # the inertance of the mobility's 1 / s part
    app = apparent_inertance(b, k_n, c_n)
    # the nut's compliance makes the pair look heavier than b, and b_app says by how much
    assert np.all(seen > b)
    # to first order in k_n / (omega c_n): the neglected part is its square, 0.02 at 1e6
    np.testing.assert_allclose(app - b, seen - b, rtol=0.03)
    np.testing.assert_allclose(app, seen, rtol=1e-4)


def test_a_record_named_setting_colon_frequency_is_read_and_a_bad_one_refused():
    from bayes_inerter.device import setting_and_frequency

    assert setting_and_frequency("a3:1") == ("A3", 1.0) and setting_and_frequency("B2:1.5") == ("B2", 1.5)
    for bad in ("A3", "A3:x", ":1", "A3:0", "A3:1:2"):
        with pytest.raises(ValueError, match="SETTING:FREQUENCY"):
            setting_and_frequency(bad)
