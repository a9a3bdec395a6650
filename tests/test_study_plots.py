"""The study's figures draw what their rows hold."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from bayes_inerter.study.plots import (  # noqa: E402
    plot_coverage,
    plot_design,
    plot_inertance,
    plot_least_squares,
    plot_models,
    plot_phi_map,
    plot_ranks,
    plot_structure,
)


def _row(setting, b, product=None):
    """A row of inertance.csv; with ``product`` as ``analysis.joint_estimate`` writes it:
    b from the joint model, the records' product beside it."""
    row = {"setting": setting, "b_theory": 0.9 * b, "b_paper": b, "b_median": b, "b_hdi_3%": b - 2, "b_hdi_97%": b + 2}
    if product is not None:
        row |= {"estimate": "joint", "b_product_median": product, "b_product_hdi_3%": product - 1,
                "b_product_hdi_97%": product + 1}
    return row


def _series(fig):
    return [c.get_label() for c in fig.axes[0].containers]


def test_theory_against_identification_shows_the_joint_model_where_it_ran():
    fig = plot_inertance([_row("A0", 750.0), _row("A1", 1660.0)])
    assert _series(fig) == ["posterior: median, 94 % interval"]
    plt.close(fig)
    # the joint model's b first, the records' product beside it, at its own median
    fig = plot_inertance([_row("A0", 752.0, product=750.0), _row("A1", 1668.0, product=1665.0)])
    labels = _series(fig)
    assert len(labels) == 2 and labels[0].startswith("joint model") and "product" in labels[1]
    assert list(fig.axes[0].containers[1].lines[0].get_ydata()) == [750.0, 1665.0]
    plt.close(fig)
    # a setting the joint model did not hold keeps its product as b and has no product point
    fig = plot_inertance([_row("A0", 752.0, product=750.0), _row("A1", 1660.0)])
    labels = _series(fig)
    assert len(labels) == 2 and labels[0].startswith("posterior")
    product_y = fig.axes[0].containers[1].lines[0].get_ydata()
    assert product_y[0] == 750.0 and np.isnan(product_y[1])
    plt.close(fig)


def test_theory_against_identification_shows_the_honest_interval():
    rows = [_row("A0", 750.0) | {"b_honest_median": 760.0, "b_honest_3%": 700.0, "b_honest_97%": 820.0,
                                 "honest_identified": True},
            _row("A1", 1660.0) | {"b_honest_median": 2000.0, "b_honest_3%": 100.0, "b_honest_97%": 1e5,
                                  "honest_identified": False}]
    fig = plot_inertance(rows)
    labels = _series(fig)
    assert labels == ["posterior: median, 94 % interval", "honest: median, 94 % interval"]
    # only the identified setting gets an interval; the other a hollow marker at its median
    assert list(fig.axes[0].containers[1].lines[0].get_ydata()) == [760.0]
    hollow = [ln for ln in fig.axes[0].lines if "not identified" in ln.get_label()]
    assert len(hollow) == 1 and list(hollow[0].get_ydata()) == [2000.0]
    plt.close(fig)


def test_inertance_draws_into_the_given_figure():
    fig = plt.figure()
    got = plot_inertance([_row("A0", 752.0, product=750.0), _row("A1", 1668.0, product=1665.0)], fig=fig)
    assert got is fig and len(fig.axes) == 3
    assert _series(fig)[0].startswith("joint model")
    assert [t.get_text() for t in fig.axes[2].get_xticklabels()] == ["A0", "A1"]
    plt.close(fig)


def test_phi_map_draws_into_the_given_axes():
    rows = [{"setting": "A0", "freq_hz": 0.5, "phi_mean": 0.91}, {"setting": "A1", "freq_hz": 1.0, "phi_mean": 0.93}]
    fig, (left, right) = plt.subplots(1, 2)
    got = plot_phi_map(rows, ax=right)
    assert got is fig
    assert len(right.images) == 1 and not left.images
    grid = right.images[0].get_array()
    assert grid[0, 0] == pytest.approx(91.0) and grid[1, 1] == pytest.approx(93.0) and np.ma.is_masked(grid[0, 1])
    assert right.get_title().startswith("fit accuracy phi")
    plt.close(fig)


def test_models_draw_into_the_given_figure():
    rows = [{"record": "A1_1Hz", "model": m, "phi_mean": p, "elpd_loo": e, "elpd_se": 3.0}
            for m, p, e in (("linear", 0.5, -900.0), ("rigid", 0.7, -300.0), ("two-port", 0.8, 10.0))]
    fig = plt.figure()
    got = plot_models(rows, fig=fig)
    assert got is fig and len(fig.axes) == 2
    phi, loo = fig.axes
    assert [bar.get_height() for bar in phi.patches] == pytest.approx([50.0, 70.0, 80.0])
    assert [bar.get_height() for bar in loo.patches] == pytest.approx([-910.0, -310.0, 0.0])
    plt.close(fig)


def test_design_draws_into_the_given_figure():
    names = ["b", "k_n"]
    rows = [{"setting": s, "design": d, "b": 0.9, "k_n": 0.1} for s in ("A0", "B2") for d in ("paper", "wide")]
    fig = plt.figure()
    got = plot_design(rows, names, fig=fig)
    assert got is fig
    panels = [ax for ax in fig.axes if ax.get_title()]
    assert [ax.get_title() for ax in panels] == ["setting A0", "setting B2"]
    assert all(ax.images[0].get_array().shape == (2, 2) for ax in panels)
    plt.close(fig)


def test_ranks_draw_into_the_given_figure():
    rng = np.random.default_rng(7)
    ranks = {n: rng.integers(0, 100, 40) for n in ("b", "f_0", "c_n")}
    fig = plt.figure()
    got = plot_ranks(ranks, 99, title="given", fig=fig)
    assert got is fig and len(fig.axes) == 3
    assert [ax.get_title() for ax in fig.axes] == ["b", "f_0", "c_n"]
    assert all(sum(bar.get_height() for bar in ax.patches[1:]) == 40 for ax in fig.axes)  # patch 0: the band
    plt.close(fig)


def test_coverage_draws_into_the_given_figure():
    rows = [{"parameter": n, "coverage_50": 0.5, "se_50": 0.05, "coverage_90": 0.9, "se_90": 0.03, "replicates": 50.0}
            for n in ("b", "f_0")]
    fig = plt.figure()
    got = plot_coverage({"model-ar1": rows}, fig=fig)
    assert got is fig and len(fig.axes) == 2
    assert [ax.get_ylabel() for ax in fig.axes] == ["coverage of the central 50 % interval",
                                                    "coverage of the central 90 % interval"]
    assert fig.axes[1].get_legend().get_texts()[0].get_text() == "model-ar1 (50)"
    plt.close(fig)


def _ls_row(record, setting, freq, b_ls, truth=1000.0):
    return {"record": record, "setting": setting, "freq_hz": freq, "b_ls": b_ls, "b_ls_3%": 0.9 * b_ls,
            "b_ls_97%": 1.1 * b_ls, "phi_ls": 0.5, "b_post_mean": b_ls, "b_post_3%": 0.95 * b_ls,
            "b_post_97%": 1.05 * b_ls, "phi_post": 0.8, "b_paper": truth, "phi_paper": 0.6, "b_truth": truth}


def test_least_squares_figure_draws_each_record_and_goes_log_only_when_b_spreads():
    near = [_ls_row("A3_1Hz", "A3", 1.0, 1010.0), _ls_row("A3_0.5Hz", "A3", 0.5, 980.0)]
    fig = plot_least_squares(near)
    ax, ax2 = fig.axes
    assert ax.get_yscale() == "linear" and [t.get_text() for t in ax.get_xticklabels()] == ["A3 1", "A3 0.5"]
    assert len(ax2.lines) == 3  # least squares, posterior, the diagonal
    plt.close(fig)
    far = near + [{"record": "odd", "setting": None, "freq_hz": None, "b_ls": 15000.0, "b_ls_3%": 13000.0,
                   "b_ls_97%": 17000.0, "b_truth": 1000.0}]
    fig = plot_least_squares(far)
    assert fig.axes[0].get_yscale() == "log" and fig.axes[0].get_xticklabels()[-1].get_text() == "odd"
    plt.close(fig)


def test_structure_figure_draws_identified_and_fitted_b_per_setting():
    from bayes_inerter.study.structure import Identified, StructureFit, StructurePriors

    settings = ("A0", "A3", "B2")
    b = np.array([750.0, 3500.0, 20000.0])
    ident = Identified(settings, np.log(b), np.diag([1e-4] * 3), "test")
    fit = StructureFit(ident, StructurePriors(), {}, {s: np.full(50, v) for s, v in zip(settings, b)},
                       np.zeros(50), 0.5, 0.3, 10.0)
    fig = plot_structure({"control": fit})
    ax, ax2 = fig.axes
    assert [t.get_text() for t in ax.get_xticklabels()] == list(settings)
    # right panel: over the theory; the structural fit's markers at b / theory
    from bayes_inerter import theoretical_inertance

    fitted = [c for c in ax2.containers if c.get_label() == "structural fit, control"][0]
    assert np.allclose(fitted.lines[0].get_ydata(), b / [theoretical_inertance(s) for s in settings])
    plt.close(fig)


def _overlaps(a, b) -> bool:
    """Whether two window extents share some area (touching edges do not count)."""
    return a.x0 < b.x1 and b.x0 < a.x1 and a.y0 < b.y1 and b.y0 < a.y1


def test_model_comparison_keeps_its_labels_clear_of_the_titles_and_ticks():
    # results/quick's comparison: the best model's "0 (se ...)" label sat on the title,
    # the worst's on the tick labels
    rows = [{"record": "A3_1Hz", "model": m, "phi_mean": p, "elpd_loo": e, "elpd_se": se}
            for m, p, e, se in (("linear", 0.276, 1334.68, 22.3), ("rigid", 0.932, 1558.53, 31.1),
                                ("two-port", 0.991, 2754.9, 16.5))]
    fig = plot_models(rows)
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    titles = [ax.title.get_window_extent(renderer) for ax in fig.axes]
    labels = [t.get_window_extent(renderer) for ax in fig.axes
              for t in [ax.xaxis.label, ax.yaxis.label, *ax.texts, *ax.get_xticklabels(), *ax.get_yticklabels()]
              if t.get_text()]
    assert not [(t, lab) for t in titles for lab in labels if _overlaps(t, lab)]
    loo = fig.axes[1]
    bar_labels = [t.get_window_extent(renderer) for t in loo.texts]
    ticks = [t.get_window_extent(renderer) for t in loo.get_xticklabels() if t.get_text()]
    assert len(bar_labels) == 3 and not [(a, b) for a in bar_labels for b in ticks if _overlaps(a, b)]
    inside = loo.get_window_extent(renderer)  # each bar's label inside its panel
    assert all(inside.y0 <= b.y0 and b.y1 <= inside.y1 for b in bar_labels)
    plt.close(fig)


def test_phi_map_title_fits_a_narrow_figure():
    rows = [{"setting": "A0", "freq_hz": 0.5, "phi_mean": 0.91}, {"setting": "A1", "freq_hz": 1.0, "phi_mean": 0.93}]
    fig = plot_phi_map(rows)
    fig.canvas.draw()
    title = fig.axes[0].title.get_window_extent(fig.canvas.get_renderer())
    assert 0 <= title.x0 and title.x1 <= fig.bbox.x1 and title.y1 <= fig.bbox.y1
    plt.close(fig)


@pytest.mark.parametrize("draw", ["inertance", "least_squares", "design", "ranks", "coverage"])
def test_no_title_overlaps_a_label(draw):
    """Every other figure, drawn with the data above: no title (nor the figure's) on an
    axis label or a tick label."""
    rng = np.random.default_rng(7)
    rows = [{"parameter": n, "coverage_50": 0.5, "se_50": 0.05, "coverage_90": 0.9, "se_90": 0.03,
             "replicates": 50.0} for n in ("b", "f_0")]
    fig = {"inertance": lambda: plot_inertance([_row("A0", 752.0, product=750.0), _row("A1", 1668.0)]),
           "least_squares": lambda: plot_least_squares([_ls_row("A3_1Hz", "A3", 1.0, 1010.0),
                                                        _ls_row("A3_0.5Hz", "A3", 0.5, 980.0)]),
           "design": lambda: plot_design([{"setting": s, "design": d, "b": 0.9, "k_n": 0.1}
                                          for s in ("A0", "B2") for d in ("paper", "wide")], ["b", "k_n"]),
           "ranks": lambda: plot_ranks({n: rng.integers(0, 100, 40) for n in ("b", "f_0", "c_n")}, 99,
                                       title="given"),
           "coverage": lambda: plot_coverage({"model-ar1": rows})}[draw]()
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    titles = [ax.title for ax in fig.axes] + ([fig._suptitle] if fig._suptitle is not None else [])
    titles = [t.get_window_extent(renderer) for t in titles if t.get_text()]
    labels = [t.get_window_extent(renderer) for ax in fig.axes
              for t in [ax.xaxis.label, ax.yaxis.label, *ax.get_xticklabels(), *ax.get_yticklabels()]
              if t.get_text()]
    assert titles and not [(t, lab) for t in titles for lab in labels if _overlaps(t, lab)]
    plt.close(fig)
