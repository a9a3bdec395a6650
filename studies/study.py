"""The full study: all 27 generated records of the paper's grid, two-port posteriors run
until converged, and the rigid and linear models on the 1 Hz records; writes
results/full/ (REPORT.md, tables, figures). Running it again reuses finished fits.

    python studies/study.py [--processes 2] [--scheduler tcp://host:port]
"""

import argparse
import sys
from pathlib import Path

from bayes_inerter.cli import main

OUT = Path(__file__).resolve().parents[1] / "results" / "full"

if __name__ == "__main__":
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--processes", default=None)
    ap.add_argument("--scheduler", default=None)
    args = ap.parse_args()
    argv = ["study", "--out", str(OUT)]
    if args.processes:
        argv += ["--processes", args.processes]
    if args.scheduler:
        argv += ["--scheduler", args.scheduler]
    sys.exit(main(argv))
