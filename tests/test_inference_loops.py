"""Force loops over a steady period (``inference.summaries.loops``) and their figure."""

import dataclasses
import math

import numpy as np
import pytest

from bayes_inerter import paper_parameters
from bayes_inerter.inference.posterior.likelihood import LikelihoodSettings
from bayes_inerter.inference.summaries.loops import period_loops
from bayes_inerter.inference.posterior.model import PosteriorModel
from bayes_inerter.inference.summaries.plots import plot_loops
from bayes_inerter.records import GeneratorSettings, generate_record

FREQ = 1.0


@pytest.fixture(scope="module")
def noise_free():
    """A noise-free generator record of A3 at 1 Hz and its model, the truth's theta."""
    p = paper_parameters("A3")
    settings = dataclasses.replace(GeneratorSettings(), force_noise=0.0, accel_noise=0.0, disp_noise=0.0, duration=8.0)
    rec = generate_record(p, FREQ, settings=settings, rng=np.random.default_rng(0), setting_name="A3")
    pm = PosteriorModel(rec)
    return pm, pm.to_theta(p)


def test_the_measured_loop_is_the_drive_and_the_model_at_the_truth_follows_it(noise_free):
    pm, truth = noise_free
    lp = period_loops(pm, [truth, truth])
    w = 2 * math.pi * FREQ
    amplitude = GeneratorSettings().amplitude
    # the plate follows the servo's sine: its displacement and velocity amplitudes are the drive's
    assert np.ptp(lp.displacement) / 2 == pytest.approx(amplitude, rel=0.01)
    assert np.ptp(lp.velocity) / 2 == pytest.approx(w * amplitude, rel=0.01)
    # a quarter period turns displacement into velocity (x = X sin, v = X w cos)
    quarter = len(lp.time) // 4
    assert np.corrcoef(np.roll(lp.displacement, -quarter), lp.velocity)[0, 1] > 0.99
    # the model of the record's own physics, at the truth, gives the measured force
    rms = np.sqrt(np.mean(lp.measured ** 2))
    miss = np.sqrt(np.mean((lp.predicted - lp.measured) ** 2, axis=1))
    assert lp.predicted.shape == (2, len(lp.time))
    assert np.all(miss < 0.01 * rms), (miss, rms)
    # and a wrong inertance does not
    wrong = truth.copy()
    wrong[pm.names.index("b")] += math.log(1.2)
    off = period_loops(pm, [wrong])
    assert np.sqrt(np.mean((off.predicted[0] - lp.measured) ** 2)) > 5 * miss.max()


def test_the_band_is_ordered_and_the_level_checked(noise_free):
    pm, truth = noise_free
    rng = np.random.default_rng(1)
    draws = truth + 0.01 * rng.standard_normal((20, len(truth)))
    lp = period_loops(pm, draws)
    lo, mid, hi = lp.band(0.94)
    assert np.all(lo <= mid) and np.all(mid <= hi) and np.any(hi > lo)
    with pytest.raises(ValueError, match="credible level"):
        lp.band(1.0)


def test_loops_need_the_motion_likelihood_and_a_usable_draw(noise_free):
    pm, truth = noise_free
    ar1 = PosteriorModel(pm.record, likelihood=LikelihoodSettings(residual="ar1"))
    with pytest.raises(ValueError, match="motion-in likelihood"):
        period_loops(ar1, [ar1.to_theta(paper_parameters("A3"))])
    bad = truth.copy()
    bad[pm.names.index("b")] = np.nan
    with pytest.raises(ValueError, match="no posterior draw"):
        period_loops(pm, [bad])


def test_the_figure_has_a_row_of_two_panels_per_record(noise_free):
    pm, truth = noise_free
    lp = period_loops(pm, [truth])
    fig = plot_loops([lp, lp], ["A3 1 Hz", "again"])
    assert len(fig.axes) == 4
    assert fig.axes[0].get_xlabel() == "displacement (mm)" and fig.axes[1].get_xlabel() == "velocity (mm/s)"
    assert len(fig.axes[0].collections) == 2  # the band along each half of the loop
    with pytest.raises(ValueError, match="one title per record"):
        plot_loops([lp], ["a", "b"])


@pytest.mark.slow  # 40 s: a joint fit's start search
def test_a_joint_fit_draws_the_loops_of_every_record(tmp_path):
    from bayes_inerter.inference.fit import fit_joint

    settings = GeneratorSettings(duration=5.5, ramp=0.5)  # three steady periods after the first
    recs = [generate_record(paper_parameters(s), f, settings=settings, rng=seed, setting_name=s)
            for s, f, seed in [("A0", 1.0, 5), ("A2", 1.5, 6)]]
    fit_joint(recs, tmp_path / "joint", steps=4, plots=True)
    assert (tmp_path / "joint" / "loops.png").stat().st_size > 10_000
