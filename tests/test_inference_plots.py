"""A posterior's figures draw into the axes or figure they are given and return it."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from bayes_inerter.inference.plots import plot_bands, plot_corner, plot_phi, plot_trace  # noqa: E402

NAMES = ["b", "f_0", "f_share", "sigma", "rho"]


@pytest.fixture
def draws():
    rng = np.random.default_rng(3)
    n = 400
    return np.column_stack([rng.normal(750.0, 2.0, n), np.exp(rng.normal(5.0, 0.1, n)), rng.uniform(0.2, 0.8, n),
                            np.exp(rng.normal(-5.0, 0.1, n)), rng.uniform(0.5, 0.9, n)])


def _texts(fig):
    return [(ax.get_xlabel(), ax.get_ylabel(), ax.get_title()) for ax in fig.axes]


def test_corner_draws_into_the_given_figure(draws):
    fig = plt.figure(figsize=(7, 7))
    got = plot_corner(draws, NAMES, truths=[750.0, None, None, None, None], title="given", fig=fig)
    own = plot_corner(draws, NAMES, truths=[750.0, None, None, None, None], title="given")
    assert got is fig and len(fig.axes) == len(NAMES) ** 2
    assert _texts(fig) == _texts(own)  # the same panels and labels as on a figure of its own
    assert fig.axes[-1].get_xlabel() == "rho"
    plt.close(fig), plt.close(own)


def test_bands_draw_into_the_given_figure():
    rng = np.random.default_rng(4)
    t = np.linspace(0.0, 4.0, 2001)
    measured = np.sin(2 * np.pi * t) + 0.01 * rng.normal(size=t.size)
    sims = np.sin(2 * np.pi * t)[None, :] * (1 + 0.01 * rng.normal(size=(20, 1)))
    fig = plt.figure()
    got = plot_bands(t, measured, sims, freq=1.0, noise_sd=0.01, title="given", fig=fig)
    assert got is fig and len(fig.axes) == 3
    top, mid, zoom = fig.axes
    assert top.get_title() == "given" and zoom.get_xlabel() == "time (s)"
    assert [line.get_label() for line in top.lines] == ["measured", "posterior median"]
    assert len(mid.collections) == 3  # predictive, 94 % and 50 % bands
    plt.close(fig)


def test_trace_draws_into_the_given_figure():
    theta = np.log(np.random.default_rng(5).uniform(1.0, 2.0, size=(6, 30, len(NAMES))))
    fig = plt.figure()
    got = plot_trace(theta, NAMES, burn=10, thin=2, fig=fig)
    assert got is fig and len(fig.axes) == len(NAMES)
    assert all(len(ax.lines) == 6 for ax in fig.axes)  # one line per walker
    assert fig.axes[0].get_ylabel() == "b [kg]"
    np.testing.assert_array_equal(fig.axes[0].lines[0].get_xdata(), 10 + 2 * np.arange(30))
    plt.close(fig)


def test_phi_draws_into_the_given_axes():
    phi = np.random.default_rng(6).normal(0.95, 0.001, size=(4, 100))
    fig, (left, right) = plt.subplots(1, 2)
    got = plot_phi(phi, paper=0.93, title="given", ax=right)
    assert got is fig
    assert len(right.patches) == 50 and not left.patches  # the histogram's bars, in the given axes only
    assert right.get_title() == "given" and right.get_xlabel() == "fit accuracy φ (%), low-passed"
    assert right.get_legend().get_texts()[0].get_text() == "paper: 93.0%"
    plt.close(fig)
