"""The sensors' calibration: the scale invariance it rests on, and its arithmetic."""

import dataclasses
import math

import numpy as np
import pytest

from bayes_inerter import paper_parameters, simulate
from bayes_inerter.records.generator import GeneratorSettings, generate_record
from bayes_inerter.records.sensitivity import SensorCalibration

G_F, G_A = 1.012, 0.993  # a load cell reading 1.2 % high, an accelerometer 0.7 % low


def _drive():
    t = np.arange(3001) / 1000.0
    return t, 1500.0 * np.sin(2 * np.pi * t) + 400.0 * np.sin(2 * np.pi * 3.1 * t)


def test_a_miscalibrated_record_is_what_a_scaled_device_gives():
    """Masses, inertance, viscous coefficients, stiffnesses and dampings scaled by
    s = g_F / g_a and Coulomb forces by g_F: the device turns the load cell's reading
    into the accelerometer's exactly, Coulomb switches included, so no record can tell
    s from 1."""
    p = paper_parameters("A3")
    t, f = _drive()
    a = simulate(p, t, f, sampling="mean")
    s = G_F / G_A
    scaled = dataclasses.replace(p, **{k: v * (G_F if k in ("f1_0", "f2_0") else s) for k, v in p.as_dict().items()})
    a_read = simulate(scaled, t, G_F * f, sampling="mean")
    assert np.max(np.abs(a)) > 1.0
    np.testing.assert_allclose(a_read, G_A * a, rtol=0, atol=1e-9 * np.max(np.abs(a)))


def test_with_masses_held_the_rigid_inertance_absorbs_the_scale():
    """The likelihood holds m_s and m_B: in the rigid model the miscalibrated record is
    then fitted exactly by b_id = s (m + b) - m (the module's formula, inverted)."""
    p = paper_parameters("A1")
    t, f = _drive()
    a = simulate(p, t, f, network="rigid")
    s, m = G_F / G_A, p.m_s + p.m_B
    fitted = dataclasses.replace(p, b=s * (m + p.b) - m, f1_0=G_F * p.f1_0, c_f1=s * p.c_f1, f2_0=G_F * p.f2_0,
                                 c_f2=s * p.c_f2)
    a_read = simulate(fitted, t, G_F * f, network="rigid")
    np.testing.assert_allclose(a_read, G_A * a, rtol=0, atol=1e-9 * np.max(np.abs(a)))
    # and the formula of the module gives b back from b_id with r = g_a / g_F = 1 / s
    assert (1 / s) * (fitted.b + m) - m == pytest.approx(p.b, rel=1e-12)


def test_the_generator_applies_the_gains_to_its_sensors():
    quiet = dict(force_noise=0.0, accel_noise=0.0, disp_noise=0.0, duration=1.0, ramp=0.5)
    plain = generate_record(paper_parameters("A0"), 1.0, settings=GeneratorSettings(**quiet))
    off = generate_record(paper_parameters("A0"), 1.0,
                          settings=GeneratorSettings(**quiet, force_gain=G_F, accel_gain=G_A))
    np.testing.assert_allclose(off.force, G_F * plain.force, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(off.accel, G_A * plain.accel, rtol=1e-12, atol=1e-12)
    np.testing.assert_array_equal(off.disp, plain.disp)
    assert off.metadata["generator"]["force_gain"] == G_F
    with pytest.raises(ValueError, match="force_gain"):
        GeneratorSettings(force_gain=0.0)


def test_calibration_adds_its_share_in_quadrature():
    cal = SensorCalibration(force=0.003, accel=0.004)
    assert cal.ratio_sd == pytest.approx(0.005)
    # b_id 3000 kg with sd 4 kg, moving mass 100 kg: (3100 * 0.005) = 15.5 kg added in quadrature
    assert cal.inertance_sd(3000.0, 4.0, 100.0) == pytest.approx(math.hypot(4.0, 15.5))
    assert SensorCalibration(0.0, 0.0).inertance_sd(3000.0, 4.0, 100.0) == pytest.approx(4.0)
    assert cal.as_dict() == {"force": 0.003, "accel": 0.004}
    # an unknown sd or moving mass gives an unknown total, not an error at the end of a long study
    assert math.isnan(cal.inertance_sd(3000.0, math.nan, 100.0)) and math.isnan(cal.inertance_sd(3000.0, 4.0, math.nan))
    with pytest.raises(ValueError, match="non-negative"):
        cal.inertance_sd(3000.0, -1.0)


@pytest.mark.parametrize("bad", [-0.01, 0.5, math.nan, "1 %"])
def test_calibration_refuses_what_is_not_a_small_fraction(bad):
    with pytest.raises(ValueError, match="sensitivity uncertainty"):
        SensorCalibration(force=bad)
