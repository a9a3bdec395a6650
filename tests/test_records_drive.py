"""The drive frequency: the option, the metadata, or the record's own estimate."""

import dataclasses

import numpy as np
import pytest

from bayes_inerter import paper_parameters
from bayes_inerter.records import GeneratorSettings, Record, generate_record
from bayes_inerter.records.checks import drive_frequency
from bayes_inerter.records.drive import SOURCE_KEY, estimate_drive_frequency, resolve_drive, with_drive


def _bare(rec, disp=True):
    return Record(rec.time, rec.force, rec.accel, rec.disp if disp else None, {})


@pytest.mark.parametrize("freq", [0.5, 1.0, 1.5])
def test_estimate_is_the_drive_despite_the_ramp(freq):
    # the generator's 10 s records start with a 2 s ramp, which pulls the spectral peak
    # (0.8 % at 0.5 Hz); the steady part's harmonic least squares does not feel it
    rec = generate_record(paper_parameters("A3"), freq, rng=3, setting_name="A3")
    with_disp = estimate_drive_frequency(_bare(rec))
    from_accel = estimate_drive_frequency(_bare(rec, disp=False))
    assert with_disp.hz == pytest.approx(freq, rel=1e-5)
    assert from_accel.hz == pytest.approx(freq, rel=1e-3)
    assert with_disp.resolution_hz == pytest.approx(1 / (2 * rec.duration))
    assert "estimated" in with_disp.source


def test_estimate_of_a_record_without_a_ramp_and_off_the_grid():
    rec = generate_record(paper_parameters("A0"), 2.7, settings=GeneratorSettings(ramp=0.0), rng=4,
                          setting_name="A0")
    assert estimate_drive_frequency(_bare(rec)).hz == pytest.approx(2.7, rel=1e-4)


def test_precedence_option_then_metadata_then_estimate():
    rec = generate_record(paper_parameters("A3"), 1.0, rng=3, setting_name="A3")
    assert resolve_drive(rec).source == "record metadata drive_frequency_hz"
    assert resolve_drive(rec).hz == 1.0
    given = resolve_drive(rec, 1.02)
    assert (given.hz, given.source) == (1.02, "option --freq")
    est = resolve_drive(_bare(rec))
    assert est.hz == pytest.approx(1.0, rel=1e-5) and est.hz != 1.0
    # the checks and the sampler's coordinates see the same number
    assert drive_frequency(_bare(rec)) == est.hz
    from bayes_inerter.inference.sampling.coordinates import drive_omega

    assert drive_omega(_bare(rec)) == pytest.approx(2 * np.pi * est.hz, rel=1e-15)


def test_with_drive_writes_it_and_its_source_into_the_metadata():
    rec = _bare(generate_record(paper_parameters("A3"), 1.0, rng=3, setting_name="A3"))
    drive = resolve_drive(rec)
    settled = with_drive(rec, drive)
    assert settled.drive_frequency == drive.hz and settled.metadata[SOURCE_KEY] == drive.source
    assert resolve_drive(settled) == drive  # read back, not estimated again
    assert with_drive(settled, drive) is settled
    assert rec.metadata == {}  # the original is left as it was


@pytest.mark.parametrize("bad", [0.0, -1.0, float("nan"), True])
def test_bad_option_refused(bad):
    rec = generate_record(paper_parameters("A3"), 1.0, settings=GeneratorSettings(duration=3.0, ramp=0.5), rng=3)
    with pytest.raises(ValueError, match="positive number of Hz"):
        resolve_drive(rec, bad)


def test_a_record_with_no_drive_is_refused_with_the_fix():
    t = np.arange(2001) / 1000.0
    rec = Record(t, np.full_like(t, 3.0), np.zeros_like(t), None, {})
    with pytest.raises(ValueError, match="--freq"):
        estimate_drive_frequency(rec)


def test_the_model_settles_it_once():
    from bayes_inerter.inference.posterior.model import PosteriorModel

    # 4 s: three steady drive periods after the first, as the default likelihood needs
    rec = generate_record(paper_parameters("A3"), 1.5, settings=GeneratorSettings(duration=4.0, ramp=0.5), rng=3,
                          setting_name="A3")
    bare = dataclasses.replace(rec, metadata={"setting": "A3"})
    pm = PosteriorModel(bare)
    assert pm.drive.hz == pytest.approx(1.5, rel=1e-4)
    assert pm.record.drive_frequency == pm.drive.hz
