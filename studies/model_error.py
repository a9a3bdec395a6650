"""Coverage of b's intervals on records of a device richer than the model
(``bayes_inerter.study.model_error``, whose docstring says what each method is): one
paper-like laboratory and setting per replicate, each fit summarised by its Laplace
approximation. Writes replicates.csv, coverage.csv and coverage.png into --out (each
replicate's rows also to replicates.partial.csv as it ends: run again to go on).

    python studies/model_error.py --replicates 100 --out results/model-error [--processes 2]
        [--methods M ...] [--duration 10] [--seed 0] [--device paper-like|model] [--only K ...]
        [--rescore]
"""

import sys
from pathlib import Path

from bayes_inerter.cli.study_script import study_main
from bayes_inerter.study import model_error

OUT = Path(__file__).resolve().parents[1] / "runs" / "model-error"

if __name__ == "__main__":
    sys.exit(study_main(model_error, out=OUT, doc=__doc__))
