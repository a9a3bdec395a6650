"""Why identified inertance differs from theory: the structural model across settings
(``bayes_inerter.study.structure``) fitted to the full study's identified b's (the
control's joint draws and the paper-like study's honest intervals, both from
results/full, which ``python studies/study.py`` makes), each with a realistic
identification error. Writes into results/structure: explanations.csv, terms.csv,
frequency.csv, structure.png, summary.json and SECTION.md (taken into
results/full/REPORT.md by ``python studies/study.py --report-only``).

    python studies/structure.py [--seed 0] [--steps 6000] [--per-setting 0.015] [--common 0.02]
"""

import sys
from pathlib import Path

from bayes_inerter.cli.study_script import study_main
from bayes_inerter.study import structure

OUT = Path(__file__).resolve().parents[1] / "results" / "structure"

if __name__ == "__main__":
    sys.exit(study_main(structure, out=OUT, doc=__doc__))
