"""What other experiments would identify (frequency, amplitude, sensor band and noise),
and what a Stribeck hump or nut backlash in the device does to the identified b;
Laplace approximations, no sampling. Writes results/design/ (REPORT.md, design.csv,
richer_truth.csv, design.png).

    python studies/design.py [--seed 0]
"""

import argparse
import sys
from pathlib import Path

from tqdm import tqdm

from bayes_inerter.study.design import run_design

OUT = Path(__file__).resolve().parents[1] / "results" / "design"

if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()
    bar = tqdm(desc="design", unit="case", file=sys.stderr)

    def progress(done, total):
        bar.total = total
        bar.update(done - bar.n)

    result = run_design(OUT, seed=args.seed, progress=progress)
    bar.close()
    print(f"wrote {result['report']}")
