"""What the posterior adds to the paper's own fit: the full study's least-squares fits
(eq. 4, ``bayes-inerter identify``) summarised by device and drive frequency.

Reads results/full/least_squares.csv (the control: records made by the fitted model)
and results/full/paper-like/least_squares.csv (one paper-like laboratory), which
``python studies/study.py`` writes, and writes into results/least-squares: summary.csv
(per device and frequency: records, how often each 94 % interval holds the generating
b, median widths, mean phi by least squares, by the posterior and in Table 2) and
summary.png.

    python studies/least_squares.py
"""

import csv
import subprocess
import sys
from pathlib import Path

import numpy as np

from bayes_inerter.study.analysis import write_csv
from bayes_inerter.study.manifest import script_configuration, write_manifest

ROOT = Path(__file__).resolve().parents[1]
SOURCES = {"control": ROOT / "results" / "full" / "least_squares.csv",
           "paper-like": ROOT / "results" / "full" / "paper-like" / "least_squares.csv"}
OUT = ROOT / "results" / "least-squares"
KINDS = (("ls", "least squares (Hessian)"), ("post", "posterior HDI"), ("honest", "honest"))


def _read(path: Path) -> list[dict]:
    def num(v):
        if v in ("True", "False"):
            return v == "True"
        try:
            return float(v)
        except ValueError:
            return v or None

    with open(path, newline="") as f:
        return [{k: num(v) for k, v in r.items()} for r in csv.DictReader(f)]


def _summary(device: str, rows: list[dict], freq) -> dict:
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


def main() -> int:
    for path in SOURCES.values():
        if not path.is_file():
            print(f"error: {path} is missing; run python studies/study.py first", file=sys.stderr)
            return 1
    table = []
    for device, path in SOURCES.items():
        rows = _read(path)
        for f in sorted({r["freq_hz"] for r in rows}):
            table.append(_summary(device, [r for r in rows if r["freq_hz"] == f], f"{f:g}"))
        table.append(_summary(device, rows, "all"))
    write_manifest(OUT, script_configuration())
    write_csv(OUT / "summary.csv", table)
    import matplotlib

    matplotlib.use("Agg")
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
    fig.savefig(OUT / "summary.png", dpi=110)
    plt.close(fig)
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                            text=True).stdout.strip()
    print(f"commit {commit}")
    for r in table:
        print(", ".join(f"{k} {v:.3g}" if isinstance(v, float) else f"{k} {v}" for k, v in r.items()))
    print(f"wrote {OUT}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
