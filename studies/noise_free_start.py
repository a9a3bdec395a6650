"""Where do the default fit's chains on the generator's noise-free records start, and is
that where the posterior peaks? (issue 39, item 1; a probe of
results/noise-free-chains-v3, whose chains' medians it reads).

For record k of the paper's grid (``device.grid_case``, plate mode damped 2 %, every
noise off: ``study.noise_free``), the model ``fit_record`` samples is built and:

- the default start search (``optimize.find_start`` with the seed ``fit_record`` gives
  it: the record's number) is run: its b and log posterior;
- Nelder-Mead (``optimize.local_optimum``) is run from the truth (the likelihood's
  hyper-parameters at their starting values): its b and log posterior;
- the log posterior is profiled in b at the chain's median (every other parameter
  polished with b held): how far below the optimum near the truth the chain sat;
- the log posterior along b alone at the optimum near the truth, b moved by 5e-5 of
  itself: how thin the ridge the chains move along is.

One row per record, appended to ``--out``/start.csv as it ends (a rerun skips the
records there).

    python studies/noise_free_start.py [--records 0 1 ...] [--out results/noise-free-chains-v3]
"""

import argparse
import json
import math
import sys
import time
from pathlib import Path

import numpy as np

from _table import append_missing
from bayes_inerter.device import grid_case
from bayes_inerter.inference.posterior.model import PosteriorModel
from bayes_inerter.inference.sampling.optimize import NM_RESTARTS, find_start, held_optimum, local_optimum
from bayes_inerter.records import generate_record
from bayes_inerter.records.drive import resolve_drive, with_drive
from bayes_inerter.study.noise_free import NOISE_FREE, device

ROOT = Path(__file__).resolve().parents[1]
ZETA_B = 0.02  # the v3 folder's damping ratio
STEP = 5e-5  # the relative move of b alone


def held_b(model: PosteriorModel, theta: np.ndarray, b: float) -> float:
    """The log posterior with b held at ``b`` and every other parameter polished from
    ``theta`` (``optimize.held_optimum``)."""
    return float(model.log_prob(held_optimum(model, theta, model.names.index("b"), math.log(b)))[0])


def one(k: int, chain: dict) -> dict:
    setting, freq = grid_case(k)
    p = device(setting, ZETA_B)
    rec = generate_record(p, freq, settings=NOISE_FREE, setting_name=setting)
    rec = with_drive(rec, resolve_drive(rec, None))
    model = PosteriorModel(rec, "two-port", m_s=rec.metadata["m_s"], m_B=rec.metadata["m_B"])
    i = model.names.index("b")
    t0 = time.perf_counter()
    start, lp_start = find_start(model, np.random.default_rng(k))
    best, lp_best = local_optimum(model, model.to_theta(p), restarts=NM_RESTARTS)
    moved = best.copy()
    moved[i] += STEP
    pct = lambda b: 100.0 * (b / p.b - 1.0)  # noqa: E731
    return {"record": k, "setting": setting, "freq_hz": freq, "chain_b_pct": round(pct(float(chain["b_median"])), 4),
            "start_b_pct": round(pct(model.values(start)["b"]), 4), "start_lp": round(float(lp_start), 2),
            "optimum_b_pct": round(pct(model.values(best)["b"]), 4), "optimum_lp": round(float(lp_best), 2),
            "lp_at_chain_median": round(held_b(model, best, float(chain["b_median"])), 2),
            "lp_drop_b_alone": round(float(lp_best - model.log_prob(moved)[0]), 1),
            "seconds": round(time.perf_counter() - t0, 1)}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--records", type=int, nargs="+", default=list(range(27)))
    ap.add_argument("--out", default=str(ROOT / "results" / "noise-free-chains-v3"))
    args = ap.parse_args()
    out = Path(args.out)
    chains = {int(json.loads(p.read_text())["record"]): json.loads(p.read_text())
              for p in (out / "records").glob("*.json")}
    missing = [k for k in args.records if k not in chains]
    if missing:
        print(f"error: {out}/records has no chain for records {missing}; run studies/noise_free_chains.py first",
              file=sys.stderr)
        return 2
    append_missing(out / "start.csv", "record", args.records, lambda k: one(k, chains[k]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
