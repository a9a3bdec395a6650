"""Plots of a posterior: corner, credible bands, traces, phi, force loops.

In corner's shape: the data first, options by keyword, ``ax=`` (one panel) or ``fig=``
(several) to draw into the caller's axes or figure, the figure returned; nothing is
saved here (callers save and close). A figure made here gets its size and layout; a
caller's keeps its own."""

from __future__ import annotations

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.patches import Patch  # noqa: E402
import numpy as np  # noqa: E402

from ...device import TABLE_I  # noqa: E402
from .results import every_nth  # noqa: E402

__all__ = ["plot_corner", "plot_bands", "plot_trace", "plot_phi", "plot_loops", "reference_values"]

UNITS = {"b": "kg", "f1_0": "N", "c_f1": "N s/m", "f2_0": "N", "c_f2": "N s/m", "c_n": "N s/m",
         "k_n": "N/m", "c_B": "N s/m", "k_B": "N/m", "sigma": "m/s²", "f_0": "N", "c_f": "N s/m", "delay": "s"}
LINEAR = ("rho", "f_share", "c_share", "b", "delay")  # drawn as is; everything else in log10


def _linear(name: str) -> bool:
    """Drawn as is: the inertance in kg (the joint model's ``b_<setting>`` too), shares,
    the channels' delay (of either sign), AR(1) coefficients (the joint model's
    ``rho_<f>Hz`` too). The other parameters span orders of magnitude and are drawn in
    log10."""
    return name in LINEAR or name.startswith("rho_") or name.startswith("b_")


def _label(name: str) -> str:
    unit = UNITS.get("b" if name.startswith("b_") else name, "")  # the joint model's b_<setting>
    if _linear(name):
        return f"{name} [{unit}]" if unit else name
    return f"log10 {name} [{unit}]"


def _to_plot(name, x):
    return x if _linear(name) else np.log10(x)


def _figure(fig, **new):
    """``fig``, or a new figure made with ``new`` (its size and layout) when None."""
    return plt.figure(**new) if fig is None else fig


def reference_values(model, metadata: dict):
    """(truth, paper) values of the sampled quantities for the corner plot's markers,
    None where they do not apply.

    The truth comes from a generated record's metadata; the paper's values are Table I
    (and Table 2's b for the record's setting), given only for a record that names one
    of the paper's settings, turned into sums and shares where those
    are sampled. In the rigid model f1_0 and c_f1 are totals: the truth is summed, the
    paper's split values are not marked.
    """
    from ...device import SETTINGS

    truth = dict(metadata.get("true_parameters") or {})
    setting = metadata.get("setting")
    paper = dict(TABLE_I)
    if setting and str(setting).upper() in SETTINGS:
        paper["b"] = SETTINGS[str(setting).upper()].b_paper
    if model.model == "rigid":
        if truth:
            truth["f1_0"] = truth.get("f1_0", 0.0) + truth.get("f2_0", 0.0)
            truth["c_f1"] = truth.get("c_f1", 0.0) + truth.get("c_f2", 0.0)
        paper.pop("f1_0"), paper.pop("c_f1")
    t_s = model.sampled_from_physical(truth) if truth else {}
    if not (setting and str(setting).upper() in SETTINGS):  # not the paper's device: nothing to mark
        return [None if n not in t_s else _to_plot(n, t_s[n]) for n in model.names], None
    p_s = model.sampled_from_physical(paper)
    t_out = [None if n not in t_s else _to_plot(n, t_s[n]) for n in model.names]
    p_out = [None if n not in p_s else _to_plot(n, p_s[n]) for n in model.names]
    return t_out, p_out


#: The corner plot's marks: colour and line style of each (``plot_corner``'s legend).
TRUTH_COLOR, PAPER_COLOR, INTERVAL_COLOR, THEORY_COLOR = "tab:blue", "tab:red", "tab:orange", "tab:purple"


def plot_corner(values: np.ndarray, names, *, truths=None, paper=None, title: str = "", fig=None,
                interval=None, theory: float | None = None, b: str = "b"):
    """Corner plot of (n, ndim) draws in SI units: b in kg, shares and rho as they are,
    the other parameters in log10. ``truths`` and ``paper`` (in the plotted scale, None
    where unknown) are marked only where given. ``fig``: draw into this figure (empty,
    or with ndim x ndim axes, as ``corner.corner`` takes it). ``title``: the figure's
    title, as the caller words it.

    On the parameter named ``b`` (kg): ``interval`` (lo, hi), the reported interval, is
    shaded on its histogram and drawn as dashed lines in its 2-D panels, whose range is
    widened to hold it; ``theory``, the theoretical b (the device file's), is a line of
    its own colour where it falls inside the panels (the legend gives its value and says
    when it is off them). A legend names every mark drawn."""
    import logging

    import corner
    from matplotlib.lines import Line2D

    if (interval is not None or theory is not None) and b not in list(names):
        raise ValueError(f"interval and theory mark the parameter {b!r}, which is not among {list(names)}")
    x = np.column_stack([_to_plot(n, values[:, i]) for i, n in enumerate(names)])
    # corner logs "Too few points to create valid contours" to the root logger for
    # panels of a parameter pinned to a point; the panel shows that plainly already
    root = logging.getLogger()
    level = root.level
    root.setLevel(logging.ERROR)
    made = fig is None
    try:
        fig = corner.corner(
            x, fig=fig, labels=[_label(n) for n in names], truths=truths, truth_color=TRUTH_COLOR,
            quantiles=[0.03, 0.5, 0.97], show_titles=True, title_fmt=".4g",
            title_kwargs={"fontsize": 8}, label_kwargs={"fontsize": 8}, plot_datapoints=False,
        )
    finally:
        root.setLevel(level)
    if paper is not None and any(p is not None for p in paper):
        corner.overplot_lines(fig, [np.nan if p is None else p for p in paper], color=PAPER_COLOR, ls="--")
    handles = []
    if truths is not None and any(t is not None for t in truths):
        handles.append(Line2D([], [], color=TRUTH_COLOR, label="truth"))
    if paper is not None and any(p is not None for p in paper):
        handles.append(Line2D([], [], color=PAPER_COLOR, ls="--", label="paper"))
    if interval is not None or theory is not None:
        handles += _mark_b(fig, len(names), list(names).index(b), interval, theory)
    _title_and_legend(fig, title, handles, grow=made)
    return fig


#: How far above its frame a corner panel's own texts (its title, tick labels) may stand,
#: inches: panels lower than this below the figure's title and legend are not measured.
REACH = 1.0


def _title_and_legend(fig, title: str, handles: list, *, grow: bool) -> None:
    """``title`` at the top of a corner figure, the legend of ``handles`` under it on the
    right (in the empty upper triangle where it fits); the panels moved down until
    neither overlaps a panel, its title or its labels: ``grow``, the figure is made
    taller for it (one made here), else the panels' grid is lowered (the caller's)."""
    legend = fig.legend(handles=handles, loc="upper right", fontsize=8, frameon=False) if handles else None
    inch = fig.dpi
    for _ in range(6):
        renderer = fig._get_renderer()  # any canvas's, Agg's or a bare Figure's
        height = fig.get_figheight() * inch
        texts = []
        below = height - 0.1 * inch  # the texts' top: 0.1 in under the figure's edge
        if title:
            sup = fig.suptitle(title, fontsize=10, y=below / height, va="top")
            texts.append(sup.get_window_extent(renderer))
            below = texts[-1].y0
        if legend is not None:
            legend.set_bbox_to_anchor((0.98, (below - 0.05 * inch) / height), transform=fig.transFigure)
            texts.append(legend.get_window_extent(renderer))
        # only panels whose frame tops lie within REACH of the texts' bottom can reach them
        # (their titles and tick labels stand out a fraction of an inch); a corner plot of
        # 15 parameters has 120 panels, each tight box several milliseconds
        low = min((t.y0 for t in texts), default=height)
        panels = [ax.get_tightbbox(renderer) for ax in fig.axes
                  if ax.get_frame_on() and ax.get_position().y1 * height + REACH * inch >= low]
        need = max([p.y1 - t.y0 for t in texts for p in panels if t.overlaps(p)], default=0.0)
        if need <= 0:
            return
        step = (need + 0.05 * inch) / inch  # inches
        pars, h = fig.subplotpars, fig.get_figheight()
        if grow:
            fig.set_size_inches(fig.get_figwidth(), h + step)
            fig.subplots_adjust(top=pars.top * h / (h + step), bottom=pars.bottom * h / (h + step))
        else:
            fig.subplots_adjust(top=pars.top - step / h)


def _mark_b(fig, ndim: int, k: int, interval, theory) -> list:
    """Mark the reported ``interval`` and the ``theory`` on the ``k``-th parameter's
    panels of a corner figure (``ndim`` x ``ndim`` axes); return their legend handles."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    axes = np.asarray(fig.axes).reshape(ndim, ndim)
    column = [axes[i, k] for i in range(k + 1, ndim)]  # b on the x axis below the histogram
    row = [axes[k, j] for j in range(k)]  # b on the y axis left of it
    hist = axes[k, k]
    lo, hi = hist.get_xlim()
    handles = []
    if interval is not None:
        a, z = sorted(float(v) for v in interval)
        pad = 0.05 * (max(hi, z) - min(lo, a))
        lo, hi = min(lo, a - pad), max(hi, z + pad)  # the interval inside the panels
        for ax in [hist, *column]:
            ax.set_xlim(lo, hi)
        for ax in row:
            ax.set_ylim(lo, hi)
        hist.axvspan(a, z, color=INTERVAL_COLOR, alpha=0.2, lw=0)
        for v in (a, z):
            for ax in [hist, *column]:
                ax.axvline(v, color=INTERVAL_COLOR, ls="--", lw=1.2)
            for ax in row:
                ax.axhline(v, color=INTERVAL_COLOR, ls="--", lw=1.2)
        handles.append(Patch(facecolor=INTERVAL_COLOR, alpha=0.4, edgecolor=INTERVAL_COLOR, ls="--",
                             label=f"reported 94 % interval: {a:.5g} to {z:.5g} kg"))
    if theory is not None:
        t = float(theory)
        where = "" if lo <= t <= hi else f" (off the panels, to the {'left' if t < lo else 'right'})"
        for ax in [hist, *column, *row]:  # a line off the panels must not widen them
            ax.set_autoscale_on(False)
        for ax in [hist, *column]:
            ax.axvline(t, color=THEORY_COLOR, lw=1.5)
        for ax in row:
            ax.axhline(t, color=THEORY_COLOR, lw=1.5)
        handles.append(Line2D([], [], color=THEORY_COLOR, lw=1.5,
                              label=f"theoretical b (device file): {t:.5g} kg{where}"))
    return handles


def _reversal_time(time, accel_lp, freq):
    """A velocity reversal in the last full cycle: where the integrated, high-passed
    acceleration (the velocity, up to drift) crosses zero."""
    from scipy import signal

    fs = (len(time) - 1) / (time[-1] - time[0])
    v = np.cumsum(accel_lp) / fs
    sos = signal.butter(2, max(0.1 * (freq or 1.0), 0.05), btype="highpass", fs=fs, output="sos")
    v = signal.sosfiltfilt(sos, v)
    period = 1.0 / (freq or 1.0)
    sel = np.flatnonzero((time > time[-1] - 1.5 * period) & (time < time[-1] - 0.3 * period))
    crossings = sel[np.flatnonzero(np.diff(np.sign(v[sel])) != 0)]
    return time[crossings[0]] if len(crossings) else time[-1] - period


def _steady(time, freq) -> np.ndarray:
    """Where the response is steady: the record without its first and last drive period
    (without its first and last tenth where the drive frequency is not known, or where
    that would leave less than half of it)."""
    duration = time[-1] - time[0]
    cut = 1.0 / freq if freq else 0.1 * duration
    if duration - 2 * cut < 0.5 * duration:
        cut = 0.1 * duration
    return (time >= time[0] + cut) & (time <= time[-1] - cut)


def _steady_ylim(ax, time, series, freq) -> None:
    """The y-limits of ``ax`` from the steady part of ``series`` (``_steady``), so that a
    start-up spike or the end's ringing does not squash the rest; what lies beyond them
    is said in the panel."""
    steady = _steady(time, freq)
    reach = max(float(np.nanmax(np.abs(y[steady]))) for y in series)
    whole = max(float(np.nanmax(np.abs(y))) for y in series)
    if not np.isfinite(reach) or reach <= 0:
        return
    ax.set_ylim(-1.1 * reach, 1.1 * reach)
    if whole > 1.1 * reach:
        ax.text(0.99, 0.02, f"scaled to the steady part; the record's ends reach ±{whole:.3g} m/s²",
                transform=ax.transAxes, ha="right", va="bottom", fontsize=7, color="0.3",
                bbox={"facecolor": "w", "alpha": 0.7, "lw": 0})


def plot_bands(time, measured_lp, sims: np.ndarray, *, freq=None, noise_sd: float | None = None, title: str = "",
               fig=None):
    """Median, 50 % and 94 % credible bands of the simulated low-passed acceleration
    (parameter uncertainty) and, given ``noise_sd`` (the residual model's marginal sd),
    the 94 % predictive band that adds the residual's spread (normal approximation).

    Three panels: the measured and the median over the whole record; the residual about
    the posterior median with the bands about it (bands far thinner than the signal are
    visible only so), its y-limits set by the steady part (without the first and last
    drive period, where a start-up spike would squash the rest); a zoom on a velocity
    reversal. Legends sit outside the data.
    ``fig``: draw the three panels into this (empty) figure."""
    q = np.percentile(sims, [3, 25, 50, 75, 97], axis=0)
    t_rev = _reversal_time(time, measured_lp, freq)
    span = 0.12 / (freq or 1.0)
    fig = _figure(fig, figsize=(11, 9), layout="constrained")
    axes = fig.subplots(3, 1)
    top, mid, zoom = axes
    top.plot(time, measured_lp, color="k", lw=0.8, label="measured")
    top.plot(time, q[2], color="tab:red", lw=0.8, label="posterior median")
    top.set_ylabel("acceleration,\nlow-passed (m/s²)")
    top.set_title(title)
    d = q - q[2]
    if noise_sd is not None:
        half = 1.880794 * np.sqrt(((q[4] - q[0]) / (2 * 1.880794)) ** 2 + noise_sd**2)
        mid.fill_between(time, -half, half, color="tab:blue", alpha=0.15, lw=0,
                         label="94 % predictive band (with residual noise)")
    mid.fill_between(time, d[0], d[4], color="tab:orange", alpha=0.35, lw=0, label="94 % credible band (parameters)")
    mid.fill_between(time, d[1], d[3], color="tab:orange", alpha=0.7, lw=0, label="50 % credible band")
    mid.plot(time, measured_lp - q[2], color="k", lw=0.6, label="measured - median")
    mid.axhline(0, color="tab:red", lw=0.8)
    mid.set_ylabel("about the posterior\nmedian (m/s²)")
    edges = [measured_lp - q[2], d[0], d[4]] + ([-half, half] if noise_sd is not None else [])
    _steady_ylim(mid, time, edges, freq)
    sel = (time >= t_rev - span) & (time <= t_rev + span)
    if noise_sd is not None:
        zoom.fill_between(time[sel], (q[2] - half)[sel], (q[2] + half)[sel], color="tab:blue", alpha=0.15, lw=0)
    zoom.fill_between(time[sel], q[0][sel], q[4][sel], color="tab:orange", alpha=0.35, lw=0)
    zoom.fill_between(time[sel], q[1][sel], q[3][sel], color="tab:orange", alpha=0.7, lw=0)
    zoom.plot(time[sel], q[2][sel], color="tab:red", lw=0.8)
    zoom.plot(time[sel], measured_lp[sel], color="k", lw=0.8)
    zoom.set_ylabel("acceleration,\nlow-passed (m/s²)")
    zoom.set_title(f"zoom on a velocity reversal near {t_rev:.2f} s", fontsize=9)
    zoom.set_xlabel("time (s)")
    for ax in axes:
        ax.grid(alpha=0.3)
    for ax in (top, mid):
        ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8, frameon=False)
    return fig


def plot_trace(theta: np.ndarray, names, *, burn: int = 0, thin: int = 1, warmup: int | None = None, fig=None):
    """Walker traces of every parameter after burn-in: b in kg, shares and rho as they
    are, the others in log10 (as :func:`plot_corner`).

    ``theta`` has shape (walkers, draws, ndim) from the kept (thinned) chain, as sampled
    (natural logs where the prior is log-scaled). ``fig``: draw the ndim panels into
    this (empty) figure."""
    ndim = theta.shape[2]
    fig = _figure(fig, figsize=(9, 1.3 * ndim + 1), layout="constrained")
    axes = np.atleast_1d(fig.subplots(ndim, 1, sharex=True))
    steps = burn + thin * np.arange(theta.shape[1])
    for i, ax in enumerate(axes):
        y = theta[:, :, i] / np.log(10) if not _linear(names[i]) else (
            np.exp(theta[:, :, i]) if names[i] == "b" or names[i].startswith("b_") else theta[:, :, i])
        ax.plot(steps, y.T, lw=0.4, alpha=0.5)
        ax.set_ylabel(_label(names[i]), fontsize=7)
        ax.tick_params(labelsize=7)
    # the same two numbers ``fit`` prints: the warm-up, and 2 tau after it
    how = f": a warm-up of {warmup}, then 2 tau" if warmup is not None and warmup < burn else ""
    axes[-1].set_xlabel(f"step (the first {burn} discarded{how}; {every_nth(thin)} shown)")
    return fig


def plot_phi(phi: np.ndarray, *, paper: float | None = None, title: str = "", ax=None):
    """Posterior of the fit accuracy phi (eq. 5, low-passed). ``ax``: draw into these axes."""
    if ax is None:
        fig, ax = plt.subplots(figsize=(6, 3.5), layout="constrained")
    else:
        fig = ax.figure
    ax.hist(phi.ravel() * 100, bins=50, color="tab:green", alpha=0.8)
    if paper is not None:
        ax.axvline(paper * 100, color="tab:red", ls="--", label=f"paper: {paper:.1%}")
        ax.legend(fontsize=8)
    ax.ticklabel_format(axis="x", useOffset=False)  # phi near 100 %: the digits themselves, no offset
    ax.set_xlabel("fit accuracy φ (%), low-passed")
    ax.set_ylabel("draws")
    ax.set_title(title, fontsize=10)
    return fig


def _arcs(x: np.ndarray) -> list[np.ndarray]:
    """Indices of a closed curve's two arcs on which ``x`` is monotonic (from its minimum
    to its maximum and back), so that a band along each can be filled over x."""
    n = len(x)
    lo, hi = int(np.argmin(x)), int(np.argmax(x))
    up = np.arange(lo, hi + 1 if hi >= lo else hi + n + 1) % n
    down = np.arange(hi, lo + 1 if lo >= hi else lo + n + 1) % n
    return [up, down]


def plot_loops(loops, titles, *, level: float = 0.94, per_row: int | None = None, fig=None):
    """Force-displacement and force-velocity loops over one steady period
    (``loops.PeriodLoops``), two panels per record: the measured force (black) and the
    model's predicted force given the measured motion, its posterior median (red) and
    ``level`` credible band (orange), filled along each half of the loop.
    ``loops``, ``titles``: one each per record. ``per_row``: records side by side in a
    row (default 1 for up to three records, else 3). ``fig``: draw into this (empty)
    figure."""
    loops = list(loops)
    titles = list(titles)
    if len(loops) != len(titles) or not loops:
        raise ValueError(f"give one title per record's loops, got {len(loops)} loops and {len(titles)} titles")
    per_row = per_row or (1 if len(loops) <= 3 else 3)
    rows = -(-len(loops) // per_row)
    fig = _figure(fig, figsize=(10 * per_row, 3.4 * rows + 0.4), layout="constrained")
    axes = np.atleast_2d(fig.subplots(rows, 2 * per_row))
    for k, (lp, title) in enumerate(zip(loops, titles)):
        pair = axes[k // per_row, 2 * (k % per_row): 2 * (k % per_row) + 2]
        lo, mid, hi = lp.band(level)
        for ax, x, unit in ((pair[0], lp.displacement, "displacement (mm)"), (pair[1], lp.velocity, "velocity (mm/s)")):
            for arc in _arcs(x):
                ax.fill_between(x[arc] * 1e3, lo[arc] / 1e3, hi[arc] / 1e3, color="tab:orange", alpha=0.45, lw=0)
            closed = np.append(np.arange(len(x)), 0)
            ax.plot(x[closed] * 1e3, lp.measured[closed] / 1e3, color="k", lw=1.0)
            ax.plot(x[closed] * 1e3, mid[closed] / 1e3, color="tab:red", lw=0.9, ls="--")
            ax.set_xlabel(unit)
            ax.set_ylabel("force (kN)")
            ax.grid(alpha=0.3)
        pair[0].set_title(title, fontsize=10, loc="left")
    for ax in axes.ravel()[2 * len(loops):]:
        ax.set_visible(False)
    handles = [plt.Line2D([], [], color="k", lw=1.0), plt.Line2D([], [], color="tab:red", lw=0.9, ls="--"),
               Patch(color="tab:orange", alpha=0.45)]
    fig.legend(handles, ["measured (the steady periods' mean)", "model given the measured motion, posterior median",
                         f"{level:.0%} credible band (parameters)"], fontsize=8, loc="outside upper center", ncol=3,
               frameon=False)
    return fig
