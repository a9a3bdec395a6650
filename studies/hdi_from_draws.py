"""How often does an interval computed from a finite set of posterior draws hold the
truth when the posterior is exactly right? (issue 39, item 4: the calibrations' nominal.)

A calibration counts the 94 % and 50 % highest-density intervals that
``inference.summaries.results.hdi`` computes from each chain's kept draws (about 600 a
chain in results/coverage-sbc-v12). Computed from n draws, the shortest interval that
holds a share of them is itself an estimate, and a short one: it holds less than its
share of the posterior on average. Here the posterior is a standard normal, the truth is
drawn from it, and the n draws are independent or an AR(1) sequence of coefficient rho
(draws that are not independent, as a chain's thinned draws may not be), ``--replicates``
times for each (n, rho); the share of intervals that held is what a perfectly calibrated
posterior would show in a calibration with that many draws.

    python studies/hdi_from_draws.py [--draws 300 600 1200 5000] [--rho 0 0.9]
        [--shape normal uniform halfnormal] [--replicates 4000] [--seed 7]
        [--out results/hdi-from-draws]

``--shape`` gives the posterior other shapes (``SHAPES``): the uniform of a parameter the
record leaves at its prior, and the half-normal of one piled against a wall.

Writes coverage.csv (shape, draws, rho, replicates, the 94 % and 50 % intervals' held shares and
their binomial se) and prints one line for each.
"""

from __future__ import annotations

import argparse
import itertools
import math
from pathlib import Path

import numpy as np
from scipy import signal, special

from bayes_inerter.inference.summaries.results import hdi
from bayes_inerter.study.manifest import script_configuration, write_manifest

from _table import write_table

ROOT = Path(__file__).resolve().parents[1]
LEVELS = (0.94, 0.50)


#: The posterior's shapes (``--shape``): a standard normal; the uniform on (0, 1) of a
#: parameter the record leaves at its prior; the half-normal of one piled against a wall.
SHAPES = ("normal", "uniform", "halfnormal")


def draws(rng: np.random.Generator, n: int, rho: float) -> np.ndarray:
    """n draws of a standard normal, an AR(1) sequence of coefficient ``rho`` (0: independent)."""
    e = rng.standard_normal(n) * math.sqrt(1.0 - rho * rho)
    e[0] = rng.standard_normal()
    return signal.lfilter([1.0], [1.0, -rho], e) if rho else e


def shaped(z: np.ndarray, shape: str) -> np.ndarray:
    """Standard normal values ``z`` carried to ``shape`` by a monotone map (its normal
    CDF for the uniform, the absolute value for the half-normal), which keeps a
    sequence's dependence."""
    if shape == "uniform":
        return special.ndtr(z)
    return np.abs(z) if shape == "halfnormal" else z


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--draws", type=int, nargs="+", default=[300, 600, 1200, 5000])
    ap.add_argument("--rho", type=float, nargs="+", default=[0.0, 0.9])
    ap.add_argument("--shape", nargs="+", default=["normal"], choices=SHAPES)
    ap.add_argument("--replicates", type=int, default=4000)
    ap.add_argument("--seed", type=int, default=7)
    ap.add_argument("--out", default=str(ROOT / "results" / "hdi-from-draws"))
    args = ap.parse_args(argv)
    if min(args.draws) < 20 or not all(0.0 <= r < 1.0 for r in args.rho) or args.replicates < 10:
        ap.error("--draws must be at least 20, --rho in [0, 1), --replicates at least 10")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    write_manifest(out, script_configuration())
    rows = []
    for shape, n, rho in itertools.product(args.shape, args.draws, args.rho):
        # the normal's seeds as before the shapes existed, so its rows are remade as they were
        key = [args.seed, n, int(round(rho * 1000))] + ([] if shape == "normal" else [SHAPES.index(shape)])
        rng = np.random.default_rng(key)
        held = {level: 0 for level in LEVELS}
        for _ in range(args.replicates):
            x, truth = shaped(draws(rng, n, rho), shape), shaped(rng.standard_normal(), shape)
            for level in LEVELS:
                lo, hi = hdi(x, level)
                held[level] += bool(lo <= truth <= hi)
        row = {"shape": shape, "draws": n, "rho": rho, "replicates": args.replicates}
        for level in LEVELS:
            p = held[level] / args.replicates
            row[f"held_{round(100 * level)}"] = f"{p:.4f}"
            row[f"se_{round(100 * level)}"] = f"{math.sqrt(p * (1 - p) / args.replicates):.4f}"
        rows.append(row)
        print(f"{shape}, {n} draws, rho {rho:g}: the 94 % interval held {row['held_94']} (se {row['se_94']}), "
              f"the 50 % {row['held_50']} (se {row['se_50']})", flush=True)
    write_table(out / "coverage.csv", rows)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
