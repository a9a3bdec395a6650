"""What the posterior adds to the paper's own fit: the full study's least-squares fits
(eq. 4, ``bayes-inerter identify``) summarised by device and drive frequency.

The study of results/least-squares (``studies/least_squares.py``, through
``cli.study_script``): :class:`Config` and :func:`run` read the full study's
least_squares.csv (the control: records made by the fitted model) and
paper-like/least_squares.csv (one paper-like laboratory) and write summary.csv (per
device and frequency: records, how often each 94 % interval holds the generating b,
median widths, mean phi by least squares, by the posterior and in Table 2) and
summary.png. The fits themselves are ``study.least_squares``'s, run by the full study.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .analysis import read_csv, write_csv
from .output import StudyOutput

__all__ = ["Config", "run", "KINDS", "summary_row", "plot_summary"]

#: The intervals compared: (column key, label).
KINDS = (("ls", "least squares (Hessian)"), ("post", "posterior HDI"), ("honest", "honest"))


@dataclass(frozen=True)
class Config:
    """``full``: the full study's folder (None: ``full`` beside the output folder)."""

    full: str | None = field(default=None, metadata={"help": "the full study's folder (default: OUT/../full)"})


def summary_row(device: str, rows: list[dict], freq) -> dict:
    """One row of summary.csv: ``rows`` (a least_squares.csv's, read as numbers) of
    ``device`` at ``freq``."""
    out = {"device": device, "freq_hz": freq, "records": len(rows)}
    for key, _ in KINDS:
        held = [r[f"covers_{key}"] for r in rows if isinstance(r.get(f"covers_{key}"), bool)]
        widths = [(r[f"b_{key}_97%"] - r[f"b_{key}_3%"]) / r["b_truth"] for r in rows
                  if isinstance(r.get(f"b_{key}_3%"), float) and isinstance(r.get(f"b_{key}_97%"), float)]
        out[f"{key}_intervals"] = len(held)
        out[f"{key}_hold"] = sum(held)
        out[f"{key}_median_width_%"] = 100 * float(np.median(widths)) if widths else None
    for key in ("phi_ls", "phi_post", "phi_paper"):
        vals = [r[key] for r in rows if isinstance(r.get(key), float)]
        out[f"mean_{key}"] = float(np.mean(vals)) if vals else None
    return out


def plot_summary(table: list[dict]):
    """summary.png's figure: the share of 94 % intervals that hold the generating b, and
    their median widths, by device and frequency."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    per = [r for r in table if r["freq_hz"] != "all"]
    labels = [f"{r['device']}\n{r['freq_hz']} Hz" for r in per]
    x = np.arange(len(per))
    for i, (key, name) in enumerate(KINDS):
        share = [r[f"{key}_hold"] / r[f"{key}_intervals"] if r[f"{key}_intervals"] else np.nan for r in per]
        width = [r[f"{key}_median_width_%"] if r[f"{key}_median_width_%"] is not None else np.nan for r in per]
        axes[0].bar(x + (i - 1) * 0.27, share, 0.27, label=name, color=f"C{i}")
        axes[1].bar(x + (i - 1) * 0.27, width, 0.27, label=name, color=f"C{i}")
    axes[0].axhline(0.94, color="k", lw=0.8, ls="--")
    axes[0].set_ylabel("share of 94 % intervals holding the generating b")
    axes[0].set_ylim(0, 1.05)
    axes[1].set_yscale("log")
    axes[1].set_ylabel("median 94 % width, % of b")
    for ax in axes:
        ax.set_xticks(x, labels, fontsize=8)
    axes[0].legend(fontsize=8, loc="lower left")
    axes[0].set_title("coverage, record by record (honest: identified records only)", fontsize=9)
    axes[1].set_title("width", fontsize=9)
    fig.tight_layout()
    return fig


def run(config: Config, out, executor=None, *, progress=None) -> StudyOutput:
    """summary.csv and summary.png into ``out`` from the full study's least-squares
    tables (``executor`` and ``progress`` unused: it reads two tables)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(out)
    full = Path(config.full) if config.full else out.parent / "full"
    sources = {"control": full / "least_squares.csv", "paper-like": full / "paper-like" / "least_squares.csv"}
    for path in sources.values():
        if not path.is_file():
            raise ValueError(f"{path} is missing; run the full study (studies/study.py) first")
    table = []
    for device, path in sources.items():
        rows = read_csv(path)
        for f in sorted({r["freq_hz"] for r in rows}):
            table.append(summary_row(device, [r for r in rows if r["freq_hz"] == f], f"{f:g}"))
        table.append(summary_row(device, rows, "all"))
    out.mkdir(parents=True, exist_ok=True)
    write_csv(out / "summary.csv", table)
    fig = plot_summary(table)
    fig.savefig(out / "summary.png", dpi=110)
    plt.close(fig)
    lines = [", ".join(f"{k} {v:.3g}" if isinstance(v, float) else f"{k} {v}" for k, v in r.items()) for r in table]
    return StudyOutput(written=(out / "summary.csv", out / "summary.png"), lines=tuple(lines),
                       values={"summary": table})
