"""The study's figures draw what their rows hold."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from bayes_inerter.study.plots import plot_inertance  # noqa: E402


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
