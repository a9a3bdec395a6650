"""Does the default fit's own posterior hold b on records of a richer device?
(``bayes_inerter.study.paper_like_coverage``, whose docstring says what a replicate
is): one paper-like record per replicate, fitted as ``bayes-inerter fit`` fits it, each
chain to the convergence rule. One JSON per replicate in --out/replicates (run again to
go on); replicates.csv and coverage.csv from all of them.

    python studies/paper_like_coverage.py --replicates 27 [--seed0 1000] [--out results/paper-like-coverage]
        [--max-steps 20000] [--processes 2] [--family default] [--model two-port-stribeck]
        [--likelihood input_noise=16]
        [--freq 0.5] [--parity odd] [--duration 20] [--work runs/NAME] [--summarise [--against FOLDER]]

With --summarise --against FOLDER (the same replicates fitted otherwise) it also writes
pairs.csv and pairs_summary.csv, replicate by replicate.
"""

import sys
from pathlib import Path

from bayes_inerter.cli.study_script import study_main
from bayes_inerter.study import paper_like_coverage

OUT = Path(__file__).resolve().parents[1] / "results" / "paper-like-coverage"

if __name__ == "__main__":
    sys.exit(study_main(paper_like_coverage, out=OUT, doc=__doc__))
