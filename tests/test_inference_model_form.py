"""b with a model-form error drawn after the likelihood (inference.summaries.model_form)."""

import math

import numpy as np
import pytest

from bayes_inerter.inference.summaries.model_form import ModelFormError, accel_amplitude
from bayes_inerter.records.record import Record


def _sine_record(amplitude=0.4, freq=1.0, fs=1000.0, seconds=10.0):
    t = np.arange(int(seconds * fs) + 1) / fs
    w = 2 * math.pi * freq
    env = np.clip(t / 2.0, 0, 1)  # ramped in, as the paper's tests are
    accel = amplitude * np.sin(w * t + 0.3) * env
    return Record(t, 3000.0 * accel, accel, disp=-accel / w**2, metadata={"drive_frequency_hz": freq})


def test_the_sd_adds_the_friction_share_over_the_inertial_force_in_quadrature():
    form = ModelFormError(sd=0.003, friction=0.01)
    b, f_0, a = np.array([1000.0, 4000.0]), np.array([400.0, 400.0]), 0.2
    expected = np.sqrt(0.003**2 + (0.01 * f_0 / (b * a)) ** 2)  # 0.01 * 400 / 200 = 2 % for the lighter b
    np.testing.assert_allclose(form.relative_sd(b, f_0, a), expected)
    assert ModelFormError(sd=0.003, friction=0.0).relative_sd(b, f_0, a) == pytest.approx([0.003, 0.003])


def test_the_draws_keep_bs_centre_and_spread_it_by_the_law():
    """Each draw of b times e^eps: the median of log b stays (eps is centred) and the sd of
    log(b_device / b) is the law's."""
    rng = np.random.default_rng(3)
    b = np.full(200_000, 2000.0)
    f_0 = np.full(b.shape, 300.0)
    form = ModelFormError(sd=0.0025, friction=0.005)
    got = form.draws(b, f_0, 0.1, rng)
    eps = np.log(got / b)
    sd = math.hypot(0.0025, 0.005 * 300.0 / (2000.0 * 0.1))
    assert np.median(eps) == pytest.approx(0.0, abs=3 * sd / math.sqrt(len(b)) * 1.26)
    assert np.std(eps) == pytest.approx(sd, rel=0.01)
    again = form.draws(b, f_0, 0.1, np.random.default_rng(3))
    np.testing.assert_array_equal(got, again)  # the generator given decides the draws


@pytest.mark.parametrize("bad", [-0.01, 1.0, float("nan"), True])
def test_the_error_refuses_what_is_not_a_share(bad):
    with pytest.raises(ValueError, match="must be a share"):
        ModelFormError(sd=bad)
    with pytest.raises(ValueError, match="must be a share"):
        ModelFormError(friction=bad)


def test_the_accelerations_amplitude_is_read_at_the_drive_over_the_steady_periods():
    rec = _sine_record(amplitude=0.4)
    assert accel_amplitude(rec) == pytest.approx(0.4, rel=1e-3)
    with pytest.raises(ValueError, match="amplitude"):
        ModelFormError().relative_sd(1000.0, 100.0, 0.0)
