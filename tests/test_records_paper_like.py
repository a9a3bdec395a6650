"""Tests of the paper-like device (bayes_inerter.records.paper_like)."""

import math

import numpy as np
import pytest

from bayes_inerter.device import paper_parameters
from bayes_inerter.records.generator import GeneratorSettings
from bayes_inerter.records.paper_like import PaperLike, laboratory, paper_like_record
from bayes_inerter.records.sensitivity import SensorCalibration


def test_each_draw_lies_in_its_ranges_and_the_seed_fixes_it():
    dev = PaperLike()
    draws = [dev.draw(np.random.default_rng(k)) for k in range(200)]
    for s in draws:
        assert s.network == "full" and s.friction == "stribeck" and s.noise_corner == dev.noise_corner
        assert dev.ratio[0] <= s.stribeck_ratio <= dev.ratio[1]
        assert dev.velocity[0] <= s.stribeck_velocity <= dev.velocity[1]
        assert dev.backlash[0] <= s.backlash <= dev.backlash[1]
    # the sensitivities scatter as their calibration says (200 draws: sd within 15 %)
    assert np.std([s.force_gain for s in draws]) == pytest.approx(dev.calibration.force, rel=0.15)
    assert np.std([s.accel_gain for s in draws]) == pytest.approx(dev.calibration.accel, rel=0.15)
    # log-uniform backlash: about half the draws below the geometric mean of the range
    mid = math.sqrt(dev.backlash[0] * dev.backlash[1])
    assert 0.4 < np.mean([s.backlash < mid for s in draws]) < 0.6
    assert dev.draw(np.random.default_rng(3)) == dev.draw(np.random.default_rng(3))


def test_exact_calibration_and_fixed_sizes_give_that_device():
    dev = PaperLike(ratio=(1.5, 1.5), velocity=(0.01, 0.01), backlash=(2e-5, 2e-5),
                    calibration=SensorCalibration(0.0, 0.0))
    s = dev.draw(np.random.default_rng(0))
    assert (s.stribeck_ratio, s.stribeck_velocity, s.backlash, s.force_gain, s.accel_gain) == pytest.approx(
        (1.5, 0.01, 2e-5, 1.0, 1.0))


@pytest.mark.parametrize("bad", [dict(ratio=(0.9, 1.5)), dict(velocity=(0.0, 0.1)), dict(backlash=(3e-5, 1e-5))])
def test_impossible_ranges_are_refused(bad):
    with pytest.raises(ValueError, match="paper-like"):
        PaperLike(**bad)


@pytest.mark.slow
def test_a_paper_like_record_keeps_the_papers_b_and_says_what_it_is():
    dev = PaperLike(base=GeneratorSettings(duration=1.5, ramp=0.5, oversample=12))  # above the 5 kHz sensor
    rec = paper_like_record("A1", 1.5, seed=2, device=dev)
    assert rec.metadata["truth"] == "paper-like" and rec.metadata["setting"] == "A1"
    assert rec.metadata["true_parameters"]["b"] == paper_parameters("A1").b
    assert rec.metadata["generator"]["friction"] == "stribeck" and rec.metadata["generator"]["network"] == "full"
    again = paper_like_record("A1", 1.5, seed=2, device=dev)
    np.testing.assert_array_equal(rec.accel, again.accel)
    # one seed, one laboratory: the same device at another frequency, with its own noise
    other = paper_like_record("A1", 1.0, seed=2, device=dev).metadata["generator"]
    lab = laboratory(2, device=dev)  # what a study reads to tell the sensors' share of an error
    for key in ("stribeck_ratio", "stribeck_velocity", "backlash", "force_gain", "accel_gain"):
        assert other[key] == rec.metadata["generator"][key] == getattr(lab, key)
    assert laboratory(3, device=dev).force_gain != lab.force_gain


def test_a_longer_record_is_the_same_laboratory_for_longer():
    dev = PaperLike(base=GeneratorSettings(duration=1.0, ramp=0.5, oversample=12))
    short = paper_like_record("A1", 1.5, seed=2, device=dev)
    longer = paper_like_record("A1", 1.5, seed=2, device=dev, duration=1.5)
    assert longer.time[-1] == pytest.approx(1.5) and short.time[-1] == pytest.approx(1.0)
    for key in ("stribeck_ratio", "backlash", "force_gain", "accel_gain"):
        assert longer.metadata["generator"][key] == short.metadata["generator"][key]
    assert longer.metadata["generator"]["duration"] == 1.5
    with pytest.raises(ValueError, match="ramp"):
        paper_like_record("A1", 1.5, seed=2, device=dev, duration=0.25)
