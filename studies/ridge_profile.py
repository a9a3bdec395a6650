"""The profile of the log posterior along the nut stiffness k_n: for k_n on a grid over
its prior, the highest log posterior over every other parameter (Nelder-Mead, restarted
while it gains, each grid point started from the one before) and where b and the
viscous friction sit there. It shows the shape the walkers have to cross.

    python studies/ridge_profile.py [--setting A3] [--freq 1] [--points 15]
        [--out runs/long-chain]

The record is the full study's (paper grid, seed 0) for ``--setting`` and ``--freq``;
the first point starts at the generating parameters. Writes
``--out``/<record>/profile.csv and prints it.
"""

import argparse
import math
import sys
from pathlib import Path

import numpy as np
from _table import write_rows

ROOT = Path(__file__).resolve().parents[1]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--setting", default="A3")
    ap.add_argument("--freq", type=float, default=1.0)
    ap.add_argument("--points", type=int, default=15)
    ap.add_argument("--out", default=str(ROOT / "runs" / "long-chain"))
    args = ap.parse_args()

    from tqdm import tqdm

    from bayes_inerter.device import InerterParameters
    from bayes_inerter.inference.posterior.model import PosteriorModel
    from bayes_inerter.inference.sampling.optimize import NM_RESTARTS, local_optimum
    from bayes_inerter.records.generator import paper_record
    from bayes_inerter.study.design import noise_at

    try:
        rec = paper_record(args.setting, args.freq, seed=0)
    except ValueError as exc:
        sys.exit(f"error: {exc}")
    if args.points < 2:
        sys.exit("error: --points must be at least 2")
    model = PosteriorModel(rec)
    truth = rec.metadata["true_parameters"]
    params = InerterParameters(**{k: v for k, v in truth.items() if k in InerterParameters.__dataclass_fields__})
    theta = model.to_theta(params, 1.0, 0.0)
    theta = model.to_theta(params, *noise_at(model, theta))
    i_k = model.names.index("k_n")
    lo, hi = model.bounds()[i_k]
    free = [i for i in range(model.ndim) if i != i_k]

    class Conditional:
        """The posterior with k_n held at one value (what local_optimum needs of a model)."""

        def __init__(self, log_k):
            self.log_k = log_k

        def full(self, y):
            t = theta.copy()
            t[free] = y
            t[i_k] = self.log_k
            return t

        def log_prob(self, y):
            return model.log_prob(self.full(y))

    rows = []
    for log_k in tqdm(np.linspace(lo, hi, args.points), desc="profile", unit="point", file=sys.stderr):
        cond = Conditional(log_k)
        y, lp = local_optimum(cond, theta[free], restarts=NM_RESTARTS)
        theta = cond.full(y)
        v = model.values(theta)
        rows.append({"log10_k_n": round(log_k / math.log(10), 3), "log_post": round(lp, 2), "b": round(v["b"], 2),
                     "c_f": round(v["c_f"], 1), "c_n": f"{v['c_n']:.4g}", "k_B": f"{v['k_B']:.4g}"})
    path = write_rows(Path(args.out) / f"{args.setting}_{args.freq:g}Hz" / "profile.csv", rows)
    print(f"generating values: b {truth['b']}, log10 k_n {math.log10(truth['k_n']):.2f}; wrote {path}")


if __name__ == "__main__":
    main()
