"""What the posterior adds to the paper's own fit: the full study's least-squares fits
(eq. 4, ``bayes-inerter identify``) summarised by device and drive frequency
(``bayes_inerter.study.least_squares_summary``). Reads results/full/least_squares.csv
and results/full/paper-like/least_squares.csv, which ``python studies/study.py``
writes; writes results/least-squares/summary.csv and summary.png.

    python studies/least_squares.py
"""

import sys
from pathlib import Path

from bayes_inerter.cli.study_script import study_main
from bayes_inerter.study import least_squares_summary

OUT = Path(__file__).resolve().parents[1] / "results" / "least-squares"

if __name__ == "__main__":
    sys.exit(study_main(least_squares_summary, out=OUT, doc=__doc__))
