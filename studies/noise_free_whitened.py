"""Does a polish whitened by the Hessian take the default start on the generator's
noise-free records up to the optimum near the truth, and is b there within 0.1 %?
(issue 39, item 1; a probe of results/noise-free-chains-v3, beside its start.csv).

For record k of the paper's grid (``device.grid_case``, plate mode damped 2 %, every
noise off: ``study.noise_free``), the model ``fit_record`` samples is built and:

- the default start search (``optimize.find_start``, seeded with the record's number
  as ``fit_record`` seeds it): its b and log posterior, and its seconds;
- that start polished by ``optimize.whitened_optimum``: its b, log posterior, seconds;
- the truth (the likelihood's hyper-parameters at their starting values) polished by
  ``optimize.local_optimum`` and then ``whitened_optimum``: the highest point known
  near the truth, its b and log posterior.

One row per record, appended to ``--out``/whitened.csv as it ends (a rerun skips the
records there).

    python studies/noise_free_whitened.py [--records 0 1 ...] [--out results/noise-free-chains-v3]
"""

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from _table import append_missing
from bayes_inerter.device import grid_case
from bayes_inerter.inference.posterior.model import PosteriorModel
from bayes_inerter.inference.sampling.optimize import NM_RESTARTS, find_start, local_optimum, whitened_optimum
from bayes_inerter.records import generate_record
from bayes_inerter.records.drive import resolve_drive, with_drive
from bayes_inerter.study.noise_free import NOISE_FREE, device

ROOT = Path(__file__).resolve().parents[1]
ZETA_B = 0.02  # the v3 folder's damping ratio


def one(k: int) -> dict:
    setting, freq = grid_case(k)
    p = device(setting, ZETA_B)
    rec = generate_record(p, freq, settings=NOISE_FREE, setting_name=setting)
    rec = with_drive(rec, resolve_drive(rec, None))
    model = PosteriorModel(rec, "two-port", m_s=rec.metadata["m_s"], m_B=rec.metadata["m_B"])
    pct = lambda theta: round(100.0 * (model.values(theta)["b"] / p.b - 1.0), 4)  # noqa: E731
    t0 = time.perf_counter()
    start, lp_start = find_start(model, np.random.default_rng(k))
    t1 = time.perf_counter()
    polished, lp_polished = whitened_optimum(model, start)
    t2 = time.perf_counter()
    near, _ = local_optimum(model, model.to_theta(p), restarts=NM_RESTARTS)
    truth, lp_truth = whitened_optimum(model, near)
    return {"record": k, "setting": setting, "freq_hz": freq,
            "start_b_pct": pct(start), "start_lp": round(float(lp_start), 2), "start_seconds": round(t1 - t0, 1),
            "whitened_b_pct": pct(polished), "whitened_lp": round(float(lp_polished), 2),
            "whitened_seconds": round(t2 - t1, 1),
            "truth_b_pct": pct(truth), "truth_lp": round(float(lp_truth), 2)}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--records", type=int, nargs="+", default=list(range(27)))
    ap.add_argument("--out", default=str(ROOT / "results" / "noise-free-chains-v3"))
    args = ap.parse_args()
    append_missing(Path(args.out) / "whitened.csv", "record", args.records, one)
    return 0


if __name__ == "__main__":
    sys.exit(main())
