"""Physical-sense checks: records of a simple rigid device (mass, Coulomb and viscous
friction, driven in displacement) pass; the same records scaled, swapped or clipped are
refused by the check that should see it, naming the cause."""

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings, strategies as st

from bayes_inerter.records import Record
from bayes_inerter.records.checks import (
    B_RANGE, CHECKS, RecordCheckError, check_record, drive_frequency, fundamental, require_physical,
)

M_B, M_S = 57.2, 21.7


def rigid_record(b=3000.0, freq=1.0, f0=700.0, c=1500.0, amplitude=0.01, fs=1000.0, duration=4.0, seed=0,
                 disp=True, metadata=True):
    """A displacement-driven rigid device: F = (m_B + m_s + b) a + f0 sgn(v) + c v, with
    a few N and mm/s^2 of noise. Independent of the package's simulator."""
    rng = np.random.default_rng(seed)
    t = np.arange(int(duration * fs) + 1) / fs
    w = 2 * math.pi * freq
    x = amplitude * np.sin(w * t)
    v = amplitude * w * np.cos(w * t)
    a = -w * w * x
    force = (M_B + M_S + b) * a + f0 * np.tanh(v / 1e-3) + c * v + rng.normal(0, 2.0, t.size)
    accel = a + rng.normal(0, 0.01, t.size)
    meta = {"drive_frequency_hz": freq, "m_s": M_S, "m_B": M_B} if metadata else {}
    return Record(time=t, force=force, accel=accel, disp=x + rng.normal(0, 1e-6, t.size) if disp else None,
                  metadata=meta)


def first_check(rec, **kw):
    found = check_record(rec, m_s=M_S, m_B=M_B, **kw)
    return found[0] if found else None


devices = st.fixed_dictionaries({
    "b": st.floats(300.0, 30000.0), "freq": st.sampled_from([0.5, 1.0, 1.5]),
    "f0": st.floats(5.0, 1500.0), "c": st.floats(0.0, 3000.0), "seed": st.integers(0, 2**16),
    "disp": st.booleans(), "metadata": st.booleans(),
})
FAST = settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@FAST
@given(devices)
def test_records_of_a_device_within_the_priors_pass(device):
    assert check_record(rigid_record(**device), m_s=M_S, m_B=M_B) == []


def test_drive_frequency_found_without_metadata():
    rec = rigid_record(freq=1.5, metadata=False)
    assert drive_frequency(rec) == pytest.approx(1.5, rel=0.01)
    z = fundamental(rec.time, rec.force, 1.5) / fundamental(rec.time, rec.accel, 1.5)
    assert z.real == pytest.approx(M_B + M_S + 3000.0, rel=0.02)


MISTAKES = {
    # name: (how the file is wrong, the check that must see it, words of the cause)
    "force in kN": (lambda r: dataclasses.replace(r, force=r.force / 1000), "apparent-mass", "force in kN"),
    "force/accel swapped": (lambda r: dataclasses.replace(r, force=r.accel, accel=r.force), None,
                            "force and acceleration columns swapped"),
    "accel in mm/s^2": (lambda r: dataclasses.replace(r, accel=r.accel * 1000), None, "mm/s^2"),
    "accel sign": (lambda r: dataclasses.replace(r, accel=-r.accel), None, "acceleration's sign"),
    "time in ms": (lambda r: dataclasses.replace(r, time=r.time * 1000, metadata={}), "time-unit", "ms"),
}


@FAST
@given(devices, st.sampled_from(sorted(MISTAKES)))
def test_wrong_files_are_refused_naming_the_cause(device, mistake):
    make, check, words = MISTAKES[mistake]
    found = first_check(make(rigid_record(**device)))
    assert found is not None, mistake
    if check is not None:
        assert found.check == check
    assert words in found.message
    assert "\n" not in found.message


@FAST
@given(devices.filter(lambda d: d["disp"]), st.sampled_from(["swap", "disp mm", "accel g", "force-disp"]))
def test_acceleration_against_displacement(device, mistake):
    rec = rigid_record(**device)
    wrong = {"swap": dataclasses.replace(rec, accel=rec.disp, disp=rec.accel),
             "force-disp": dataclasses.replace(rec, force=rec.disp, disp=rec.force),
             "disp mm": dataclasses.replace(rec, disp=rec.disp * 1000),
             "accel g": dataclasses.replace(rec, accel=rec.accel / 9.80665)}[mistake]
    found = first_check(wrong)
    assert found is not None and found.check == "accel-vs-disp"
    words = {"swap": "acceleration and displacement columns swapped", "disp mm": "disp=mm",
             "force-disp": "force and displacement columns swapped",
             "accel g": "accel=g"}[mistake]
    assert words in found.message


@FAST
@given(devices, st.floats(0.3, 0.9), st.sampled_from(["force", "accel"]))
def test_clipped_channel_refused(device, level, channel):
    rec = rigid_record(**device)
    x = getattr(rec, channel)
    clipped = np.clip(x, -level * np.abs(x).max(), level * np.abs(x).max())
    found = first_check(dataclasses.replace(rec, **{channel: clipped}))
    assert found is not None and found.check == "clipped"
    assert ("force" if channel == "force" else "acceleration") in found.message


@pytest.mark.parametrize("channel", ["force", "accel"])
def test_dead_or_constant_channel_refused(channel):
    rec = rigid_record()
    noise = np.random.default_rng(1).normal(0, 1.0, rec.time.size)
    for dead in (np.full(rec.time.size, 3.0), noise):
        found = first_check(dataclasses.replace(rec, **{channel: dead}))
        assert found is not None and found.check == "flat"


def test_skip_names_a_check_and_require_physical_names_the_override():
    rec = rigid_record()
    wrong = dataclasses.replace(rec, force=rec.force / 1000)
    with pytest.raises(RecordCheckError, match=r"--skip-check apparent-mass\)$") as info:
        require_physical(wrong, m_s=M_S, m_B=M_B, where="run1.csv")
    assert str(info.value).startswith("run1.csv: ")
    require_physical(wrong, m_s=M_S, m_B=M_B, skip=("apparent-mass",))  # the user knows better
    with pytest.raises(ValueError, match="unknown check"):
        check_record(rec, skip=("units",))


def test_check_names_and_bounds_match_their_sources():
    from bayes_inerter.cli import RECORD_CHECKS
    from bayes_inerter.inference.posterior.priors import DEFAULT_PRIORS

    assert RECORD_CHECKS == CHECKS
    assert B_RANGE == (DEFAULT_PRIORS["b"].low, DEFAULT_PRIORS["b"].high)


def test_generated_records_pass(tmp_path):
    from bayes_inerter import paper_parameters
    from bayes_inerter.records import GeneratorSettings, generate_record

    for name, freq in (("A0", 0.5), ("B2", 1.5)):
        p = paper_parameters(name)
        rec = generate_record(p, freq, settings=GeneratorSettings(duration=2.0, ramp=0.5), rng=3, setting_name=name)
        assert check_record(rec, m_s=p.m_s, m_B=p.m_B) == []


@pytest.mark.parametrize("bits", [8, 10, 12, 16])
def test_a_quantised_record_without_noise_is_not_called_clipped(bits):
    # a DAQ's levels make many samples share the peak's value; only a pile-up is a rail
    rec = rigid_record(b=800.0, freq=0.5)
    a = -(2 * math.pi * 0.5) ** 2 * 0.01 * np.sin(2 * math.pi * 0.5 * rec.time)  # noise-free
    quiet = dataclasses.replace(rec, force=(M_B + M_S + 800.0) * a, accel=a, disp=None)
    for channel in ("force", "accel"):
        x = getattr(quiet, channel)
        q = (x.max() - x.min()) / 2**bits
        quantised = dataclasses.replace(quiet, **{channel: np.round(x / q) * q})
        found = check_record(quantised, m_s=M_S, m_B=M_B)
        assert all(f.check != "clipped" for f in found), (bits, channel, found)


def test_spikes_do_not_hide_the_drive():
    # impacts (a nut's backlash) put a few large spikes in the acceleration: its rms then
    # says little about the drive, its bulk still does
    rec = rigid_record(freq=0.5)
    accel = rec.accel.copy()
    accel[::250] += 40.0  # 40 m/s^2 spikes, four a second, against a 0.1 m/s^2 drive
    assert check_record(dataclasses.replace(rec, accel=accel), m_s=M_S, m_B=M_B) == []


def test_a_named_setting_narrows_b_and_sees_a_g_or_lbf_that_the_prior_allows():
    from bayes_inerter.device import SETTINGS
    from bayes_inerter.records.checks import EXPECTED_B_FACTOR, b_range_for

    b = SETTINGS["A3"].b_paper
    rec = dataclasses.replace(rigid_record(b=b, disp=False), metadata={"setting": "A3", "drive_frequency_hz": 1.0})
    narrow = b_range_for(rec)
    assert narrow == (b / EXPECTED_B_FACTOR, b * EXPECTED_B_FACTOR)
    assert check_record(rec, m_s=M_S, m_B=M_B, b_range=narrow) == []
    for wrong, words in ((dataclasses.replace(rec, accel=rec.accel / 9.80665), "acceleration in g"),
                         (dataclasses.replace(rec, force=rec.force / 4.4482216152605), "force in lbf")):
        assert check_record(wrong, m_s=M_S, m_B=M_B) == []  # the default prior's range cannot see it
        found = check_record(wrong, m_s=M_S, m_B=M_B, b_range=narrow)
        assert found and found[0].check == "apparent-mass" and words in found[0].message
    assert b_range_for(dataclasses.replace(rec, metadata={})) == B_RANGE
