"""A study's figures: theory against identification (the paper's Fig. 9 with
uncertainty), the fit accuracy as a heat map beside Table 2, and model comparison; and
the design and calibration studies' figures.

In corner's shape: the data first, options by keyword, ``ax=`` (one panel) or ``fig=``
(several) to draw into the caller's axes or figure, the figure returned; nothing is
saved here (callers save and close). A figure made here gets its size and its
``tight_layout``; a caller's keeps its own layout."""

from __future__ import annotations

import numpy as np

from ..device import FREQUENCIES_HZ, SETTINGS
from .analysis import Z94, is_joint

__all__ = ["plot_inertance", "plot_least_squares", "plot_structure", "plot_phi_map", "plot_models", "plot_design", "plot_ranks", "plot_coverage"]


def _figure(fig, figsize):
    """(``fig``, False), or (a new figure of ``figsize``, True) when None: whether this
    function made it, and so lays it out."""
    import matplotlib.pyplot as plt

    return (plt.figure(figsize=figsize), True) if fig is None else (fig, False)


def plot_inertance(rows: list[dict], *, fig=None):
    """b per setting: theory, the paper's identified value, the posterior (median, 94 %),
    the honest interval where the rows have it (``study.honest``; a hollow marker where
    no record identifies b), and where the rows have them (``analysis.joint_estimate``)
    the records' product beside the joint model's b; below, each relative to theory. ``fig``: draw the three
    panels into this (empty) figure."""
    fig, made = _figure(fig, (8, 9))
    ax, rel, width = fig.subplots(3, 1, sharex=True, gridspec_kw={"height_ratios": [3, 2, 2]})
    x = np.arange(len(rows))
    theory = np.array([r["b_theory"] for r in rows])
    paper = np.array([r["b_paper"] for r in rows])
    med = np.array([r["b_median"] for r in rows])
    err = np.array([[r["b_median"] - r["b_hdi_3%"] for r in rows], [r["b_hdi_97%"] - r["b_median"] for r in rows]])
    joint = is_joint(rows)
    ax.plot(x, theory, "s", mfc="none", color="k", ms=9, label="theory (geometry)")
    ax.plot(x, paper, "x", color="tab:red", ms=9, label="paper, identified by hand")
    ax.errorbar(x, med, yerr=err, fmt="o", color="tab:blue", capsize=4,
                label=("joint model (all records)" if joint else "posterior") + ": median, 94 % interval")
    honest = [i for i, r in enumerate(rows) if "b_honest_3%" in r]
    if honest:  # the interval to quote (study.honest); where no record identifies b, a hollow marker
        ident = np.array([bool(rows[i]["honest_identified"]) for i in honest])
        hm, hlo, hhi = (np.array([rows[i][k] for i in honest]) for k in ("b_honest_median", "b_honest_3%",
                                                                         "b_honest_97%"))
        hx = x[honest] - 0.2
        herr = np.array([hm - hlo, hhi - hm])
        ax.errorbar(hx[ident], hm[ident], yerr=herr[:, ident], fmt="^", color="tab:orange", capsize=4, ms=6,
                    label="honest: median, 94 % interval")
        if (~ident).any():
            ax.plot(hx[~ident], hm[~ident], "^", mfc="none", color="tab:orange", ms=8,
                    label="honest: b not identified (interval: the prior's range)")
    product = any("b_product_median" in r for r in rows)
    if product:  # each setting's records combined one by one, beside the joint model (NaN: not there)
        pm, lo, hi = (np.array([r.get(k, np.nan) for r in rows]) for k in ("b_product_median", "b_product_hdi_3%",
                                                                         "b_product_hdi_97%"))
        perr = np.array([pm - lo, hi - pm])
        ax.errorbar(x + 0.2, pm, yerr=perr, fmt="D", color="tab:green", capsize=4, ms=5,
                    label="each record on its own, combined per setting (product)")
    ax.set_yscale("log")
    ax.set_ylabel("inertance b (kg)")
    ax.legend(loc="upper left")
    ax.grid(alpha=0.3, which="both")
    rel.axhline(0, color="k", lw=0.8)
    rel.plot(x, 100 * (paper / theory - 1), "x", color="tab:red", ms=9)
    rel.errorbar(x, 100 * (med / theory - 1), yerr=100 * err / theory, fmt="o", color="tab:blue", capsize=4)
    if honest:
        th = theory[honest]
        rel.errorbar(hx[ident], 100 * (hm[ident] / th[ident] - 1), yerr=100 * herr[:, ident] / th[ident], fmt="^",
                     color="tab:orange", capsize=4, ms=6)
    if product:
        rel.errorbar(x + 0.2, 100 * (pm / theory - 1), yerr=100 * perr / theory, fmt="D", color="tab:green",
                     capsize=4, ms=5)
    rel.set_ylabel("relative to theory (%)")
    rel.grid(alpha=0.3)
    # the intervals are far narrower than the gaps to theory: their own panel shows them
    width.axhline(0, color="k", lw=0.8)
    width.errorbar(x, np.zeros_like(med), yerr=100 * err / med, fmt="o", color="tab:blue", capsize=4)
    if honest:
        width.errorbar(hx[ident], np.zeros(ident.sum()), yerr=100 * herr[:, ident] / hm[ident], fmt="^",
                       color="tab:orange", capsize=4, ms=6)
    if product:
        width.errorbar(x + 0.2, np.zeros_like(pm), yerr=100 * perr / pm, fmt="D", color="tab:green", capsize=4, ms=5)
    width.set_ylabel("94 % interval about\nits median (%)")
    width.set_xticks(x, [r["setting"] for r in rows])
    width.set_xlabel("flywheel setting")
    width.grid(alpha=0.3)
    ax.set_title("Inertance per flywheel setting: theory against identification")
    if made:
        fig.tight_layout()
    return fig


def plot_least_squares(rows: list[dict], *, fig=None):
    """The paper's least squares beside the posterior, record by record
    (``study.least_squares``): left, each record's b over the reference (the generating b
    where the rows have it, else the paper's) with the least-squares interval, the
    posterior's 94 % HDI and the honest interval; right, phi by least squares and by the
    posterior against the paper's Table 2."""
    fig, own = _figure(fig, (12, 4.8))
    ax, ax2 = fig.subplots(1, 2, gridspec_kw={"width_ratios": [2.2, 1]})
    truth = all(r.get("b_truth") for r in rows)
    ref = [r["b_truth"] if truth else r.get("b_paper") for r in rows]
    x = np.arange(len(rows))
    kinds = (("ls", "least squares (eq. 4), Hessian interval", "C3", "s", -0.22),
             ("post", "posterior, 94 % HDI", "C0", "o", 0.0), ("honest", "honest interval", "C1", "^", 0.22))
    for key, label, color, marker, dx in kinds:
        lo = np.array([_ratio(r.get(f"b_{key}_3%"), b) for r, b in zip(rows, ref)])
        hi = np.array([_ratio(r.get(f"b_{key}_97%"), b) for r, b in zip(rows, ref)])
        mid_key = {"ls": "b_ls", "post": "b_post_mean", "honest": None}[key]
        mid = (np.array([_ratio(r.get(mid_key), b) for r, b in zip(rows, ref)]) if mid_key
               else np.sqrt(lo * hi))
        ok = np.isfinite(lo) & np.isfinite(hi) & np.isfinite(mid)
        if ok.any():
            ax.errorbar(x[ok] + dx, mid[ok], yerr=[mid[ok] - lo[ok], hi[ok] - mid[ok]], fmt=marker, color=color,
                        ms=4, capsize=2, lw=1, label=label)
    ax.axhline(1.0, color="k", lw=0.8)
    drawn = np.concatenate([np.ravel(line.get_ydata()) for line in ax.lines] + [np.ones(1)]).astype(float)
    drawn = drawn[np.isfinite(drawn) & (drawn > 0)]
    if drawn.max() / drawn.min() > 3:  # a log scale only where the records' b's spread that far
        ax.set_yscale("log")
    ax.set_xticks(x, [f"{r['setting']} {r['freq_hz']:g}" if r.get("freq_hz") is not None else r["record"]
                      for r in rows], rotation=90, fontsize=7)
    ax.set_ylabel("b / " + ("generating b" if truth else "paper's identified b"))
    ax.set_title("b per record (setting, Hz)", fontsize=10)
    ax.legend(fontsize=7, loc="upper right")
    paper = np.array([_num(r.get("phi_paper")) for r in rows])
    for key, label, color, marker in (("phi_ls", "least squares (unfiltered, as the paper)", "C3", "s"),
                                      ("phi_post", "posterior mean (low-passed)", "C0", "o")):
        ax2.plot(paper, [_num(r.get(key)) for r in rows], marker, color=color, ms=4, label=label)
    ax2.plot([0, 1], [0, 1], "k-", lw=0.8)
    ax2.set_xlim(0, 1)
    ax2.set_ylim(min(0.0, np.nanmin([_num(r.get("phi_ls")) for r in rows] + [0.0])), 1)
    ax2.set_xlabel("phi, paper's Table 2")
    ax2.set_ylabel("phi, this study")
    ax2.set_title("fit accuracy phi (eq. 5)", fontsize=10)
    ax2.legend(fontsize=7, loc="lower right")
    if own:
        fig.tight_layout()
    return fig


def plot_structure(fits: dict, *, fig=None):
    """The paper's Fig. 9 with the structural model (``study.structure``): per setting,
    each of ``fits`` (label -> ``StructureFit``) drawn as its identified b's 94 %
    interval and the structure's fit (median, 94 % band), beside the geometry's theory
    and the paper's identified values; left in kg, right over the theory."""
    from ..device import theoretical_inertance

    fig, own = _figure(fig, (12, 4.8))
    ax, ax2 = fig.subplots(1, 2)
    names = [s for s in SETTINGS if any(s in f.identified.settings for f in fits.values())]
    x = np.arange(len(names))
    theory = np.array([theoretical_inertance(s) for s in names])
    paper = np.array([SETTINGS[s].b_paper for s in names])
    for a, scale in ((ax, np.ones(len(names))), (ax2, theory)):
        a.plot(x, theory / scale, "k_", ms=14, mew=2, label="theory (geometry)")
        a.plot(x, paper / scale, "kx", ms=7, label="paper, Table 2")
    for i, (label, fit) in enumerate(fits.items()):
        dx = (i - (len(fits) - 1) / 2) * 0.25
        idx = [names.index(s) for s in fit.identified.settings]
        ident, sd = fit.identified.mean, fit.identified.sd
        lo, hi = np.exp(ident - Z94 * sd), np.exp(ident + Z94 * sd)
        band = np.array([np.percentile(fit.b[s], [3, 50, 97]) for s in fit.identified.settings])
        for a, scale in ((ax, np.ones(len(names))), (ax2, theory)):
            sc = scale[idx]
            a.errorbar(np.array(idx) + dx, np.exp(ident) / sc, yerr=[(np.exp(ident) - lo) / sc, (hi - np.exp(ident)) / sc],
                       fmt="o", color=f"C{2 * i}", ms=4, capsize=2, label=f"identified, {label}")
            a.errorbar(np.array(idx) + dx + 0.08, band[:, 1] / sc,
                       yerr=[(band[:, 1] - band[:, 0]) / sc, (band[:, 2] - band[:, 1]) / sc], fmt="s",
                       mfc="none", color=f"C{2 * i + 1}", ms=5, capsize=2, label=f"structural fit, {label}")
    ax.set_yscale("log")
    ax.set_ylabel("inertance b (kg)")
    ax2.axhline(1.0, color="k", lw=0.6)
    ax2.set_ylabel("b / theory")
    for a in (ax, ax2):
        a.set_xticks(x, names)
        a.set_xlabel("flywheel setting")
    ax.legend(fontsize=7, loc="upper left")
    ax.set_title("inertance per setting", fontsize=10)
    ax2.set_title("over the geometry's theory", fontsize=10)
    if own:
        fig.tight_layout()
    return fig


def _num(v) -> float:
    return float(v) if v is not None and v != "" else float("nan")


def _ratio(v, ref) -> float:
    return _num(v) / ref if ref else float("nan")


def plot_phi_map(rows: list[dict], *, ax=None):
    """Posterior mean of phi per setting and frequency; each cell also shows the paper's.
    ``ax``: draw into these axes (the colour bar takes room beside them)."""

    settings = [s for s in SETTINGS if any(r["setting"] == s for r in rows)]
    freqs = [f for f in FREQUENCIES_HZ if any(r["freq_hz"] == f for r in rows)]
    grid = np.full((len(freqs), len(settings)), np.nan)
    for r in rows:
        if r["setting"] in settings and r["freq_hz"] in freqs:
            grid[freqs.index(r["freq_hz"]), settings.index(r["setting"])] = 100 * r["phi_mean"]
    if ax is None:
        fig, made = _figure(None, (1.1 * len(settings) + 2.5, 0.9 * len(freqs) + 1.8))
        ax = fig.subplots()
    else:
        fig, made = ax.figure, False
    papers = [100 * SETTINGS[s].fit_paper[f] for s in settings for f in freqs if SETTINGS[s].fit_paper.get(f)]
    shown = np.concatenate([grid[np.isfinite(grid)], papers]) if papers or np.isfinite(grid).any() else np.array([0.0])
    lo, hi = float(np.min(shown)), float(np.max(shown))
    if hi - lo < 1e-9:
        lo, hi = lo - 0.5, hi + 0.5
    im = ax.imshow(grid, cmap="viridis", vmin=lo, vmax=hi, aspect="auto")  # the scale spans what is shown
    for i, f in enumerate(freqs):
        for j, s in enumerate(settings):
            paper = SETTINGS[s].fit_paper.get(f)
            text = ("-" if np.isnan(grid[i, j]) else f"{grid[i, j]:.1f}") + (f"\n({100 * paper:.1f})" if paper else "")
            ax.text(j, i, text, ha="center", va="center", fontsize=8,
                    color="w" if np.nan_to_num(grid[i, j], nan=lo) < (lo + hi) / 2 else "k")
    ax.set_xticks(range(len(settings)), settings)
    ax.set_yticks(range(len(freqs)), [f"{f:g} Hz" for f in freqs])
    ax.set_title("fit accuracy phi (%): posterior mean\n(in brackets: the paper's Table 2)")  # fits 2 settings
    fig.colorbar(im, ax=ax, label="phi (%)")
    if made:
        fig.tight_layout()
    return fig


def plot_models(rows: list[dict], *, fig=None):
    """Per compared record: phi and LOO (elpd, relative to the best) of each model.
    ``fig``: draw the two panels into this (empty) figure."""
    records = sorted({r["record"] for r in rows})
    models = ["linear", "rigid", "two-port"]
    fig, made = _figure(fig, (10, 4))
    a1, a2 = fig.subplots(1, 2)
    width = 0.8 / len(records)
    for k, rec in enumerate(records):
        sub = {r["model"]: r for r in rows if r["record"] == rec}
        best = max(r["elpd_loo"] for r in sub.values())
        x = np.arange(len(models)) + k * width
        a1.bar(x, [100 * sub[m]["phi_mean"] if m in sub else np.nan for m in models], width, label=rec)
        diffs = [sub[m]["elpd_loo"] - best if m in sub else np.nan for m in models]
        a2.bar(x, diffs, width, label=rec)
        for xi, m, d in zip(x, models, diffs):
            if m in sub:
                a2.annotate(f"{d:.0f}\n(se {sub[m]['elpd_se']:.0f})", (xi, d), ha="center", va="top" if d < 0 else "bottom",
                            fontsize=7, xytext=(0, -2 if d < 0 else 2), textcoords="offset points")
    paper = {"linear": 49, "rigid": 65, "two-port": 75}
    a1.plot(np.arange(len(models)) + 0.4 - width / 2, [paper[m] for m in models], "x", color="tab:red", ms=10,
            label="paper (all records)")
    for ax in (a1, a2):
        ax.set_xticks(np.arange(len(models)) + 0.4 - width / 2, models)
        ax.grid(alpha=0.3, axis="y")
    a1.set_ylabel("fit accuracy phi (%)")
    a1.legend(fontsize=8)
    a2.set_ylabel("elpd_loo - best model's (nats; higher is better)")
    # room above and below the bars for their labels, clear of the title and the ticks
    low = min([0.0] + [b.get_height() for b in a2.patches if np.isfinite(b.get_height())])
    a2.set_ylim(low - 0.18 * (-low or 1.0), 0.15 * (-low or 1.0))
    a1.set_title("fit accuracy")
    a2.set_title("LOO: expected log predictive density")
    if made:
        fig.tight_layout()
    return fig


def plot_design(rows: list[dict], names: list[str], *, fig=None):
    """Laplace contraction of each parameter (columns) under each design (rows), one
    panel per flywheel setting. ``fig``: draw the panels into this (empty) figure."""
    settings = list(dict.fromkeys(r["setting"] for r in rows))
    designs = list(dict.fromkeys(r["design"] for r in rows))
    fig, made = _figure(fig, (0.55 * len(names) * len(settings) + 4, 0.42 * len(designs) + 2))
    axes = fig.subplots(1, len(settings), sharey=True, squeeze=False)
    for ax, s in zip(axes[0], settings):
        grid = np.array([[next(r[n] for r in rows if r["setting"] == s and r["design"] == d) for n in names]
                         for d in designs])
        im = ax.imshow(np.clip(grid, 0, 1), cmap="viridis", vmin=0, vmax=1, aspect="auto")
        for i in range(len(designs)):
            for j in range(len(names)):
                ax.text(j, i, f"{grid[i, j]:.2f}", ha="center", va="center", fontsize=6,
                        color="w" if grid[i, j] < 0.6 else "k")
        ax.set_xticks(range(len(names)), names, rotation=60, fontsize=8)
        ax.set_title(f"setting {s}", fontsize=9)
    axes[0, 0].set_yticks(range(len(designs)), designs, fontsize=8)
    fig.colorbar(im, ax=axes[0, -1], label="contraction (Laplace)")
    fig.suptitle("What each experiment would identify: 1 - var(posterior) / var(prior)", fontsize=10)
    if made:
        fig.tight_layout()
    return fig


def plot_ranks(ranks: dict, L: int, *, bins: int = 10, title: str = "", fig=None):
    """SBC rank histograms, one panel per parameter, with the band a uniform histogram
    stays inside 99 % of the time (per bin, binomial). ``fig``: draw the panels into
    this (empty) figure."""
    from scipy import stats

    names = list(ranks)
    cols = min(4, len(names))
    rows = -(-len(names) // cols)
    fig, made = _figure(fig, (3.2 * cols, 2.4 * rows + 0.6))
    axes = fig.subplots(rows, cols, squeeze=False)
    for ax, name in zip(axes.flat, names):
        r = np.asarray(ranks[name])
        n = len(r)
        lo, hi = stats.binom.ppf([0.005, 0.995], n, 1.0 / bins)
        ax.axhspan(lo, hi, color="0.85")
        ax.axhline(n / bins, color="0.5", lw=0.8)
        ax.hist(r, bins=bins, range=(0, L + 1), color="tab:blue", edgecolor="w")
        ax.set_title(name, fontsize=9)
        ax.tick_params(labelsize=7)
    for ax in list(axes.flat)[len(names):]:
        ax.axis("off")
    fig.suptitle(title + "\ngrey: 99 % band of a uniform histogram", fontsize=9)
    if made:
        fig.tight_layout()
    return fig


def plot_coverage(cases: dict, *, levels=(50, 90), interval: str = "central", fig=None):
    """Coverage of the ``levels`` (per cent) intervals per parameter, one marker per
    calibration case (rows with ``coverage_<q>`` and ``se_<q>``), with bars of 2 binomial
    se (at the nominal level) around each. ``interval`` names the intervals in the
    labels. ``fig``: draw the panels into this (empty) figure."""
    names = []
    for rows in cases.values():
        names += [r["parameter"] for r in rows if r["parameter"] not in names]
    fig, made = _figure(fig, (12, 4.2))
    axes = fig.subplots(1, len(levels), sharey=False, squeeze=False)[0]
    width = 0.8 / max(len(cases), 1)
    for ax, q in zip(axes, levels):
        for j, (case, rows) in enumerate(cases.items()):
            by = {r["parameter"]: r for r in rows}
            x = [i - 0.4 + width * (j + 0.5) for i, n in enumerate(names) if n in by]
            y = [by[n][f"coverage_{q}"] for n in names if n in by]
            se = [by[n][f"se_{q}"] for n in names if n in by]
            ax.errorbar(x, y, yerr=2 * np.asarray(se), fmt="o", ms=4, capsize=2, label=f"{case} ({int(rows[0]['replicates'])})")
        ax.axhline(q / 100, color="k", lw=1)
        ax.set_xticks(range(len(names)))
        ax.set_xticklabels(names, rotation=45, ha="right")
        ax.set_ylabel(" ".join(w for w in ("coverage of the", interval, f"{q} % interval") if w))
        ax.set_title(f"{q} % intervals (bars: 2 binomial se)")
        ax.grid(alpha=0.3)
    axes[-1].legend(fontsize=8, loc="lower left")
    if made:
        fig.tight_layout()
    return fig
