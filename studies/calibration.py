"""Simulation-based calibration (Talts et al.): prior draws, records made from them,
posteriors fitted as a user's are, the rank of each truth. Writes
results/calibration/<truth>-<residual>/ (REPORT.md, coverage.csv, ranks.csv, ranks.png,
one JSON per replicate); running again reuses the replicates already there. Then
rewrites results/calibration/REPORT.md and coverage.png: every case there side by side.

    python studies/calibration.py [--replicates 100] [--truth model|generator]
        [--residual ar1|iid] [--friction coulomb|stribeck] [--backlash M] [--noise-corner HZ]
        [--steps 800]
        [--processes 2]
"""

import sys
from pathlib import Path

from bayes_inerter.cli.study_script import study_main
from bayes_inerter.study import calibration

RESULTS = Path(__file__).resolve().parents[1] / "results" / "calibration"

if __name__ == "__main__":
    sys.exit(study_main(calibration, out=lambda config: RESULTS / calibration.case_name(config), doc=__doc__))
