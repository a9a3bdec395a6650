"""Which of the priors' tails holds a paper-like record's chain back?

Issue 40, item 1: on paper-like records a third of the default fits stop at the
20,000-step cap (results/coverage-paper-like-v5). Here one record is fitted by
``fit_record`` as ``bayes-inerter fit`` runs it (the default likelihood, the chain to the
convergence rule or the cap, the fit's seed the laboratory's), once with the default
priors and once with each ``--variants`` variant, which replaces one or two priors by the
same family over another range (``VARIANTS``). Each row: the record, the variant, the
chain's steps and whether it met the rule, every parameter's autocorrelation time (as the
rule computes it), b's median and 94 % highest-density interval, the seconds (a shared
machine: read the steps and tau, not the seconds), the commit.

The cuts are diagnoses, not candidate defaults: a range cut to make a chain fast is
a prior chosen on the records it is measured on. ``physical-nut`` is a candidate: the
nut's stiffness over a catalogue nut's range, argued from physics before it was run.
``nut-damping`` is another: the prior truncated to a damping ratio of the flywheel's
mode on the nut of at least 0.5 % (``priors.NUT_DAMPING_FLOOR``), the plate mode's
physical floor, argued before it was run.

A record is ``SEED:SETTING:FREQUENCY``: ``records.paper_like.paper_like_record`` of that
setting and drive frequency (Hz) in the laboratory drawn from SEED (the coverage studies'
replicate k is seed0 + k). Each row is appended to ``--out``/tails.csv as its fit ends
(a row already there for the same record and variant is kept and not fitted again).

    python studies/prior_tails.py --record 1369:A6:1 [--record ...] [--variants default tails]
        [--max-steps 20000] [--out results/chain-geometry]
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from _table import append_row, git_commit, read_rows
from bayes_inerter import paper_parameters
from bayes_inerter.inference import fit_record
from bayes_inerter.inference.sampling.convergence import Convergence
from bayes_inerter.inference.posterior.priors import NUT_DAMPING_FLOOR, LogUniform
from bayes_inerter.inference.summaries.results import hdi
from bayes_inerter.records.paper_like import paper_like_record

ROOT = Path(__file__).resolve().parents[1]

#: Prior variants by name: priors that replace the defaults (``priors.DEFAULT_PRIORS``,
#: ``SPLIT_PRIORS``), each the default's family over another range.
_CF_FLOOR = {"c_f": LogUniform(10.0, 2e5)}  # viscous friction sum: default 0.1 to 2e5 N s/m
_KN_CEILING = {"k_n": LogUniform(1e3, 1e8)}  # nut stiffness: default 1e3 to 1e9 N/m
#: A catalogue nut's axial stiffness (1e8 to 1e9 N/m), a decade either side for the screw
#: shaft and supports in series: the physical range, which Table I's 4.3e5 N/m lies below.
_KN_PHYSICAL = {"k_n": LogUniform(1e7, 1e10)}
VARIANTS = {"default": {}, "cf-floor": _CF_FLOOR, "kn-ceiling": _KN_CEILING, "tails": {**_CF_FLOOR, **_KN_CEILING},
            "physical-nut": _KN_PHYSICAL, "nut-damping": NUT_DAMPING_FLOOR}


#: tails.csv's columns: the sampled parameters' tau are the single-record model's.
FIELDS = ("seed", "setting", "freq_hz", "variant", "converged", "steps", "tau_max", "slowest", "b_true",
          "b_median", "hdi94_lo", "hdi94_hi", "seconds", "commit",
          *(f"tau_{n}" for n in ("b", "f_0", "f_share", "c_f", "c_share", "c_n", "k_n", "zeta_B", "k_B", "tau",
                                 "gain", "delay")))


def record_spec(text: str) -> tuple[int, str, float]:
    try:
        seed, setting, freq = text.split(":")
        return int(seed), setting.upper(), float(freq)
    except ValueError:
        raise argparse.ArgumentTypeError(f"takes SEED:SETTING:FREQUENCY (1369:A6:1), got {text!r}") from None


def fit_variant(seed: int, setting: str, freq: float, variant: str, max_steps: int, commit: str) -> dict:
    rec = paper_like_record(setting, freq, seed=seed)
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        res = fit_record(rec, Path(tmp) / "fit", seed=seed, plots=False, priors=VARIANTS[variant],
                         convergence=replace(Convergence(), max_steps=max_steps))
    b = np.asarray(res.idata.posterior["b"]).ravel()
    lo, hi = hdi(b)
    names, tau = list(res.tau_by_parameter), np.array(list(res.tau_by_parameter.values()), dtype=float)
    row = {"seed": seed, "setting": setting, "freq_hz": freq, "variant": variant,
           "converged": bool(res.converged), "steps": int(res.iterations),
           "tau_max": float(np.nanmax(tau)), "slowest": names[int(np.nanargmax(tau))],
           "b_true": paper_parameters(setting).b, "b_median": float(np.median(b)),
           "hdi94_lo": float(lo), "hdi94_hi": float(hi), "seconds": round(time.perf_counter() - t0, 1),
           "commit": commit}
    row.update({f"tau_{n}": round(float(t), 1) for n, t in zip(names, tau)})
    return {k: row.get(k, "") for k in FIELDS}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--record", action="append", required=True, type=record_spec)
    ap.add_argument("--variants", nargs="+", default=["default", "tails"], choices=sorted(VARIANTS))
    ap.add_argument("--max-steps", type=int, default=20000)
    ap.add_argument("--out", default=str(ROOT / "results" / "chain-geometry"))
    args = ap.parse_args(argv)
    path = Path(args.out) / "tails.csv"
    done = {(int(r["seed"]), r["setting"], float(r["freq_hz"]), r["variant"]) for r in read_rows(path)}
    commit = git_commit(ROOT)
    for seed, setting, freq in args.record:
        for variant in args.variants:
            if (seed, setting, freq, variant) in done:
                continue
            done.add((seed, setting, freq, variant))
            row = fit_variant(seed, setting, freq, variant, args.max_steps, commit)
            append_row(path, row, FIELDS)
            print(f"{setting} {freq:g} Hz laboratory {seed}, {variant}: {row['steps']} steps, converged "
                  f"{row['converged']}, largest tau {row['tau_max']:.0f} ({row['slowest']}), b {row['b_median']:.0f} "
                  f"(94 % {row['hdi94_lo']:.0f} to {row['hdi94_hi']:.0f}; true {row['b_true']:.0f}), "
                  f"{row['seconds']} s", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
