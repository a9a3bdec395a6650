"""The full study: the inertance of each flywheel setting from the paper's 27 records,
led by records of a device richer than the fitted model (``bayes_inerter.study.full``,
whose docstring says what runs): the control and one paper-like laboratory fitted
with the same models, then results/full/REPORT.md led by the paper-like records.
Running it again reuses finished fits and the paper-like records (delete
results/full/paper-like/records to draw another laboratory with --seed); results/full's
fits were sampled with --tempering 4, and only that reuses them.

    python studies/study.py [--processes 2] [--scheduler tcp://host:port] [--seed 0]
                            [--paper-like-steps N] [--max-steps N] [--tempering T (default: none)] [--report-only]
"""

import sys
from pathlib import Path

from bayes_inerter.cli.study_script import study_main
from bayes_inerter.study import full

OUT = Path(__file__).resolve().parents[1] / "results" / "full"

if __name__ == "__main__":
    sys.exit(study_main(full, out=OUT, doc=__doc__))
