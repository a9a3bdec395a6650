import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bayes_inerter.friction import STRIBECK_SEGMENTS, Coulomb, PiecewiseLinear, Smooth, Stribeck, make_law, stribeck_knots

finite = st.floats(0.0, 1e4, allow_nan=False)
speeds = st.floats(-10.0, 10.0, allow_nan=False)


def laws():
    coulomb = st.builds(Coulomb, finite, finite)
    stribeck = st.builds(
        lambda fc, extra, vs, c: Stribeck(fc, fc + extra, vs, c),
        finite, finite, st.floats(1e-4, 1.0), finite,
    )
    smooth = st.builds(
        lambda fc, extra, vb, c: Smooth(fc + extra, fc, vb, c),
        finite, finite, st.floats(1e-4, 1.0), finite,
    )
    piecewise = st.builds(lambda law, pieces: law.piecewise(pieces), stribeck, st.integers(2, 6))
    return st.one_of(coulomb, stribeck, smooth, piecewise)


@settings(max_examples=200, deadline=None)
@given(laws(), speeds)
def test_laws_are_odd_dissipative_and_finite(law, v):
    f = law.force(v)
    assert np.isfinite(f)
    assert f * v >= 0  # friction never feeds energy in
    assert law.force(-v) == pytest.approx(-f, abs=1e-9 * (1 + abs(f)))
    fr, slope = law.regularized(v, 1e-4)
    assert np.isfinite(fr) and np.isfinite(slope)


@settings(max_examples=100, deadline=None)
@given(laws(), st.floats(-0.05, 0.05), st.floats(1e-5, 1e-3))
def test_regularized_slope_is_the_derivative(law, v, v_eps):
    dv = 1e-9
    f_plus, _ = law.regularized(v + dv, v_eps)
    f_minus, _ = law.regularized(v - dv, v_eps)
    _, slope = law.regularized(v, v_eps)
    numeric = (f_plus - f_minus) / (2 * dv)
    # the central difference carries rounding of order eps |f| / dv: 1.8e-3 for a 4.5 kN
    # force (a fresh clone's hypothesis run found it), beyond the fixed 1e-3
    rounding = 4 * np.finfo(float).eps * max(abs(f_plus), abs(f_minus)) / (2 * dv)
    assert slope == pytest.approx(numeric, rel=1e-4, abs=1e-3 * (1 + abs(slope)) + rounding)


def test_regularized_coulomb_tends_to_sign():
    law = Coulomb(10.0, 2.0)
    v = np.array([-0.1, -1e-3, 1e-3, 0.1])
    f, _ = law.regularized(v, 1e-7)
    np.testing.assert_allclose(f, law.force(v), rtol=1e-12)


def test_smooth_law_formula():
    law = Smooth(f_brk=12.0, f_c=10.0, v_brk=0.01, c=3.0)
    v = 0.004
    v_st, v_coul = 0.01 * np.sqrt(2), 0.001
    expected = (
        np.sqrt(2 * np.e) * 2.0 * np.exp(-((v / v_st) ** 2)) * v / v_st
        + 10.0 * np.tanh(v / v_coul)
        + 3.0 * v
    )
    assert law.force(v) == pytest.approx(expected)
    # the Simscape law peaks at the break-away force near v_brk (for small viscous part)
    v = np.linspace(1e-4, 0.05, 20001)
    peak = Smooth(12.0, 10.0, 0.01, 0.0).force(v).max()
    assert peak == pytest.approx(12.0, rel=0.02)


def test_stribeck_levels():
    law = Stribeck(f_c=10.0, f_s=13.0, v_s=0.01, c=0.0)
    assert law.bound == 13.0
    assert law.force(1e-9) == pytest.approx(13.0)
    assert law.force(1.0) == pytest.approx(10.0)


def test_bounds_and_linear_parts():
    assert Coulomb(5.0, 1.0).bound == 5.0 and Coulomb(5.0, 1.0).is_coulomb
    assert Smooth(5.0, 5.0, 1e-3, 1.0).bound == 0.0
    assert Stribeck(5.0, 6.0, 1e-2, 2.0).without_coulomb() == Coulomb(0.0, 2.0)


@pytest.mark.parametrize(
    "build, message",
    [
        (lambda: Coulomb(-1.0, 0.0), "f0 must be non-negative"),
        (lambda: Coulomb(float("nan"), 0.0), "f0 must be finite"),
        (lambda: Stribeck(10.0, 5.0, 0.01), "f_s"),
        (lambda: Stribeck(10.0, 12.0, 0.0), "v_s must be positive"),
        (lambda: Smooth(1.0, 2.0, 0.01), "f_brk"),
        (lambda: make_law("dahl", 1.0, 0.0), "unknown friction law 'dahl'"),
        (lambda: PiecewiseLinear((0.0, 0.1), (1.0,)), "as many forces as speeds"),
        (lambda: PiecewiseLinear((0.1,), (1.0,)), "start at 0 and increase"),
        (lambda: PiecewiseLinear((0.0, 0.2, 0.1), (1.0, 1.0, 1.0)), "start at 0 and increase"),
        (lambda: PiecewiseLinear((0.0,), (-1.0,)), "forces must be non-negative"),
        (lambda: PiecewiseLinear((0.0,), (2.0,), f_s=1.0), "f_s"),
        (lambda: Stribeck(10.0, 12.0, 0.01).piecewise(9), "segments must be 2 to 8"),
    ],
)
def test_bad_laws(build, message):
    with pytest.raises(ValueError, match=message):
        build()


def test_make_law():
    assert make_law("coulomb", 3.0, 1.0) == Coulomb(3.0, 1.0)
    assert make_law("stribeck", 3.0, 1.0).bound == pytest.approx(3.9)
    assert isinstance(make_law("smooth", 3.0, 1.0), Smooth)


def test_piecewise_linear_pieces_are_continuous_and_coulomb_is_one_piece():
    law = PiecewiseLinear((0.0, 0.01, 0.03), (13.0, 11.0, 10.0), c=2.0, f_s=14.0)
    speeds, a, slopes = law.segments()
    for i in range(len(speeds) - 1):
        assert a[i] + slopes[i] * speeds[i + 1] == pytest.approx(a[i + 1] + slopes[i + 1] * speeds[i + 1])
    assert slopes[-1] == 2.0 and law.bound == 14.0 and law.viscous == 2.0
    v = np.array([-0.5, -0.02, -1e-6, 1e-6, 0.005, 0.02, 0.5])
    np.testing.assert_allclose(law.force(v), np.sign(v) * np.interp(np.abs(v), [0, 0.01, 0.03, 1.0],
                                                                    [13.0, 11.0, 10.0, 10.0 + 2.0 * 0.97]))
    coulomb = Coulomb(5.0, 1.5)
    assert coulomb.piecewise() == PiecewiseLinear((0.0,), (5.0,), 1.5, 5.0)
    np.testing.assert_allclose(coulomb.piecewise().force(v), coulomb.force(v))
    np.testing.assert_allclose(coulomb.piecewise().regularized(v, 1e-4), coulomb.regularized(v, 1e-4))
    assert Smooth(5.0, 5.0, 1e-3).piecewise() is None


@pytest.mark.parametrize("pieces, within", [(4, 0.027), (6, 0.015)])
def test_stribeck_in_pieces_stays_near_the_law(pieces, within):
    """The documented deviations (delta = 2): 4 pieces within 2.7 %, 6 within 1.5 % of
    f_s - f_c; the knots on the law but the last, where the Coulomb level takes over."""
    law = Stribeck(f_c=100.0, f_s=130.0, v_s=0.01, c=5.0)
    form = law.piecewise(pieces)
    assert len(form.speeds) == pieces and form.f_s == 130.0 and form.c == 5.0
    assert form.forces[0] == pytest.approx(130.0)
    np.testing.assert_allclose(form.forces[:-1], law.force(np.array(form.speeds[:-1]) + 1e-300)[:], rtol=1e-12)
    assert form.forces[-1] == pytest.approx(100.0 + 5.0 * form.speeds[-1])
    v = np.linspace(1e-7, 0.1, 100001)
    deviation = np.max(np.abs(form.force(v) - law.force(v))) / 30.0
    assert deviation <= within
    assert deviation == pytest.approx(stribeck_knots(2.0, pieces)[1], rel=0.02)
    assert law.piecewise() == law.piecewise(STRIBECK_SEGMENTS) and STRIBECK_SEGMENTS == 4
    assert Stribeck(100.0, 100.0, 0.01).piecewise() == PiecewiseLinear((0.0,), (100.0,), 0.0, 100.0)


def test_laws_on_one_node_add_up():
    laws = [Coulomb(3.0, 1.0), Stribeck(10.0, 13.0, 0.01, 2.0).piecewise(3), PiecewiseLinear((0.0, 0.05), (1.0, 2.0))]
    total = PiecewiseLinear.total(laws)
    v = np.linspace(1e-6, 0.2, 2001)
    np.testing.assert_allclose(total.force(v), sum(law.force(v) for law in laws), rtol=1e-12)
    assert total.f_s == pytest.approx(3.0 + 13.0 + 1.0) and total.c == pytest.approx(3.0)
    assert PiecewiseLinear.total([Coulomb(1.0), Smooth(1.0, 1.0, 1e-3)]) is None
