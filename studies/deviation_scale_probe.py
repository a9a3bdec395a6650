"""One calibration record fitted under the exact density and under the users' likelihood.

The single-record calibration of seed 23 (results/coverage-sbc-lf-exact-s23-untempered)
fits its records under the exact density (``LikelihoodSettings(normaliser="full",
deviation_scale="parameters")``: the deviations' prior sd follows each walker's own
Coulomb forces), and its untempered chains stop at the cap on most records whose
friction outweighs their inertial force (results/capped-by-force-ratio). ``fit`` runs the
users' likelihood (the reference point's normaliser and scale). This fits replicate K's
own record under both, a fixed number of steps each from the same seed, and prints each
chain's largest autocorrelation time and its slowest parameters: is the slowness the
record's or the exact density's? Fixed-length chains' taus are estimates from below.

    python studies/deviation_scale_probe.py --replicate 25 --steps 3000 --out results/capped-by-force-ratio
"""
from __future__ import annotations

import argparse
import dataclasses
import time
from pathlib import Path

import numpy as np

from _table import append_row, git_commit
from bayes_inerter.inference.fit import fit_record
from bayes_inerter.study.study_calibration import Config, replicate_device

ROOT = Path(__file__).resolve().parents[1]

#: The calibration run whose records are fitted (its command line, results/coverage-sbc-lf-exact-s23-untempered).
SEED23 = dict(replicates=150, seed=23, single=True, residual="motion", normaliser="full",
              deviation_scale="parameters", converge=True, max_steps=20000, freqs=(1.5,), tau_rtol=0.2,
              likelihood_force=True, domain=True, interval_draws="kept")

#: The variants: the exact density the calibration samples, and the users' likelihood.
VARIANTS = {"exact (full, parameters)": {"normaliser": "full", "deviation_scale": "parameters"},
            "users' (reference, reference)": {"normaliser": "reference", "deviation_scale": "reference"}}

FIELDS = ("replicate", "variant", "steps", "seconds", "tau_max", "slowest", "b_3", "b_97", "b_truth", "commit")


def probe_arguments(doc: str, table: str) -> argparse.ArgumentParser:
    """The probes' command line: one seed-23 replicate, a fixed number of steps, where its
    fits go, and the folder whose ``table`` the rows are appended to."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("--replicate", type=int, required=True)
    ap.add_argument("--steps", type=int, default=3000)
    ap.add_argument("--fits", type=Path, default=ROOT / "runs" / "deviation-scale-probe")
    ap.add_argument("--out", type=Path, default=None, help=f"append rows to OUT/{table}")
    return ap


def seed23_replicate(k: int):
    """(the calibration's settings, replicate ``k``'s device and records) of :data:`SEED23`."""
    cs = Config(**SEED23).settings()
    return cs, replicate_device(cs, k)


def main(argv=None) -> int:
    a = probe_arguments(__doc__, "deviation_scale.csv").parse_args(argv)
    if a.steps < 300 or a.replicate < 0:
        print("error: --steps must be at least 300 and --replicate at least 0")
        return 2
    cs, device = seed23_replicate(a.replicate)
    seed = int(np.random.default_rng([cs.seed, a.replicate, 7]).integers(2**31))
    rows = []
    for name, change in VARIANTS.items():
        likelihood = dataclasses.replace(cs.likelihood, **change)
        out = a.fits / f"s23_{a.replicate}_{change['normaliser']}_{a.steps}"
        t0 = time.perf_counter()
        res = fit_record(device.records[0], out, steps=a.steps, seed=seed, priors=cs.priors(), plots=False,
                         likelihood=likelihood, interval="posterior", fresh=True)
        taus = {k: float(v) for k, v in res.tau_by_parameter.items()}
        order = sorted(taus, key=taus.get, reverse=True)
        b = np.asarray(res.idata.posterior["b"]).ravel()
        row = {"replicate": a.replicate, "variant": name, "steps": a.steps,
               "seconds": round(time.perf_counter() - t0, 1), "tau_max": round(taus[order[0]], 1),
               "slowest": order[0], "b_truth": round(device.truth["b"], 2),
               "b_3": round(float(np.quantile(b, 0.03)), 2), "b_97": round(float(np.quantile(b, 0.97)), 2),
               "commit": ""}
        rows.append(row)
        print(f"replicate {a.replicate}, {name}: largest tau {row['tau_max']} steps ({order[0]}), "
              f"{row['seconds']} s; b {row['b_3']} to {row['b_97']} kg against {row['b_truth']}", flush=True)
    if a.out is not None:
        commit = git_commit(ROOT)
        for r in rows:
            append_row(a.out / "deviation_scale.csv", {k: ({**r, "commit": commit})[k] for k in FIELDS}, FIELDS)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
