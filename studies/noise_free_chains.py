"""Does the default fit's posterior hold b on the generator's noise-free records?
(``bayes_inerter.study.noise_free``): record k of the paper's grid made with every
noise off, fitted as ``bayes-inerter fit`` fits it, each chain to the convergence rule.
One JSON per record in --out/records (run again to go on), chains.csv from all.

    python studies/noise_free_chains.py [--records 27] [--out results/noise-free-chains]
        [--zeta-B 0.02] [--max-steps 20000] [--tempering T [--hottest-beta B]] [--only K ...]
        [--tau-floor N] [--processes 1] [--summarise]
"""

import sys
from pathlib import Path

from bayes_inerter.cli.study_script import study_main
from bayes_inerter.study import noise_free

OUT = Path(__file__).resolve().parents[1] / "results" / "noise-free-chains"

if __name__ == "__main__":
    sys.exit(study_main(noise_free, out=OUT, doc=__doc__))
