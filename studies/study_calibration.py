"""Simulation-based calibration in the configuration the study reports
(``bayes_inerter.study.study_calibration``): devices drawn from a wide physical prior,
10 s generator records at 0.5 and 1.5 Hz fitted with the joint model and the package's
start, the 94 % and 50 % intervals checked directly, failed replicates counted. Writes
results/study-calibration/ (REPORT.md, SECTION.md, coverage.csv, ranks.csv,
coverage.png, ranks.png, one JSON per replicate); running again reuses the replicates
already there. About a minute per replicate and process on a 2-core machine.

    python studies/study_calibration.py [--replicates 200] [--steps 600] [--processes 2]
        [--seed 0] [--out FOLDER] [--single] [--residual motion] [--converge] [--freqs 0.5 1.5]
        [--input-noise 0] [--tempering TEMPS] [--tau-floor N]

``--raise-cap`` raises a folder's cap to ``--max-steps`` before running: the replicates
whose chains stopped unconverged at its old cap move to ``capped-<old>/`` and are fitted
again (``study_calibration.raise_cap``; the others' chains are the same under any cap).

``--summarise`` writes coverage_so_far.csv from the replicates finished in ``--out``
(counts over every chain and over the converged ones), for a run still in chunks, and
rank_correlations.csv: the parameters whose truths' ranks move together; a single-record
calibration's coverage_by_frequency.csv: the same counts at each drive frequency.
``--single`` fits each replicate's one record alone (its frequency ``freqs[k % n]``),
``--residual`` chooses the likelihood, ``--input-noise N`` takes N draws of the
drivetrain's input noise (``LikelihoodSettings.input_noise``; 0 turns it off),
``--tau-floor N`` raises the floor of the discrepancy tau's prior to N newtons in the
fits (``--residual motion``; a probe of the likelihood, results/noise-free-tau-floor),
``--converge`` runs every chain to the convergence rule (at most ``--max-steps``)
instead of ``--steps``. A folder keeps one configuration (settings.json): its
replicates are reused, so a run stopped by a session's end continues where it stopped
(each replicate's fit in progress is kept in ``--work``, by default OUT/.running).
    python studies/study_calibration.py --inspect K [--steps N]

``--inspect K`` runs replicate K again (joint, or ``--single``) with its fit kept
(in ``--work``, by default OUT/.running, as inspect_<joint|single>_seed<S>_K_<steps>)
and prints the joint log posterior at the truth and at the posterior medians, and each
parameter's truth beside its interval: a chain far below the truth's log posterior is
in a wrong basin, one above it has a posterior that excludes the truth.
"""

import sys
from pathlib import Path

from bayes_inerter.cli.study_script import study_main
from bayes_inerter.study import study_calibration

OUT = Path(__file__).resolve().parents[1] / "results" / "study-calibration"

if __name__ == "__main__":
    sys.exit(study_main(study_calibration, out=OUT, doc=__doc__))
