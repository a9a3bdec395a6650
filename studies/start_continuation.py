"""Does the start search's tau continuation find higher starts, and where?

Issue 39, item 1: on the generator's noise-free records the start search ended in
basins hundreds of nats below the optimum near the truth (results/noise-free-chains).
``optimize.tau_continued`` polishes the start again with the discrepancy's sd held at
``--factors`` times its own, largest first, then free (``optimize.TAU_CONTINUATION``).
This script runs ``optimize.find_start`` on each record twice from the same seed, with
the continuation off and on, and writes the starts' log posterior (the model without its
reference point, as the search sees it), b's error against the truth, the gain, tau and
the seconds of each search.

The records (``--set``):

- ``sbc``: single records of the model's own physics, the calibration's devices of
  ``--sbc-seed`` (design seed 4 by default), replicates 0 to ``--sbc-replicates`` - 1,
  at (0.5, 1, 1.5) Hz in turn (``study.study_calibration.replicate_device``);
- ``paper-like``: records of the paper-like device of design laboratories 11 to 13
  (``records.paper_like``), eight settings and frequencies named in :data:`PAPER_LIKE`;
- ``noise-free``: the generator's records of Table I and Table 2 with every noise off,
  records ``--noise-free`` of the paper's grid (``grid_case``).

    python studies/start_continuation.py [--set sbc paper-like noise-free] [--out results/start-continuation/starts.csv]
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import time
from pathlib import Path

import numpy as np

from _table import append_row, read_rows, sbc_design_records
from bayes_inerter.device import grid_case
from bayes_inerter import paper_parameters
from bayes_inerter.inference import PosteriorModel
from bayes_inerter.inference.sampling import optimize
from bayes_inerter.records import GeneratorSettings, generate_record
from bayes_inerter.records.paper_like import paper_like_record
from bayes_inerter.study.study_calibration import STUDY_SBC_PRIORS

ROOT = Path(__file__).resolve().parents[1]
#: The paper-like design records: (setting, frequency in Hz, laboratory).
PAPER_LIKE = (("A3", 0.5, 11), ("B1", 1.0, 11), ("A6", 1.5, 11), ("A0", 1.0, 12), ("B2", 0.5, 12),
              ("A5", 1.5, 12), ("A1", 1.0, 13), ("A4", 0.5, 13))
#: The noise-free records: indices of the paper's grid (``grid_case``).
NOISE_FREE = (0, 1, 2, 22, 23, 24, 25, 26, 21, 3)
FIELDS = ("set", "record", "freq_hz", "seed", "variant", "log_post", "b_error_pct", "gain", "tau", "seconds")


def records(which: str, args, *, zeta_b: float | None = None, seed_by_record: bool = False):
    """(record label, frequency, seed, model, true b) of each record of the set ``which``;
    the noise-free device's plate mode damped ``zeta_b`` (None: Table I's c_B) and each
    noise-free record searched from its grid index as seed (``seed_by_record``; else 0)."""
    if which == "sbc":
        for k, freq, record, b_true in sbc_design_records(args.sbc_seed, range(args.sbc_replicates)):
            yield str(k), freq, args.sbc_seed, PosteriorModel(record, priors=STUDY_SBC_PRIORS), b_true
    elif which == "paper-like":
        for setting, freq, lab in PAPER_LIKE:
            yield setting, freq, lab, PosteriorModel(paper_like_record(setting, freq, seed=lab)), \
                paper_parameters(setting).b
    else:
        quiet = GeneratorSettings(force_noise=0.0, accel_noise=0.0, disp_noise=0.0)
        for k in args.noise_free:
            setting, freq = grid_case(k)
            p = paper_parameters(setting)
            if zeta_b is not None:
                p = dataclasses.replace(p, c_B=2.0 * zeta_b * math.sqrt(p.k_B * p.m_B))
            yield (setting, freq, k if seed_by_record else 0,
                   PosteriorModel(generate_record(p, freq, settings=quiet, setting_name=setting)), p.b)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--set", nargs="+", default=["sbc", "paper-like", "noise-free"],
                    choices=["sbc", "paper-like", "noise-free"])
    ap.add_argument("--sbc-seed", type=int, default=4)
    ap.add_argument("--sbc-replicates", type=int, default=12)
    ap.add_argument("--noise-free", type=int, nargs="+", default=list(NOISE_FREE), metavar="K")
    ap.add_argument("--factors", type=float, nargs="+", default=[1000.0, 100.0, 10.0])
    ap.add_argument("--out", type=Path, default=ROOT / "results" / "start-continuation" / "starts.csv")
    args = ap.parse_args(argv)
    done = {(r["set"], r["record"], r["freq_hz"], r["seed"], r["variant"]) for r in read_rows(args.out)}
    for which in args.set:
        for label, freq, seed, model, b_true in records(which, args):
            for variant, factors in (("before", ()), ("continued", tuple(args.factors))):
                key = (which, label, str(float(freq)), str(seed), variant)
                if key in done:
                    continue
                t0 = time.perf_counter()
                theta, lp = optimize.find_start(model, np.random.default_rng(seed), continuation=factors)
                values = dict(zip(model.names, model.to_values(theta)))
                append_row(args.out, {"set": which, "record": label, "freq_hz": float(freq), "seed": seed,
                                      "variant": variant, "log_post": round(float(lp), 2),
                                      "b_error_pct": round(100.0 * (values["b"] / b_true - 1.0), 3),
                                      "gain": round(float(values.get("gain", 1.0)), 4),
                                      "tau": float(f"{values['tau']:.4g}"),
                                      "seconds": round(time.perf_counter() - t0, 1)}, FIELDS)
    return 0


if __name__ == "__main__":
    sys.exit(main())
