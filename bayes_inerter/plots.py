"""Plots of records and of simulations against them.

In corner's shape: the data first, options by keyword, ``axes=`` or ``fig=`` to draw
into the caller's axes or figure, the figure returned; nothing is saved here (callers
save and close). A figure made here gets its size and layout; a caller's keeps its own."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")  # files only; no display is assumed

import matplotlib.pyplot as plt  # noqa: E402

from .records.record import Record  # noqa: E402

__all__ = ["plot_record", "plot_records", "plot_fits"]


def _title(record: Record) -> str:
    meta = record.metadata
    parts = []
    if meta.get("setting"):
        parts.append(f"setting {meta['setting']}")
    if record.drive_frequency:
        parts.append(f"{record.drive_frequency:g} Hz")
    parts.append(f"{record.duration:g} s at {record.fs:g} Hz")
    return ", ".join(parts)


def _figure(fig, **new):
    """``fig``, or a new figure made with ``new`` (its size and layout) when None."""
    return plt.figure(**new) if fig is None else fig


def plot_record(record: Record, *, axes=None, label: str | None = None, color=None):
    """Force, displacement and acceleration of a record against time, stacked.
    ``axes``: three axes to draw into (as :func:`plot_records` gives each record)."""
    if axes is None:
        fig, axes = plt.subplots(3, 1, sharex=True, figsize=(8, 6.5), layout="constrained")
    else:
        fig = axes[0].figure
    t = record.time
    axes[0].plot(t, record.force / 1e3, lw=0.8, color=color, label=label)
    axes[0].set_ylabel("force (kN)")
    if record.disp is not None:
        axes[1].plot(t, record.disp * 1e3, lw=0.8, color=color, label=label)
    axes[1].set_ylabel("displacement (mm)")
    axes[2].plot(t, record.accel, lw=0.5, color=color, label=label)
    axes[2].set_ylabel("acceleration (m/s²)")
    axes[2].set_xlabel("time (s)")
    for ax in axes:
        ax.grid(alpha=0.3)
    axes[0].set_title(label or _title(record))
    return fig


def plot_records(records: list[Record], *, labels=None, fig=None):
    """Several records side by side, one column each (force, displacement, acceleration).
    ``fig``: draw the 3 x n panels into this (empty) figure."""
    n = len(records)
    fig = _figure(fig, figsize=(5.5 * n, 6.5), layout="constrained")
    axes = fig.subplots(3, n, sharex="col", squeeze=False)
    for j, rec in enumerate(records):
        plot_record(rec, axes=axes[:, j], label=(labels[j] if labels else _title(rec)))
    return fig


def plot_fits(time, measured, simulated: dict, *, zoom=None, title: str = "", fig=None):
    """Measured acceleration against simulated ones (name -> (array, phi)), whole and
    zoomed. ``fig``: draw the two panels into this (empty) figure."""
    fig = _figure(fig, figsize=(9, 6.5), layout="constrained")
    axes = fig.subplots(2, 1)
    for ax, window in zip(axes, (None, zoom)):
        sel = slice(None) if window is None else (time >= window[0]) & (time <= window[1])
        ax.plot(time[sel], measured[sel], color="k", lw=1.2, label="measured (low-passed)")
        for name, (a, phi) in simulated.items():
            ax.plot(time[sel], a[sel], lw=1.0, label=f"{name}: φ = {phi:.1%}")
        ax.set_ylabel("acceleration (m/s²)")
        ax.grid(alpha=0.3)
    axes[1].set_xlabel("time (s)")
    axes[0].legend(loc="upper right", fontsize=8)
    axes[0].set_title(title)
    if zoom is not None:
        axes[1].set_title(f"zoom {zoom[0]:g}-{zoom[1]:g} s", fontsize=9)
    return fig
