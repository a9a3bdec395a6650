"""The study's figures draw what their rows hold."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from bayes_inerter.study.plots import plot_inertance  # noqa: E402


def _row(setting, b, joint=None):
    row = {"setting": setting, "b_theory": 0.9 * b, "b_paper": b, "b_median": b, "b_hdi_3%": b - 2, "b_hdi_97%": b + 2}
    if joint is not None:
        row |= {"b_joint_mean": joint, "b_joint_hdi_3%": joint - 1, "b_joint_hdi_97%": joint + 1}
    return row


def _series(fig):
    return [c.get_label() for c in fig.axes[0].containers]


def test_theory_against_identification_shows_the_joint_model_where_it_ran():
    fig = plot_inertance([_row("A0", 750.0), _row("A1", 1660.0)])
    assert _series(fig) == ["posterior median, 94 % interval"]
    plt.close(fig)
    # a setting the joint model did not hold is left out of its series, not an error
    fig = plot_inertance([_row("A0", 750.0, joint=752.0), _row("A1", 1660.0)])
    labels = _series(fig)
    assert len(labels) == 2 and labels[1].startswith("joint model")
    joint_y = fig.axes[0].containers[1].lines[0].get_ydata()
    assert joint_y[0] == 752.0 and np.isnan(joint_y[1])
    plt.close(fig)
