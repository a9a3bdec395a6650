"""The records' figures draw into the axes or figure they are given and return it."""

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402

from bayes_inerter.plots import plot_fits, plot_record, plot_records  # noqa: E402
from bayes_inerter.records.record import Record  # noqa: E402


@pytest.fixture
def record():
    t = np.arange(1001) / 1000.0
    return Record(time=t, force=1e3 * np.sin(2 * np.pi * t), accel=np.cos(2 * np.pi * t),
                  disp=1e-3 * np.sin(2 * np.pi * t), metadata={"setting": "A1", "drive_frequency_hz": 1.0})


def test_record_draws_into_the_given_axes(record):
    fig, axes = plt.subplots(3, 2)
    got = plot_record(record, axes=axes[:, 1], label="given")
    assert got is fig
    assert [len(ax.lines) for ax in axes[:, 1]] == [1, 1, 1] and not any(ax.lines for ax in axes[:, 0])
    assert axes[0, 1].get_title() == "given" and axes[2, 1].get_xlabel() == "time (s)"
    np.testing.assert_allclose(axes[0, 1].lines[0].get_ydata(), record.force / 1e3)
    plt.close(fig)


def test_records_draw_into_the_given_figure(record):
    fig = plt.figure()
    got = plot_records([record, record], labels=["one", "two"], fig=fig)
    assert got is fig and len(fig.axes) == 6
    assert [ax.get_title() for ax in fig.axes if ax.get_title()] == ["one", "two"]
    plt.close(fig)


def test_fits_draw_into_the_given_figure(record):
    fig = plt.figure()
    got = plot_fits(record.time, record.accel, {"model": (0.9 * record.accel, 0.9)}, zoom=(0.2, 0.4), title="given",
                    fig=fig)
    assert got is fig and len(fig.axes) == 2
    whole, zoom = fig.axes
    assert whole.get_title() == "given" and zoom.get_title() == "zoom 0.2-0.4 s"
    assert [line.get_label() for line in whole.lines] == ["measured (low-passed)", "model: φ = 90.0%"]
    assert zoom.lines[0].get_xdata().min() >= 0.2 and zoom.lines[0].get_xdata().max() <= 0.4
    plt.close(fig)
