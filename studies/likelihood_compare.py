"""The likelihoods side by side with real chains: which one's posterior holds b?

Issue 39's measurement before choosing the default. Each case is one record fitted by
``fit_record`` with each candidate likelihood, every chain run to the convergence rule
(``Convergence``, capped at ``--max-steps``); the row keeps b's posterior median, its
94 % and 50 % highest-density intervals and whether they hold the true b, the chain's
state (converged, longest tau, steps) and the seconds. Candidates:

- ``ar1``: the time-domain likelihood (30 Hz low-passed acceleration, AR(1) residual,
  the measured force taken as exact), the c_B prior log-uniform as before (``modal``
  off), its interval the posterior's own;
- ``ar1-honest``: the same chain, its b interval the package's post-hoc "honest" one
  (no second chain: the row is read from the same fit);
- ``harmonic``: the harmonic likelihood (``inference.posterior.harmonic``: force in,
  acceleration out at the drive's harmonics, errors in both signals, the discrepancy
  and the channels' gain sampled) with the plate mode's damping ratio under its
  physical prior (``modal``);
- ``motion``: the motion-in likelihood (``inference.posterior.motion``: the measured motion in,
  the force out at the drive's harmonics, no simulation; the same noise, discrepancy,
  gain and ``modal``);
- ``motion-law-sampled``: the same with the friction law's deviations' scale sampled
  (``LikelihoodSettings(law_sampled=True)``).

Records: ``control`` (the generator's records of the model's own physics, Table I and
Table 2), ``noise-free`` (the same with the sensors' noise off: ideal sensors, band-limited
at 1 kHz) and ``paper-like`` (``records.paper_like_record``, a richer device), each at
the settings and frequencies asked, one laboratory seed. Rows already in the CSV are
not fitted again, so a run that stops continues where it stopped.

    python studies/likelihood_compare.py [--out results/likelihood-compare] [--kinds paper-like control]
        [--settings A0 A3 B2] [--freqs 0.5 1 1.5] [--candidates motion harmonic ar1] [--seed 11]
        [--max-steps 6000] [--processes 2]
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from bayes_inerter import paper_parameters
from bayes_inerter.inference import fit_record
from bayes_inerter.inference.sampling.convergence import Convergence
from bayes_inerter.inference.posterior.likelihood import LikelihoodSettings
from bayes_inerter.inference.summaries.results import hdi
from bayes_inerter.records import GeneratorSettings, generate_record
from bayes_inerter.records.paper_like import paper_like_record
from bayes_inerter.study.manifest import script_configuration, write_manifest

ROOT = Path(__file__).resolve().parents[1]
FIELDS = ("kind", "setting", "freq_hz", "seed", "candidate", "b_true", "b_median", "hdi94_lo", "hdi94_hi",
          "hdi50_lo", "hdi50_hi", "covered94", "covered50", "err_pct", "width94_pct", "phi", "converged",
          "tau_max", "steps", "seconds", "identified")


KINDS = ("paper-like", "control", "noise-free")
CANDIDATES = ("motion", "harmonic", "ar1", "motion-law-sampled")


def _record(kind: str, setting: str, freq: float, seed: int):
    if kind in ("control", "noise-free"):
        settings = GeneratorSettings(force_noise=0.0, accel_noise=0.0, disp_noise=0.0) if kind == "noise-free" else None
        return generate_record(paper_parameters(setting), freq, settings=settings, rng=seed, setting_name=setting)
    return paper_like_record(setting, freq, seed=seed)


def _fit(record, candidate: str, max_steps: int, processes: int, seed: int) -> list[dict]:
    """The rows of one fit: for ``ar1``, also the ``ar1-honest`` row read from the same chain."""
    if candidate in ("harmonic", "motion", "motion-law-sampled"):
        kw = {"likelihood": LikelihoodSettings(residual=candidate.split("-")[0],
                                               law_sampled=candidate == "motion-law-sampled"), "interval": "posterior"}
    else:
        kw = {"likelihood": LikelihoodSettings(residual="ar1"), "interval": "honest"}
    modal = candidate != "ar1"
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        res = fit_record(record, Path(tmp) / "fit", convergence=replace(Convergence(), max_steps=max_steps),
                         processes=processes, seed=seed, plots=False, priors=None, modal=modal, **kw)
        b = np.asarray(res.idata.posterior["b"]).ravel()
        phi = json.loads((Path(tmp) / "fit" / "fit.json").read_text())["b_interval"]["phi"]
    seconds = time.perf_counter() - t0
    tau = np.asarray(res.tau if not isinstance(res.tau, dict) else list(res.tau.values()), dtype=float)
    base = {"b_median": float(np.median(b)), "converged": bool(res.converged),
            "tau_max": float(np.nanmax(tau)) if np.any(np.isfinite(tau)) else "", "steps": int(res.iterations),
            "seconds": round(seconds, 1), "phi": phi}
    lo94, hi94 = hdi(b, 0.94)
    lo50, hi50 = hdi(b, 0.5)
    rows = [{**base, "candidate": candidate, "hdi94_lo": lo94, "hdi94_hi": hi94, "hdi50_lo": lo50,
             "hdi50_hi": hi50, "identified": bool(res.b_interval.identified) if candidate != "ar1" else True}]
    if candidate == "ar1":
        bi = res.b_interval
        rows.append({**base, "candidate": "ar1-honest", "hdi94_lo": bi.lo, "hdi94_hi": bi.hi, "hdi50_lo": "",
                     "hdi50_hi": "", "identified": bool(bi.identified)})
    return rows


def _finish(row: dict, b_true: float) -> dict:
    row["b_true"] = b_true
    row["covered94"] = bool(row["hdi94_lo"] <= b_true <= row["hdi94_hi"])
    row["covered50"] = bool(row["hdi50_lo"] <= b_true <= row["hdi50_hi"]) if row["hdi50_lo"] != "" else ""
    row["err_pct"] = round(100 * (row["b_median"] / b_true - 1), 3)
    row["width94_pct"] = round(100 * (row["hdi94_hi"] - row["hdi94_lo"]) / b_true, 3)
    return row


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default=str(ROOT / "results" / "likelihood-compare"))
    ap.add_argument("--kinds", nargs="+", default=["paper-like", "control"], choices=KINDS)
    ap.add_argument("--settings", nargs="+", default=["A0", "A3", "B2"])
    ap.add_argument("--freqs", nargs="+", type=float, default=[0.5, 1.0, 1.5])
    ap.add_argument("--candidates", nargs="+", default=["motion", "harmonic", "ar1"], choices=CANDIDATES)
    ap.add_argument("--seed", type=int, default=11)
    ap.add_argument("--max-steps", type=int, default=6000)
    ap.add_argument("--processes", type=int, default=min(2, os.cpu_count() or 1))
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    write_manifest(out, script_configuration())
    path = out / "fits.csv"
    done = set()
    if path.exists():
        with path.open() as f:
            done = {(r["kind"], r["setting"], float(r["freq_hz"]), int(r["seed"]), r["candidate"])
                    for r in csv.DictReader(f)}
    else:
        with path.open("w", newline="") as f:
            csv.DictWriter(f, FIELDS).writeheader()
    cases = [(k, s, fr, c) for k in args.kinds for fr in args.freqs for s in args.settings for c in args.candidates]
    for i, (kind, setting, freq, cand) in enumerate(cases, 1):
        if (kind, setting, freq, args.seed, cand) in done:
            continue
        print(f"[{i}/{len(cases)}] {kind} {setting} {freq:g} Hz, {cand} ...", flush=True)
        try:
            rows = _fit(_record(kind, setting, freq, args.seed), cand, args.max_steps, args.processes, args.seed)
        except (ValueError, RuntimeError) as exc:
            print(f"  failed: {exc}", file=sys.stderr, flush=True)
            continue
        b_true = paper_parameters(setting).b
        with path.open("a", newline="") as f:
            w = csv.DictWriter(f, FIELDS)
            for row in rows:
                row = _finish({**row, "kind": kind, "setting": setting, "freq_hz": freq, "seed": args.seed}, b_true)
                w.writerow({k: row.get(k, "") for k in FIELDS})
                print(f"  {row['candidate']}: b {row['b_median']:.1f} (true {b_true:.1f}, {row['err_pct']:+.2f} %), "
                      f"94 % [{row['hdi94_lo']:.1f}, {row['hdi94_hi']:.1f}] {'holds' if row['covered94'] else 'MISSES'}"
                      f", converged {row['converged']}, tau {row['tau_max']}, {row['seconds']} s", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
