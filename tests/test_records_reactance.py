"""A record's reactance over its resistance at the drive (records.reactance)."""

import math

import numpy as np
import pytest

from bayes_inerter import paper_parameters
from bayes_inerter.records import Record, generate_record
from bayes_inerter.records.reactance import DriveImpedance, drive_impedance

FREQ = 1.0
W = 2 * math.pi * FREQ


def _record(force_of, x0=0.01, fs=1000.0, seconds=6.0):
    t = np.arange(0.0, seconds, 1 / fs)
    x = x0 * np.sin(W * t)
    v = x0 * W * np.cos(W * t)
    a = -x0 * W ** 2 * np.sin(W * t)
    return Record(t, force_of(x, v, a), a, x, {"drive_frequency_hz": FREQ})


def test_an_inerter_a_damper_and_coulomb_friction_give_their_own_mass_and_damping():
    inerter = drive_impedance(_record(lambda x, v, a: 3000.0 * a))
    assert inerter.mass == pytest.approx(3000.0, rel=1e-9) and abs(inerter.damping) < 1e-6
    assert inerter.ratio > 1e6
    damper = drive_impedance(_record(lambda x, v, a: 500.0 * v))
    assert damper.damping == pytest.approx(500.0, rel=1e-9) and abs(damper.mass) < 1e-6
    # a Coulomb force's fundamental is 4 f_0 / pi in phase with the velocity
    both = drive_impedance(_record(lambda x, v, a: 3000.0 * a + 200.0 * np.sign(v)))
    velocity = 0.01 * W
    assert both.damping == pytest.approx(4 * 200.0 / (math.pi * velocity), rel=2e-3)
    assert both.mass == pytest.approx(3000.0, rel=2e-3)
    assert both.ratio == pytest.approx(W * both.mass / both.damping)
    assert both.as_dict()["ratio"] == both.ratio


def test_a_generated_record_reads_near_its_inertance_and_falls_with_the_drive():
    p = paper_parameters("A3")
    got = [drive_impedance(generate_record(p, f, rng=2, setting_name="A3")) for f in (0.5, 1.5)]
    assert all(abs(g.mass / p.b - 1.0) < 0.05 for g in got)  # the apparent mass: b, the plate's mass and the nut
    assert got[0].ratio < got[1].ratio  # friction weighs more at the slower drive


def test_no_damping_means_an_unbounded_ratio_and_too_short_a_record_is_refused():
    assert DriveImpedance(1.0, 10.0, 0.0).ratio == math.inf
    with pytest.raises(ValueError, match="steady drive periods"):
        drive_impedance(_record(lambda x, v, a: 3000.0 * a, seconds=1.5))
