"""Do too few drive periods make b's interval too narrow at 0.5 Hz? (a design probe)

A 10 s paper-like record at 0.5 Hz, less its 2 s ramp and one settling period, holds 3
steady periods, and the motion-in likelihood takes each harmonic's noise from their
scatter. This fits the same laboratories' records (design seeds 9150 and up, setting
``SETTINGS_ORDER[i]`` for seed 9150 + i, used for nothing else) as ``bayes-inerter fit``
fits them, in five ways: the paper's 10 s; 20 s long (8 steady periods); 20 s long with
only its last 3 periods compared (``LikelihoodSettings(settle=6)``: the start-up long
gone, the periods as few as at 10 s); the same 20 s record cut to its first 10 s (its
first 3 periods: the same noise as the last way's, the periods of the 10 s record);
and the 10 s record compared up to its 20th harmonic only (``cutoff`` 10 Hz). Each fit's folder goes to --work (finished fits are reused);
fits.csv has one row a fit.

    python studies/record_length_probe.py --records 6 [--ways 10s 20s 20s-last3 20s-first10s 10s-20harmonics]
        [--work runs/record-length] [--out results/record-length]
"""

import argparse
import csv
import dataclasses
import json
import sys
from pathlib import Path

import numpy as np

from bayes_inerter.device import paper_parameters
from bayes_inerter.inference.fit import fit_record
from bayes_inerter.inference.posterior.likelihood import LikelihoodSettings
from bayes_inerter.inference.summaries.results import hdi
from bayes_inerter.records import Record
from bayes_inerter.records.paper_like import laboratory, paper_like_record

ROOT = Path(__file__).resolve().parents[1]
SETTINGS_ORDER = ("A3", "B1", "A6", "A0", "B2", "A1", "A4", "A2", "A5")
FREQ = 0.5
SEED0 = 9150
#: A normal's 94 % interval in its sds (2 x 1.88): z is b's error over the 94 % width / this.
WIDTH94_SDS = 3.76
#: way: (record length s, likelihood settings, seconds kept of the record: None all)
WAYS = {"10s": (None, {}, None), "20s": (20.0, {}, None), "20s-last3": (20.0, {"settle": 6}, None),
        "20s-first10s": (20.0, {}, 10.0), "10s-20harmonics": (None, {"cutoff": 20 * FREQ}, None)}


def _first(rec: Record, seconds: float) -> Record:
    """The record's first ``seconds`` (its first sample at time 0)."""
    keep = rec.time <= rec.time[0] + seconds + 1e-9
    return dataclasses.replace(rec, time=rec.time[keep], force=rec.force[keep], accel=rec.accel[keep],
                               disp=None if rec.disp is None else rec.disp[keep])


def fit_one(way: str, i: int, work: Path) -> dict:
    setting, seed = SETTINGS_ORDER[i % len(SETTINGS_ORDER)], SEED0 + i
    duration, changes, kept = WAYS[way]
    out = work / way / f"{setting}-{FREQ}-{seed}"
    if not (out / "fit.json").exists():  # a finished fit is read, its record not made again
        rec = paper_like_record(setting, FREQ, seed=seed, duration=duration)
        if kept is not None:
            rec = _first(rec, kept)
        fit_record(rec, out, seed=seed, plots=False, likelihood=LikelihoodSettings(**changes))
    import arviz as az  # after the fit: its import is slow
    post = az.from_netcdf(str(out / "posterior.nc")).posterior
    b = np.asarray(post["b"]).ravel()
    info = json.loads((out / "fit.json").read_text())
    lab = laboratory(seed)
    b_params = paper_parameters(setting)
    b_true = b_params.b
    lo, hi = hdi(b, 0.94)
    lo50, hi50 = hdi(b, 0.5)
    return {"way": way, "setting": setting, "seed": seed, "b_true": b_true, "b_median": float(np.median(b)),
            "error_pct": 100 * (float(np.median(b)) / b_true - 1),
            "gain_ratio_pct": 100 * (lab.force_gain / lab.accel_gain - 1),
            "z": (float(np.median(b)) - b_true) / ((hi - lo) / WIDTH94_SDS), "covered94": bool(lo <= b_true <= hi),
            "covered50": bool(lo50 <= b_true <= hi50), "width94_pct": 100 * (hi - lo) / b_true,
            "tau_median_N": float(np.median(np.asarray(post["tau"]))),
            # the friction's split between plate and rotation, f1_0 / (f1_0 + f2_0), against the truth's
            "f_share_median": float(np.median(np.asarray(post["f_share"]))),
            "f_share_hdi94": [float(v) for v in hdi(np.asarray(post["f_share"]).ravel(), 0.94)],
            "f_share_true": b_params.f1_0 / (b_params.f1_0 + b_params.f2_0),
            "corr_b_f_share": float(np.corrcoef(b, np.asarray(post["f_share"]).ravel())[0, 1]),
            "converged": bool(info.get("converged")),
            "steps": info.get("iterations")}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--records", type=int, default=6)
    ap.add_argument("--ways", nargs="+", default=list(WAYS), choices=list(WAYS))
    ap.add_argument("--work", type=Path, default=ROOT / "runs" / "record-length")
    ap.add_argument("--out", type=Path, default=ROOT / "results" / "record-length")
    ap.add_argument("--only-done", action="store_true", help="tabulate the finished fits only, fit nothing")
    a = ap.parse_args(argv)
    rows = []
    for way in a.ways:
        for i in range(a.records):
            setting = SETTINGS_ORDER[i % len(SETTINGS_ORDER)]
            if a.only_done and not (a.work / way / f"{setting}-{FREQ}-{SEED0 + i}" / "fit.json").exists():
                continue
            rows.append(fit_one(way, i, a.work))
            print(f"{way} {setting}: b {rows[-1]['b_median']:.1f} kg, z {rows[-1]['z']:+.2f}", flush=True)
    a.out.mkdir(parents=True, exist_ok=True)
    with open(a.out / "fits.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    with open(a.out / "summary.csv", "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["way", "fits", "rms_z", "mean_z", "covered94", "covered50", "median_width94_pct",
                    "rms_error_beyond_gain_pct", "median_tau_N", "f_share_held94"])
        for way in a.ways:
            r = [x for x in rows if x["way"] == way]
            if not r:
                continue
            z = np.array([x["z"] for x in r])
            beyond = np.array([x["error_pct"] - x["gain_ratio_pct"] for x in r])
            w.writerow([way, len(r), f"{np.sqrt(np.mean(z ** 2)):.2f}", f"{np.mean(z):+.2f}",
                        sum(x["covered94"] for x in r), sum(x["covered50"] for x in r),
                        f"{np.median([x['width94_pct'] for x in r]):.2f}", f"{np.sqrt(np.mean(beyond ** 2)):.2f}",
                        f"{np.median([x['tau_median_N'] for x in r]):.3f}",
                        sum(x["f_share_hdi94"][0] <= x["f_share_true"] <= x["f_share_hdi94"][1] for x in r)])
    print(f"wrote {a.out / 'fits.csv'} and summary.csv")
    return 0


if __name__ == "__main__":
    sys.exit(main())
