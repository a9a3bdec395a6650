"""How often does the friction split's mirror hold a mode the start search missed?

On paper-like records of design laboratories (never the coverage seeds): the start
search's optimum with the mirror turned off (``optimize.MIRROR_SHARES = ()``), the
likelihood's reference set there, and that optimum's mirror (f_share to 1 - f_share)
polished as the search polishes (``optimize.mirrored_modes`` with no limit in nats).
A row per record: both log posteriors, both f_share, the gain in nats (the mirror's
fields empty where its polish came back within ``optimize.MIRROR_SEPARATION`` of the
start), and the seconds of the search and of the mirror's polish (one process). A row is written after every
record, and a rerun skips the rows already there.

    python studies/mirror_modes.py [--labs 11] [--cases A0@0.5 A3@1 ...]
        [--out results/likelihood-candidates/mirror_modes.csv]
"""

from __future__ import annotations

import argparse
import math
import time
from pathlib import Path

import numpy as np

from bayes_inerter.inference import PosteriorModel
from bayes_inerter.inference.sampling import optimize
from bayes_inerter.masses import resolve_masses
from bayes_inerter.records.drive import resolve_drive, with_drive
from bayes_inerter.records.paper_like import paper_like_record

from _table import append_row, read_rows

ROOT = Path(__file__).resolve().parents[1]
CASES = tuple(f"{s}@{f:g}" for s in ("A0", "A3", "B2") for f in (0.5, 1.0, 1.5)) + ("A6@0.5", "B1@1", "B1@1.5")
FIELDS = ("lab", "case", "start_f_share", "start_lp", "mirror_f_share", "mirror_lp", "gain_nats",
          "search_s", "mirror_s")


def one(lab: int, case: str) -> dict:
    setting, freq = case.split("@")
    record = paper_like_record(setting, float(freq), seed=lab)
    record = with_drive(record, resolve_drive(record))  # as fit_record does
    masses = resolve_masses(record)
    model = PosteriorModel(record, "two-port", m_s=masses.m_s, m_B=masses.m_B)
    t0 = time.perf_counter()
    kept, optimize.MIRROR_SHARES = optimize.MIRROR_SHARES, ()
    try:
        theta, _ = optimize.find_start(model, np.random.default_rng(lab))
    finally:
        optimize.MIRROR_SHARES = kept
    t1 = time.perf_counter()
    model = model.with_reference(theta)
    lp = float(model.log_prob(theta)[0])
    modes = optimize.mirrored_modes(model, theta, lp, nats=math.inf)
    t2 = time.perf_counter()
    i = model.names.index("f_share")
    row = {"lab": lab, "case": case, "start_f_share": round(float(theta[i]), 3), "start_lp": round(lp, 2),
           "mirror_f_share": "", "mirror_lp": "", "gain_nats": "",  # empty: the mirror came back to the start
           "search_s": round(t1 - t0, 1), "mirror_s": round(t2 - t1, 1)}
    if modes:
        got, got_lp = modes[0]
        row.update(mirror_f_share=round(float(got[i]), 3), mirror_lp=round(float(got_lp), 2),
                   gain_nats=round(float(got_lp) - lp, 2))
    return row


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--labs", type=int, nargs="+", default=[11])
    ap.add_argument("--cases", nargs="+", default=list(CASES))
    ap.add_argument("--out", type=Path, default=ROOT / "results" / "likelihood-candidates" / "mirror_modes.csv")
    args = ap.parse_args(argv)
    done = {(int(r["lab"]), r["case"]) for r in read_rows(args.out)}
    for lab in args.labs:
        for case in args.cases:
            if (lab, case) not in done:
                append_row(args.out, one(lab, case), FIELDS)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
