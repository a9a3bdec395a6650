import dataclasses

import numpy as np
import pytest

from bayes_inerter import paper_parameters, simulate
from bayes_inerter.network import accel_response
from bayes_inerter.networks import build_network
from bayes_inerter.records import GeneratorSettings, fit_accuracy, generate_record, lowpass, paper_grid
from bayes_inerter.records.generator import paper_record

QUIET = GeneratorSettings(force_noise=0.0, accel_noise=0.0, disp_noise=0.0)


@pytest.mark.parametrize("setting, freq", [("A0", 0.5), ("A1", 1.0), ("B2", 1.5)])
def test_generator_and_simulator_agree(setting, freq):
    """Driven by the record's force at the true parameters, the simulator reproduces the
    record's acceleration (phi > 0.95 after the matched low-pass), and b = truth is where
    phi peaks when b alone varies by 5 %."""
    p = paper_parameters(setting)
    rec = generate_record(p, freq, settings=QUIET)
    measured = lowpass(rec.accel, rec.fs)
    factors = [0.95, 0.975, 1.0, 1.025, 1.05]
    phis = [
        fit_accuracy(lowpass(simulate(dataclasses.replace(p, b=p.b * f), rec.time, rec.force), rec.fs), measured)
        for f in factors
    ]
    assert phis[2] > 0.95
    assert int(np.argmax(phis)) == 2


def test_linear_device_matches_frequency_response():
    """No friction: the steady state's a/F at the drive frequency is the cascade's."""
    p = dataclasses.replace(paper_parameters("A2"), f1_0=0.0, f2_0=0.0, c_f1=0.0, c_f2=0.0)
    freq = 1.5
    rec = generate_record(p, freq, settings=QUIET)
    steady = rec.time >= rec.time[-1] - 4 / freq  # whole cycles at the end
    t = rec.time[steady]
    basis = np.exp(-2j * np.pi * freq * t)
    a_coef = np.sum(rec.accel[steady] * basis)
    f_coef = np.sum(rec.force[steady] * basis)
    model = accel_response(build_network("reduced", p), [2 * np.pi * freq])[0]
    assert abs(a_coef / f_coef - model) / abs(model) < 0.01
    x_amp = 2 * abs(np.sum(rec.disp[steady] * basis)) / steady.sum()
    assert x_amp == pytest.approx(QUIET.amplitude, rel=0.01)


def test_record_starts_at_rest_and_reaches_amplitude():
    rec = generate_record(paper_parameters("A3"), 1.0, settings=QUIET)
    assert abs(rec.disp[0]) < 1e-7 and abs(rec.force[0]) < 1.0
    assert np.max(np.abs(rec.disp)) == pytest.approx(0.01, rel=0.02)
    assert rec.fs == pytest.approx(1000.0)
    assert len(rec.time) == 10001


def test_same_seed_same_record():
    p = paper_parameters("A1")
    s = GeneratorSettings(duration=2.0, ramp=0.5)
    a = generate_record(p, 1.0, settings=s, rng=7)
    b = generate_record(p, 1.0, settings=s, rng=np.random.default_rng(7))
    c = generate_record(p, 1.0, settings=s, rng=8)
    np.testing.assert_array_equal(a.force, b.force)
    np.testing.assert_array_equal(a.accel, b.accel)
    assert not np.array_equal(a.accel, c.accel)


def test_noise_sizes_are_as_set():
    p = paper_parameters("A1")
    s = GeneratorSettings(duration=2.0, ramp=0.5)
    noisy = generate_record(p, 1.0, settings=s, rng=3)
    clean = generate_record(p, 1.0, settings=dataclasses.replace(s, force_noise=0, accel_noise=0, disp_noise=0))
    assert np.std(noisy.force - clean.force) == pytest.approx(2.0, rel=0.05)
    assert np.std(noisy.accel - clean.accel) == pytest.approx(0.01, rel=0.05)


def test_coloured_noise_keeps_its_rms_and_is_correlated():
    """noise_corner colours the sensor noise: same rms as white, lag-1 correlation near
    the low-pass's (about 0.99 for 20 Hz at 1 kHz), against about 0 for white noise."""
    p = paper_parameters("A1")
    s = GeneratorSettings(duration=9.0, ramp=0.5, force_noise=0, disp_noise=0)
    clean = generate_record(p, 1.0, settings=dataclasses.replace(s, accel_noise=0))
    white = generate_record(p, 1.0, settings=s, rng=3).accel - clean.accel
    coloured = generate_record(p, 1.0, settings=dataclasses.replace(s, noise_corner=20.0), rng=3).accel - clean.accel
    lag1 = [np.corrcoef(e[1:], e[:-1])[0, 1] for e in (white, coloured)]
    assert abs(lag1[0]) < 0.05 and lag1[1] > 0.95
    assert np.std(white) == pytest.approx(0.01, rel=0.05)
    assert np.std(coloured) == pytest.approx(0.01, rel=0.3)  # few correlation times: a looser bound


@pytest.mark.parametrize("antialias", ["fir", "none"])
@pytest.mark.parametrize("piece_s", [0.05, 0.7, 3.0])
def test_pieces_give_the_same_record_bit_for_bit(antialias, piece_s):
    """Long records are made piece by piece to bound memory: any piece length gives
    exactly the one-pass numbers, including 3 s, which leaves a last piece of one fine
    sample (a 2.5 s record and its 0.5 s tail are 60,001 samples at 20 kHz)."""
    from bayes_inerter.records.generator import _record_signals

    s = GeneratorSettings(duration=2.5, ramp=0.5, antialias=antialias, force_noise=0, accel_noise=0, disp_noise=0)
    p = paper_parameters("A2")
    one = _record_signals(p, 1.5, s, chunk_s=1e3)
    many = _record_signals(p, 1.5, s, chunk_s=piece_s)
    assert len(one[0]) == int(round(s.duration * s.fs)) + 1
    for x, y in zip(one, many):
        np.testing.assert_array_equal(x, y)


def test_a_sensors_delay_shifts_its_channel_alone():
    """A 2 ms load-cell delay (two record samples) moves the force by exactly two samples,
    in one pass and piece by piece, and leaves the acceleration as it was."""
    from bayes_inerter.records.generator import _record_signals

    s = GeneratorSettings(duration=2.5, ramp=0.5, force_noise=0, accel_noise=0, disp_noise=0)
    p = paper_parameters("A2")
    plain = _record_signals(p, 1.5, s, chunk_s=1e3)
    late = dataclasses.replace(s, force_delay=2e-3)
    one = _record_signals(p, 1.5, late, chunk_s=1e3)
    many = _record_signals(p, 1.5, late, chunk_s=0.05)
    np.testing.assert_array_equal(one[0], many[0])
    np.testing.assert_allclose(one[0][100:], plain[0][98:-2], rtol=0, atol=1e-9 * np.max(np.abs(plain[0])))
    assert np.max(np.abs(one[0][100:] - plain[0][100:])) > 1.0  # N: the shift is there
    np.testing.assert_array_equal(one[1], plain[1])


def test_naive_sampling_is_worse():
    """MODEL.md section 7: instantaneous sampling gives records the model fits worse
    (after the matched low-pass, at the true parameters)."""
    p = paper_parameters("A3")
    fir = generate_record(p, 1.0, settings=QUIET)
    naive = generate_record(p, 1.0, settings=dataclasses.replace(QUIET, antialias="none"))
    phi = [
        fit_accuracy(lowpass(simulate(p, r.time, r.force), r.fs), lowpass(r.accel, r.fs))
        for r in (fir, naive)
    ]
    assert phi[1] < phi[0]


def test_metadata_holds_truth_and_settings():
    p = paper_parameters("B1")
    rec = generate_record(p, 0.5, settings=QUIET, setting_name="B1")
    m = rec.metadata
    assert m["setting"] == "B1" and m["m_s"] == 22.8 and m["drive_frequency_hz"] == 0.5
    assert m["true_parameters"]["b"] == 10468.0
    assert m["generator"]["k_p"] == 5e7 and m["generator"]["antialias"] == "fir"


@pytest.mark.slow
@pytest.mark.parametrize(
    "options",
    [dict(friction="stribeck"), dict(network="full"), dict(backlash=2e-5), dict(friction="smooth")],
)
def test_richer_truths(options):
    p = paper_parameters("A3")
    s = dataclasses.replace(QUIET, duration=0.8, ramp=0.3, **options)
    rec = generate_record(p, 1.5, settings=s)
    assert np.all(np.isfinite(rec.accel)) and np.all(np.isfinite(rec.force))
    base = generate_record(p, 1.5, settings=dataclasses.replace(QUIET, duration=0.8, ramp=0.3))
    assert not np.allclose(rec.accel, base.accel)  # the option changes the device


def test_paper_grid_spawns_independent_records():
    s = GeneratorSettings(duration=0.5, ramp=0.2)
    grid = list(paper_grid(settings=s, seed=1, names=("A0", "B2")))
    assert [(n, f) for n, f, _ in grid] == [(n, f) for n in ("A0", "B2") for f in (0.5, 1.0, 1.5)]
    again = list(paper_grid(settings=s, seed=1, names=("A0", "B2")))
    np.testing.assert_array_equal(grid[4][2].accel, again[4][2].accel)
    assert grid[0][2].metadata["true_parameters"]["b"] == 753.34
    alone = paper_record("B2", 1.0, settings=s, seed=1, names=("A0", "B2"))  # one record, made alone
    np.testing.assert_array_equal(grid[4][2].accel, alone.accel)
    with pytest.raises(ValueError, match="no setting 'C9'"):
        paper_record("C9", 1.0)


@pytest.mark.parametrize(
    "kwargs, message",
    [
        (dict(amplitude=-1.0), "amplitude must be positive"),
        (dict(fs=float("nan")), "fs must be positive"),
        (dict(force_noise=-2.0), "force_noise must be non-negative"),
        (dict(oversample=2), "oversample >= 4"),
        (dict(antialias="iir"), "antialias must be"),
        (dict(ramp=20.0), "ramp"),
        (dict(network="linear"), "truth network"),
        (dict(accel_bandwidth=50_000.0), "below the internal Nyquist"),
        (dict(noise_corner=600.0), "noise_corner must lie between"),
        (dict(accel_delay=-1e-4), "accel_delay must be non-negative"),
    ],
)
def test_bad_generator_settings(kwargs, message):
    with pytest.raises(ValueError, match=message):
        GeneratorSettings(**kwargs)


def test_bad_generator_calls():
    p = paper_parameters("A0")
    with pytest.raises(ValueError, match="needs rng"):
        generate_record(p, 1.0)
    with pytest.raises(ValueError, match="drive frequency must be positive"):
        generate_record(p, -1.0, settings=QUIET)
    with pytest.raises(ValueError, match="too high"):
        generate_record(p, 200.0, settings=QUIET)
