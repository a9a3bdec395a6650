import dataclasses

import numpy as np
import pytest
from conftest import with_backlash
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy import signal
from scipy.linalg import expm

from bayes_inerter import SimulationError, paper_parameters, simulate, simulate_network
from bayes_inerter.simulate._kernel._compiled import levels, tables
from bayes_inerter.friction import make_law, stribeck_knots
from bayes_inerter.networks import NETWORKS, build_network
from bayes_inerter.network import accel_response, compile_network
from bayes_inerter.simulate import Drive, mean_acceleration
from bayes_inerter.simulate.reference import (hybrid_reference, hybrid_reference_rich, inverse_dynamics_force,
                                              moreau_reference)


def rel_error(a, ref):
    """Relative L2 error normalised as in the paper's eq. (5)."""
    return np.linalg.norm(a - ref) / np.linalg.norm(ref - ref.mean())


@pytest.mark.parametrize(
    "setting, freq, network",
    [pytest.param("A0", 0.5, "reduced", marks=pytest.mark.slow), pytest.param("B2", 1.5, "reduced", marks=pytest.mark.slow),
     pytest.param("A3", 1.0, "full", marks=pytest.mark.slow), ("A2", 1.0, "rigid")],
)
def test_matches_independent_hybrid_reference(setting, freq, network):
    p = paper_parameters(setting)
    t, f = inverse_dynamics_force(p, freq, duration=1.6, ramp=0.4)
    a = simulate(p, t, f, network=network)
    ref = hybrid_reference(compile_network(build_network(network, p)), t, f)
    assert rel_error(a, ref) < 1e-3


@pytest.mark.slow  # 8 s; the hybrid-reference tests check sticking in the quick subset
def test_stick_slip_record_sticks():
    # A0 at 0.5 Hz: the plate's Coulomb friction dominates, the plate stops at reversals
    p = paper_parameters("A0")
    t, f = inverse_dynamics_force(p, 0.5, duration=3.0, ramp=0.5)
    f = 0.9 * f  # less force than the friction needs at times: stick phases
    a = simulate(p, t, f)
    stuck = np.mean(a == 0.0)
    assert 0.1 < stuck < 0.9
    ref = hybrid_reference(compile_network(build_network("reduced", p)), t[:1200], f[:1200])
    assert rel_error(a[:1200], ref) < 1e-3


@pytest.mark.slow
def test_moreau_stepping_converges_to_kernel():
    """Halving-free first-order scheme: error falls about tenfold per tenfold step."""
    p = paper_parameters("A1")
    t, f = inverse_dynamics_force(p, 1.0, duration=1.5, ramp=0.5)
    a = simulate(p, t, f)
    c = compile_network(build_network("reduced", p))
    errors = [rel_error(a, moreau_reference(c, t, f, r)) for r in (100, 1000)]
    assert errors[1] < errors[0] / 5
    assert errors[1] < 0.05


def test_refining_the_record_changes_nothing():
    """Upsampling the (linearly interpolated) force must give the same trajectory."""
    p = paper_parameters("A1")
    t, f = inverse_dynamics_force(p, 1.0, duration=2.0)
    a = simulate(p, t, f)
    t10 = np.linspace(t[0], t[-1], 10 * (len(t) - 1) + 1)
    a10 = simulate(p, t10, np.interp(t10, t, f))[::10]
    assert rel_error(a10, a) < 1e-6


def test_mean_sampling_is_the_mean_of_the_acceleration():
    """"mean" equals the average of the instantaneous acceleration over [t - h, t + h],
    computed independently from a 64 times finer simulation of the same trajectory, on
    a stick-slip record where the acceleration jumps at every switch."""
    p = paper_parameters("A0")
    t, f = inverse_dynamics_force(p, 0.5, duration=2.5, ramp=0.5)
    f = 0.9 * f
    mean = simulate(p, t, f, sampling="mean")
    q = 64
    tq = np.linspace(t[0], t[-1], q * (len(t) - 1) + 1)
    aq = simulate(p, tq, np.interp(tq, t, f))
    # trapezoid over the 2q fine intervals around each interior sample, divided by 2h
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (aq[1:] + aq[:-1]))]) / q
    k = np.arange(1, len(t) - 1)
    ref = (cum[(k + 1) * q] - cum[(k - 1) * q]) / 2
    assert rel_error(mean[1:-1], ref) < 1e-3
    # the instantaneous samples are not this mean: the jumps at the switches differ
    assert rel_error(simulate(p, t, f)[1:-1], ref) > 10 * rel_error(mean[1:-1], ref)


def test_mean_sampling_is_continuous_in_the_parameters():
    """On a generated record, low-passed as the likelihood does: a tenfold smaller change
    of the plate's Coulomb force changes the "mean" output tenfold less (Lipschitz) down
    to 1e-7; the instantaneous output does not, since it jumps when a switch crosses a
    sample instant (what made the likelihood rough)."""
    from bayes_inerter.records import GeneratorSettings, generate_record, lowpass

    p = paper_parameters("A1")
    rec = generate_record(p, 1.0, rng=0, settings=GeneratorSettings(duration=4.0, ramp=1.0))

    def change(eps, sampling):
        a0 = simulate(p, rec.time, rec.force, sampling=sampling)
        a1 = simulate(dataclasses.replace(p, f1_0=p.f1_0 * (1 + eps)), rec.time, rec.force, sampling=sampling)
        return np.max(np.abs(lowpass(a1 - a0, rec.fs)))

    def ratios(sampling):
        return [change(10 * eps, sampling) / change(eps, sampling) for eps in (1e-7, 1e-6, 1e-5, 1e-4)]

    mean = ratios("mean")
    assert all(8 < r < 12 for r in mean), mean
    assert max(ratios("instant")) > 15
    with pytest.raises(ValueError, match="sampling"):
        simulate(p, rec.time, rec.force, sampling="average")


@pytest.mark.parametrize("setting", ["A0", "B2"])
def test_linear_part_is_exact(setting):
    """Without contacts the kernel equals scipy's first-order-hold discretisation."""
    p = dataclasses.replace(paper_parameters(setting), f1_0=0.0, f2_0=0.0)
    t, f = inverse_dynamics_force(p, 1.5, duration=2.0)
    f = f * np.clip(t / 0.05, 0, 1)  # start from zero force: scipy's foh state is then rest
    A, B = compile_network(build_network("reduced", p)).state_space()
    h = t[1] - t[0]
    C, D = A[:1], B[:1].reshape(1, 1)
    Ad, Bd, Cd, Dd, _ = signal.cont2discrete((A, B.reshape(-1, 1), C, D), h, method="foh")
    _, y, _ = signal.dlsim((Ad, Bd, Cd, Dd, h), f)
    a = simulate(p, t, f)
    assert rel_error(a, y.ravel()) < 1e-6


def test_tables_match_scipy_expm():
    p = paper_parameters("A1")
    A, _ = compile_network(build_network("reduced", p)).state_space()
    h = 1e-3
    J = levels(A, h)
    F = tables(A, h, J)
    for j in (0, 3, 10, J):
        E = expm(A * h / 2**j)
        np.testing.assert_allclose(F[j] + np.eye(len(A)), E, rtol=1e-9, atol=1e-12)


@pytest.mark.parametrize("name", sorted(NETWORKS))
def test_chirp_spectrum_matches_cascade(name):
    """With Coulomb terms off, the simulated chirp's spectrum is the cascade's a/F."""
    p = dataclasses.replace(paper_parameters("A2"), f1_0=0.0, f2_0=0.0)
    net = build_network(name, p)
    fs, T = 10_000.0, 8.0
    t = np.arange(int(2 * T * fs)) / fs
    f = np.where(t < T, signal.chirp(t, 0.5, T, 400.0, method="logarithmic"), 0.0) * 100.0
    f *= signal.windows.tukey(len(t), 0.02)
    a = simulate_network(net, t, f)
    freqs = np.fft.rfftfreq(len(t), 1 / fs)
    empirical = np.fft.rfft(a) / np.fft.rfft(f)
    band = (freqs > 2.0) & (freqs < 300.0)
    model = accel_response(net, 2 * np.pi * freqs[band])
    err = np.abs(empirical[band] - model) / np.abs(model)
    assert np.median(err) < 0.01
    assert np.percentile(err, 95) < 0.03


bad_inputs = [
    (lambda t, f: (t, f[:-1]), "force has shape"),
    (lambda t, f: (t, np.where(np.arange(len(f)) == 7, np.nan, f)), "force has a NaN.*index 7"),
    (lambda t, f: (t, np.where(np.arange(len(f)) == 3, np.inf, f)), "force has a NaN or infinite"),
    (lambda t, f: (np.where(np.arange(len(t)) == 5, np.nan, t), f), "time has a NaN"),
    (lambda t, f: (t[::-1], f), "strictly increasing"),
    (lambda t, f: (np.r_[t[:10], t[9], t[11:]], f), "strictly increasing; it is not at index 10"),
    (lambda t, f: (t * (1 + 0.2 * (np.arange(len(t)) > 50)), f), "uniformly sampled"),
    (lambda t, f: (t[:1], f[:1]), "at least 2 samples"),
    (lambda t, f: (t.reshape(-1, 1), f), "one-dimensional"),
]


@pytest.mark.parametrize("make, message", bad_inputs)
def test_bad_records(make, message):
    p = paper_parameters("A1")
    t, f = inverse_dynamics_force(p, 1.0, duration=0.2)
    t2, f2 = make(t, f)
    with pytest.raises(ValueError, match=message):
        simulate(p, t2, f2)


def test_a_drive_checked_once_gives_the_same_simulation():
    p = paper_parameters("A3")
    t, f = inverse_dynamics_force(p, 1.0, duration=0.6, ramp=0.2)
    drive = Drive.of(t, f)
    assert drive.h == pytest.approx(t[1] - t[0])
    for sampling in ("instant", "mean"):
        np.testing.assert_array_equal(simulate(p, drive, sampling=sampling), simulate(p, t, f, sampling=sampling))
    with pytest.raises(ValueError, match="not both"):
        simulate(p, drive, f)
    with pytest.raises(ValueError, match="force record is missing"):
        simulate(p, t)
    with pytest.raises(ValueError, match="strictly increasing"):
        Drive.of(t[::-1], f)


def test_mean_acceleration_is_numpys_gradient():
    v = np.random.default_rng(3).normal(size=101).cumsum()
    for x in (v, v[:2], v[:3]):
        np.testing.assert_array_equal(mean_acceleration(x, 1e-3), np.gradient(x, 1e-3))


def test_bad_options():
    p = paper_parameters("A1")
    t, f = inverse_dynamics_force(p, 1.0, duration=0.2)
    with pytest.raises(ValueError, match="unknown network"):
        simulate(p, t, f, network="fig9")
    with pytest.raises(ValueError, match="unknown friction law"):
        simulate(p, t, f, friction="dahl")
    with pytest.raises(ValueError, match="unknown method"):
        simulate(p, t, f, method="euler")
    with pytest.raises(ValueError, match="exact kernel needs Coulomb"):
        simulate(p, t, f, friction="smooth", method="exact")
    with pytest.raises(ValueError, match="params must be InerterParameters"):
        simulate({"b": 1.0}, t, f)
    with pytest.raises(ValueError, match="initial state must have shape"):
        simulate(p, t, f, x0=np.zeros(3))


@pytest.mark.slow
def test_the_smooth_law_uses_the_stiff_solver():
    p = paper_parameters("A2")
    t, f = inverse_dynamics_force(p, 1.0, duration=0.6, ramp=0.2)
    exact = simulate(p, t, f)
    # a smooth law with a narrow tanh is close to set-valued Coulomb
    smooth = simulate(p, t, f, friction="smooth")
    assert np.all(np.isfinite(smooth))
    assert rel_error(smooth, exact) < 0.1
    np.testing.assert_array_equal(smooth, simulate(p, t, f, friction="smooth", method="stiff"))
    stribeck = simulate(p, t, f, friction="stribeck")
    assert np.all(np.isfinite(stribeck))


def test_stribeck_and_backlash_take_the_exact_kernel():
    """By default Stribeck friction runs as its piecewise-linear form on the exact kernel,
    and so does a network with backlash; the stiff solver remains an option. (Stribeck on
    the rigid network and the dead zone on the linear one: the shapes the quick subset's
    reference tests compile.)"""
    p = paper_parameters("A2")
    t, f = inverse_dynamics_force(p, 1.0, duration=0.6, ramp=0.2)
    stribeck = simulate(p, t, f, network="rigid", friction="stribeck")
    pieces = simulate(p, t, f, network="rigid", friction=lambda f0, c: make_law("stribeck", f0, c).piecewise())
    np.testing.assert_array_equal(stribeck, pieces)
    np.testing.assert_array_equal(stribeck, simulate(p, t, f, network="rigid", friction="stribeck", method="exact"))
    assert rel_error(stribeck, simulate(p, t, f, network="rigid")) > 1e-3  # the break-away shows
    net = with_backlash(build_network("linear", p), 2e-5)
    a = simulate_network(net, t, f)
    np.testing.assert_array_equal(a, simulate_network(net, t, f, method="exact"))
    assert np.all(np.isfinite(a)) and rel_error(a, simulate(p, t, f, network="linear")) > 1e-3  # the gap shows


@pytest.mark.parametrize(
    "network, setting, friction, gap, scale",
    [("rigid", "A2", "stribeck", 0.0, 1.3),
     pytest.param("reduced", "A3", "coulomb", 2e-5, 1.0, marks=pytest.mark.slow),
     pytest.param("reduced", "A1", "stribeck", 2e-5, 1.0, marks=pytest.mark.slow)],
)
def test_piecewise_laws_and_backlash_match_an_independent_hybrid_reference(network, setting, friction, gap, scale):
    """Stribeck in 4 pieces and a 20 um dead zone in the nut link, against scipy's Radau in
    each mode with scipy's event location (``reference.hybrid_reference_rich``)."""
    p = paper_parameters(setting)
    t, f = inverse_dynamics_force(p, 1.0, duration=1.0 if gap else 1.6, ramp=0.4)
    net = build_network(network, p, friction)
    compiled = compile_network(with_backlash(net, gap) if gap else net)
    a = simulate_network(compiled, t, scale * f)
    ref = hybrid_reference_rich(compiled, t, scale * f)
    assert rel_error(a, ref) < 1e-3
    assert 0.0 < np.mean(a == 0.0) < 0.5  # stuck at the start, then sliding


@pytest.mark.slow  # 5 s; the hybrid-reference tests check the Stribeck law in the quick subset
def test_stribeck_in_pieces_follows_the_law_as_its_approximation_says():
    """Through the stiff solver (the same regularisation for both), the 4-piece form and
    Stribeck's law itself give accelerations that differ by less than the pieces' force
    error allows: at most e (f_s - f_c) at each contact (e = 0.0265, ``stribeck_knots``),
    here on one rigid body of mass M, so about e (f_s - f_c) / M against the
    acceleration's spread (4.5e-3 on this record; measured: 1.3e-3)."""
    p = paper_parameters("A2")
    t, f = inverse_dynamics_force(p, 1.0, duration=1.0, ramp=0.4)
    f = 1.3 * f  # past the static bounds: the contacts slide through the fall at every reversal
    smooth = simulate(p, t, f, network="rigid", friction="stribeck", method="stiff")
    pieces = simulate(p, t, f, network="rigid", friction=lambda f0, c: make_law("stribeck", f0, c).piecewise(),
                      method="stiff")
    fall = 0.3 * (p.f1_0 + p.f2_0)  # f_s - f_c of both contacts (make_law's ratio 1.3)
    bound = stribeck_knots(2.0, 4)[1] * fall / (p.m_B + p.m_s + p.b) / np.std(smooth)
    assert 1e-4 < rel_error(pieces, smooth) < bound


@pytest.mark.slow
def test_regularised_solver_converges_to_exact_kernel():
    p = paper_parameters("A1")
    t, f = inverse_dynamics_force(p, 1.0, duration=1.5, ramp=0.5)
    exact = simulate(p, t, f)
    errs = [rel_error(simulate(p, t, f, method="stiff", v_eps=v), exact) for v in (1e-3, 1e-5)]
    assert errs[1] < errs[0] / 3


#: The wide draws of ``test_output_is_finite_over_wide_parameters``.
WIDE = st.fixed_dictionaries(
    {
        "b": st.floats(10.0, 5e4), "m_s": st.floats(1.0, 100.0),
        "m_B": st.floats(1.0, 200.0), "c_n": st.floats(0.0, 1e8),
        "k_n": st.floats(1e3, 1e9), "c_B": st.floats(0.0, 1e6),
        "k_B": st.floats(1e4, 1e10), "f1_0": st.floats(0.0, 5e3),
        "c_f1": st.floats(0.0, 1e4), "f2_0": st.floats(0.0, 5e3),
        "c_f2": st.floats(0.0, 1e4),
    }
)


@pytest.mark.slow  # 16 s: the stiff solver on extreme draws; the quick subset keeps the kernel's own sweeps
def test_output_is_finite_over_wide_parameters():
    """Every draw either simulates to finite accelerations or is refused (SimulationError:
    the contacts chatter), and most simulate: a check that every draw skipped would pass
    having checked nothing."""
    simulated = {}

    @settings(max_examples=8, deadline=None)
    @given(st.sampled_from(sorted(NETWORKS)), WIDE, st.floats(0.2, 3.0))
    def finite_or_refused(name, values, freq):
        key = (name, tuple(sorted(values.items())), freq)
        p = dataclasses.replace(paper_parameters("A0"), **values)
        t, f = inverse_dynamics_force(paper_parameters("A3"), freq, duration=0.5, ramp=0.2)
        try:
            a = simulate(p, t, f, network=name)
        except SimulationError:
            simulated[key] = False  # reported chatter is a clear outcome, not a silent one
            return
        assert np.all(np.isfinite(a))
        simulated[key] = True

    finite_or_refused()
    assert sum(simulated.values()) >= len(simulated) / 2, simulated


def test_an_exact_runner_is_run_exact_with_the_network_fixed():
    """``exact_runner`` forms the network once; each call is ``run_exact``'s, bit for bit,
    and keeps no state between calls (the motion-in likelihood's drivetrain, a period at a
    time)."""
    from bayes_inerter.simulate import exact_runner, run_exact

    b, m_s, c_n, k_n, c_B, k_B, c_f2 = 3000.0, 20.0, 5e5, 2e6, 50.0, 6e7, 200.0
    A = np.array([[-(c_B + c_n) / m_s, c_n / m_s, -k_n / m_s, k_B / m_s], [c_n / b, -(c_n + c_f2) / b, k_n / b, 0.0],
                  [1.0, -1.0, 0.0, 0.0], [-1.0, 0.0, 0.0, 0.0]])
    B = np.array([[c_B / m_s], [0.0], [0.0], [1.0]])
    h = 1e-3
    t = np.arange(2001) * h
    u = (0.06 * np.cos(2 * np.pi * t)).reshape(-1, 1)  # a plate velocity, m/s
    args = (A, B, np.array([1]), np.array([2000.0]), np.array([b]))  # f2_0 2 kN: the rotation sticks at reversals
    run = exact_runner(*args, h)
    first = run(u, store=True)
    whole = run_exact(*args, u, h, store=True)
    assert np.array_equal(first[0], whole[0]) and np.array_equal(first[1], whole[1])
    v_th = first[1][:, 1]
    assert np.sum(np.diff(v_th) == 0.0) > 10 and np.ptp(v_th) > 0.01  # the rotation sticks at times, and slides
    again = run(u[1000:], x0=first[1][1000], store=True)
    assert np.array_equal(again[1], run_exact(*args, u[1000:], h, x0=first[1][1000], store=True)[1])
    assert np.array_equal(run(u, store=True)[1], first[1])  # no state kept between calls
