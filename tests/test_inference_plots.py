"""A posterior's figures draw into the axes or figure they are given and return it."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from bayes_inerter.inference.summaries.plots import plot_bands, plot_corner, plot_phi, plot_trace  # noqa: E402

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


def _vertical(ax) -> set:
    """x of the axes' vertical lines (two equal x's), rounded."""
    return {round(float(ln.get_xdata()[0]), 6) for ln in ax.lines
            if len(ln.get_xdata()) == 2 and ln.get_xdata()[0] == ln.get_xdata()[1]}


def _horizontal(ax) -> set:
    return {round(float(ln.get_ydata()[0]), 6) for ln in ax.lines
            if len(ln.get_ydata()) == 2 and ln.get_ydata()[0] == ln.get_ydata()[1]}


def test_corner_marks_the_reported_interval_and_the_theory_on_b(draws):
    names = ["f_0", "b", "sigma"]  # b not first: its column and its row both have 2-D panels
    values = draws[:, [1, 0, 3]]
    fig = plot_corner(values, names, truths=[None, 750.0, None], paper=[None, 753.34, None],
                      title="A3_1Hz.csv: two-port model", interval=(738.0, 760.0), theory=752.5)
    axes = np.asarray(fig.axes).reshape(3, 3)
    hist, below, left = axes[1, 1], axes[2, 1], axes[1, 0]
    for ax in (hist, below):
        assert {738.0, 760.0, 752.5} <= _vertical(ax)
    assert {738.0, 760.0, 752.5} <= _horizontal(left)
    assert not {738.0, 760.0} & (_vertical(axes[0, 0]) | _vertical(axes[2, 2]))  # only b's panels
    shaded = [p for p in hist.patches if p.get_facecolor()[:3] == pytest.approx(matplotlib.colors.to_rgb("tab:orange"))]
    assert len(shaded) == 1 and shaded[0].get_x() == pytest.approx(738.0)
    # the panels hold the interval, wider than the draws (about 750 +- 6)
    for ax in (hist, below):
        lo, hi = ax.get_xlim()
        assert lo < 738.0 and hi > 760.0
    assert left.get_ylim()[0] < 738.0 and left.get_ylim()[1] > 760.0
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    assert [t.split(":")[0] for t in legend] == ["truth", "paper", "reported 94 % interval",
                                                 "theoretical b (device file)"]
    assert "738 to 760 kg" in legend[2] and "752.5 kg" in legend[3] and "off the panels" not in legend[3]
    assert fig._suptitle.get_text() == "A3_1Hz.csv: two-port model"
    plt.close(fig)


def test_corner_says_when_the_theory_is_off_the_panels(draws):
    fig = plot_corner(draws, NAMES, interval=(745.0, 755.0), theory=474.7, title="t")
    hist = fig.axes[0]
    assert 474.7 in _vertical(hist) and hist.get_xlim()[0] > 700  # marked, but the panel is not widened to it
    legend = [t.get_text() for t in fig.legends[0].get_texts()]
    assert legend[-1] == "theoretical b (device file): 474.7 kg (off the panels, to the left)"
    plt.close(fig)


def test_corner_without_marks_has_no_legend_and_needs_b_for_them(draws):
    fig = plot_corner(draws, NAMES, title="plain")
    assert not fig.legends and fig._suptitle.get_text() == "plain"
    plt.close(fig)
    with pytest.raises(ValueError, match="'b'"):
        plot_corner(draws[:, 1:], NAMES[1:], theory=700.0)


@pytest.mark.parametrize("ndim", [2, 5])
def test_corner_title_and_legend_clear_of_the_panels(draws, ndim):
    fig = plot_corner(draws[:, :ndim], NAMES[:ndim], truths=[750.0] + [None] * (ndim - 1),
                      paper=[753.0] + [None] * (ndim - 1), interval=(745.0, 755.0), theory=474.7,
                      title="a long title of a record's file: A3_1Hz_seed3.csv, two-port model")
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    texts = [fig._suptitle.get_window_extent(renderer), fig.legends[0].get_window_extent(renderer)]
    panels = [ax.get_tightbbox(renderer) for ax in fig.axes if ax.get_frame_on()]
    assert not [(t, p) for t in texts for p in panels if t.overlaps(p)]
    assert all(0 <= t.x0 and t.x1 <= fig.bbox.x1 and t.y1 <= fig.bbox.y1 for t in texts)
    plt.close(fig)


def test_bands_residual_limits_come_from_the_steady_part():
    rng = np.random.default_rng(8)
    t = np.linspace(0.0, 6.0, 3001)
    sims = np.sin(2 * np.pi * t)[None, :] * (1 + 0.001 * rng.normal(size=(20, 1)))
    measured = np.sin(2 * np.pi * t) + 0.01 * rng.normal(size=t.size)
    measured[t < 0.2] += 5.0 * np.exp(-t[t < 0.2] / 0.03)  # a start-up spike of 5 m/s² against 0.01 noise
    fig = plot_bands(t, measured, sims, freq=1.0, noise_sd=0.01, title="spike")
    mid = fig.axes[1]
    lo, hi = mid.get_ylim()
    assert hi < 0.2 and lo > -0.2  # far below the spike
    steady = (t > 1.0) & (t < 5.0)
    assert hi >= np.abs(measured - np.median(sims, axis=0))[steady].max()  # nothing of the steady part clipped
    assert any("steady part" in txt.get_text() for txt in mid.texts)  # and the panel says so
    plt.close(fig)
    # without a spike nothing is said
    fig = plot_bands(t, np.sin(2 * np.pi * t) + 0.01 * rng.normal(size=t.size), sims, freq=1.0, noise_sd=0.01)
    assert not fig.axes[1].texts
    plt.close(fig)


def test_trace_names_the_burn_in_as_fit_prints_it():
    theta = np.random.default_rng(0).normal(size=(4, 20, 2))
    fig = plot_trace(theta, ["b", "rho"], burn=740, thin=5, warmup=666)
    label = fig.axes[-1].get_xlabel()
    assert "the first 740 discarded: a warm-up of 666, then 2 tau" in label and "every 5th" in label
    plt.close(fig)


def test_fit_figures_are_titled_by_the_records_file_name():
    from bayes_inerter import paper_parameters
    from bayes_inerter.inference import PosteriorModel
    from bayes_inerter.inference.fit import _label
    from bayes_inerter.records import GeneratorSettings, generate_record

    # 4 s: three steady drive periods after the first, as the default likelihood needs
    rec = generate_record(paper_parameters("A3"), 1.5, settings=GeneratorSettings(duration=4.0, ramp=0.5), rng=0,
                          setting_name="A3")
    assert _label(PosteriorModel(rec), "run1.csv") == "run1.csv, A3, 1.5 Hz"


def test_corner_draws_the_channels_delay_as_it_is_either_sign(draws):
    """The sampled delay (s) crosses zero: drawn in log10 its panels had no finite limits."""
    rng = np.random.default_rng(4)
    delay = rng.normal(0.0, 2e-4, len(draws))
    assert np.any(delay < 0)
    fig = plot_corner(np.column_stack([draws, delay]), NAMES + ["delay"])
    assert fig.axes[-1].get_xlabel() == "delay [s]"
    lo, hi = fig.axes[-1].get_xlim()
    assert np.isfinite([lo, hi]).all() and lo < 0 < hi
    plt.close(fig)
