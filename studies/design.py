"""What other experiments would identify (frequency, amplitude, sensor band and noise),
and what a Stribeck hump or nut backlash in the device does to the identified b;
Laplace approximations, no sampling (``bayes_inerter.study.design``). Writes
results/design/ (REPORT.md, design.csv, richer_truth.csv, design.png, one JSON per case
in cases/, reused by a rerun).

    python studies/design.py [--seed 0] [--settings A0 A3 B2] [--processes 2]
"""

import sys
from pathlib import Path

from bayes_inerter.cli.study_script import study_main
from bayes_inerter.study import design

OUT = Path(__file__).resolve().parents[1] / "results" / "design"

if __name__ == "__main__":
    sys.exit(study_main(design, out=OUT, doc=__doc__))
