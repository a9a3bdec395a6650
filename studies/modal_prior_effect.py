"""What the plate mode's damping prior does to b (issue 39, item 3: "its effect on b
shown").

The default motion-in fit samples the bearing's damper as the plate mode's damping
ratio zeta_B, log-uniform on 0.5 to 10 % (``priors.MODAL_PRIORS``, an assumption);
``PosteriorModel(modal=False)`` samples c_B log-uniform instead, as the time-domain
likelihoods do. For each paper-like record (``records.paper_like.paper_like_record`` of
the laboratory ``--seed``) and each prior, the model ``fit_record`` samples is built and
its optimum found as the fit finds its start: the default search
(``optimize.find_start``, seeded with the laboratory), the likelihood's reference taken
there (``PosteriorModel.with_reference``), then polished in Hessian-whitened
coordinates (``optimize.whitened_optimum``). A point, not a chain: b's error at the
optimum, the damping ratio there and the log posterior.

One row per record and prior, appended to ``--out``/modal_prior.csv as it ends (a rerun
skips the rows there).

    python studies/modal_prior_effect.py [--records A3:0.5 A3:1 A6:0.5 B2:1 A0:1 A5:1.5] [--seed 11]
        [--out results/likelihood-candidates]
"""

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from _table import append_row, git_commit, read_rows, record_arg
from bayes_inerter import paper_parameters
from bayes_inerter.inference.posterior.model import PosteriorModel
from bayes_inerter.inference.posterior.parameters import ParameterMap
from bayes_inerter.inference.sampling.optimize import find_start, whitened_optimum
from bayes_inerter.records.paper_like import paper_like_record

ROOT = Path(__file__).resolve().parents[1]
#: the six paper-like design records the plate mode's prior was first looked at on
RECORDS = ("A3:0.5", "A3:1", "A6:0.5", "B2:1", "A0:1", "A5:1.5")
PRIORS = {"damping ratio (default)": True, "c_B log-uniform": False}
FIELDS = ("seed", "setting", "freq_hz", "prior", "b_true", "b_pct", "zeta_B", "c_B", "k_B", "lp", "seconds", "commit")


def one(seed: int, setting: str, freq: float, prior: str, commit: str) -> dict:
    rec = paper_like_record(setting, freq, seed=seed)
    model = PosteriorModel(rec, modal=PRIORS[prior])
    t0 = time.perf_counter()
    start, _ = find_start(model, np.random.default_rng(seed))
    model = model.with_reference(start)
    theta, lp = whitened_optimum(model, start)
    v = model.values(theta)
    b = paper_parameters(setting).b
    return {"seed": seed, "setting": setting, "freq_hz": freq, "prior": prior, "b_true": b,
            "b_pct": round(100.0 * (v["b"] / b - 1.0), 3),
            "zeta_B": round(float(ParameterMap(split=False, modal=True, m_B=model.m_B).sampled(v)["zeta_B"]), 6),
            "c_B": float(f"{v['c_B']:.4g}"), "k_B": float(f"{v['k_B']:.4g}"), "lp": round(float(lp), 2),
            "seconds": round(time.perf_counter() - t0, 1), "commit": commit}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--records", nargs="+", default=[record_arg(r) for r in RECORDS], type=record_arg)
    ap.add_argument("--seed", type=int, default=11, help="the paper-like laboratory (default: 11, a design seed)")
    ap.add_argument("--out", default=str(ROOT / "results" / "likelihood-candidates"))
    args = ap.parse_args()
    path = Path(args.out) / "modal_prior.csv"
    done = {(int(r["seed"]), r["setting"], float(r["freq_hz"]), r["prior"]) for r in read_rows(path)}
    commit = git_commit(ROOT)
    for setting, freq in args.records:
        for prior in PRIORS:
            if (args.seed, setting, float(freq), prior) in done:
                continue
            row = one(args.seed, setting, float(freq), prior, commit)
            append_row(path, row, FIELDS)
            print(f"{setting} {freq:g} Hz, {prior}: b {row['b_pct']:+.2f} %, zeta_B {row['zeta_B']:.3g}, "
                  f"log posterior {row['lp']}, {row['seconds']} s", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
