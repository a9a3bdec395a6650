"""Do the harmonic means over a whole-sample span move b and tau on records at 1.5 Hz?

Issue 39, item 1: on the generator's noise-free B2 record at 1.5 Hz and 1 kHz (666.67
samples a period) the harmonic means taken over each period's own window leaked what
lies above the basis; the discrepancy's tau took it up (0.23 N) and let b slide along
the nut's ridge. ``harmonic.harmonic_data`` now takes the means over the longest span of
whole periods that is a whole number of samples (``harmonic.MAX_SPAN_PERIODS``; 1
restores the periods' means). This script runs ``optimize.find_start`` on each record
twice from the same seed, with the periods' means (``periods``) and the span's
(``span``), and writes the start's log posterior (the model without its reference
point, as the search sees it), b's error against the truth, tau, b's sd in the Laplace
approximation at the start (a stand-in for the posterior's, named as such; the model
with its reference point there) and the seconds of each search.

The records, all at 1.5 Hz (``--set``; design seeds only):

- ``sbc``: single records of the model's own physics, the calibration's devices of
  ``--sbc-seed`` (design seed 4), the replicates whose record is at 1.5 Hz among the
  first ``--sbc-replicates``;
- ``paper-like``: the paper-like device of design laboratory ``--lab`` (11), every
  setting;
- ``noise-free``: the generator's records of Table I and Table 2, every noise off, every
  setting.

    python studies/whole_sample_span.py [--set sbc paper-like noise-free] [--out results/whole-sample-span/starts.csv]
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

from _table import append_row, read_rows, sbc_design_records
from bayes_inerter import paper_parameters
from bayes_inerter.inference import PosteriorModel
from bayes_inerter.inference.posterior import harmonic
from bayes_inerter.inference.sampling import optimize
from bayes_inerter.records import GeneratorSettings, generate_record
from bayes_inerter.records.paper_like import paper_like_record
from bayes_inerter.study.study_calibration import STUDY_SBC_PRIORS

ROOT = Path(__file__).resolve().parents[1]
SETTINGS = ("A0", "A1", "A2", "A3", "A4", "A5", "A6", "B1", "B2")
FREQ = 1.5
VARIANTS = (("periods", 1), ("span", harmonic.MAX_SPAN_PERIODS))
FIELDS = ("set", "record", "seed", "variant", "log_post", "b_error_pct", "b_sd_laplace_pct", "tau", "seconds")


def records(which: str, args):
    """(record label, seed, a function making the model, true b) of each record of ``which``."""
    if which == "sbc":
        for k, _, record, b_true in sbc_design_records(args.sbc_seed, range(2, args.sbc_replicates, 3)):  # at 1.5 Hz
            yield str(k), args.sbc_seed, (lambda r=record: PosteriorModel(r, priors=STUDY_SBC_PRIORS)), b_true
    elif which == "paper-like":
        for setting in SETTINGS:
            rec = paper_like_record(setting, FREQ, seed=args.lab)
            yield setting, args.lab, (lambda r=rec: PosteriorModel(r)), paper_parameters(setting).b
    else:
        quiet = GeneratorSettings(force_noise=0.0, accel_noise=0.0, disp_noise=0.0)
        for setting in SETTINGS:
            p = paper_parameters(setting)
            rec = generate_record(p, FREQ, settings=quiet, setting_name=setting)
            yield setting, 0, (lambda r=rec: PosteriorModel(r)), p.b


def _b_sd_pct(model: PosteriorModel, theta: np.ndarray) -> float:
    """b's sd in the Laplace approximation at ``theta``, % (b is sampled in log scale)."""
    i = model.names.index("b")
    cov = optimize.laplace_covariance(model.with_reference(theta), theta)
    return 100.0 * math.sqrt(max(float(cov[i, i]), 0.0))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--set", nargs="+", default=["noise-free", "paper-like", "sbc"],
                    choices=["sbc", "paper-like", "noise-free"])
    ap.add_argument("--sbc-seed", type=int, default=4)
    ap.add_argument("--sbc-replicates", type=int, default=30)
    ap.add_argument("--lab", type=int, default=11)
    ap.add_argument("--out", type=Path, default=ROOT / "results" / "whole-sample-span" / "starts.csv")
    args = ap.parse_args(argv)
    done = {(r["set"], r["record"], r["seed"], r["variant"]) for r in read_rows(args.out)}
    kept = harmonic.MAX_SPAN_PERIODS
    try:
        for which in args.set:
            for label, seed, make, b_true in records(which, args):
                for variant, span in VARIANTS:
                    if (which, label, str(seed), variant) in done:
                        continue
                    harmonic.MAX_SPAN_PERIODS = span
                    t0 = time.perf_counter()
                    model = make()
                    theta, lp = optimize.find_start(model, np.random.default_rng(seed))
                    values = dict(zip(model.names, model.to_values(theta)))
                    append_row(args.out, {"set": which, "record": label, "seed": seed, "variant": variant,
                                          "log_post": round(float(lp), 2),
                                          "b_error_pct": round(100.0 * (values["b"] / b_true - 1.0), 3),
                                          "b_sd_laplace_pct": round(_b_sd_pct(model, theta), 3),
                                          "tau": float(f"{values['tau']:.4g}"),
                                          "seconds": round(time.perf_counter() - t0, 1)}, FIELDS)
    finally:
        harmonic.MAX_SPAN_PERIODS = kept
    return 0


if __name__ == "__main__":
    sys.exit(main())
