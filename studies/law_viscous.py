"""Does keeping the viscous direction in the friction law's deviations move b less?

Side by side on paper-like records of design laboratories (never the coverage seeds):
each record fitted twice with the same seed and a fixed number of steps, by the default
likelihood (the law's deviations beyond the plate's Coulomb and viscous harmonics) and
with ``LikelihoodSettings(law_beyond_viscous=False)`` (beyond the Coulomb wave alone).
b's error is reported beside the part the laboratory's sensor gains explain, as
``studies/paper_like_coverage.py`` reports it: a load cell reading g_F times the force
and an accelerometer reading g_a times the acceleration make b come out b g_F / g_a, and
``beyond_gains_pct`` is 100 (b_median / (b g_F / g_a) - 1). A row is written to the
CSV after every fit, and a rerun skips the rows already there.

    python studies/law_viscous.py [--labs 11 12 13 14] [--cases A3@0.5 B1@0.5 ...]
        [--steps 8000] [--force-delay 0] [--accel-delay 0]
        [--out results/likelihood-candidates/law_viscous.csv]

``--force-delay`` and ``--accel-delay`` (s) give the device's sensors those latencies
(``PaperLike``), as the coverage study's "delays" family does.
"""

from __future__ import annotations

import argparse
import csv
import statistics
import tempfile
from pathlib import Path

import numpy as np

from bayes_inerter import paper_parameters
from bayes_inerter.inference import fit_record
from bayes_inerter.inference.posterior.likelihood import LikelihoodSettings
from bayes_inerter.records.paper_like import PaperLike, laboratory, paper_like_record
from bayes_inerter.study.manifest import script_configuration, write_manifest

ROOT = Path(__file__).resolve().parents[1]
CASES = ("A3@0.5", "B1@0.5", "A3@1", "A6@1", "B1@1.5", "A0@1.5")
VARIANTS = {"default": LikelihoodSettings(), "beyond-coulomb": LikelihoodSettings(law_beyond_viscous=False)}
FIELDS = ("lab", "case", "variant", "steps", "b_median_pct", "b_sd_pct", "gains_pct", "beyond_gains_pct", "tau_max")


def fit_one(lab: int, case: str, variant: str, steps: int, device: PaperLike | None = None) -> dict:
    setting, freq = case.split("@")
    rec = paper_like_record(setting, float(freq), seed=lab, device=device)
    p = paper_parameters(setting)
    lab_settings = laboratory(lab, device=device)
    gain = lab_settings.force_gain / lab_settings.accel_gain
    with tempfile.TemporaryDirectory() as tmp:
        res = fit_record(rec, Path(tmp), seed=lab, processes=1, plots=False, steps=steps,
                         likelihood=VARIANTS[variant])
        b = np.asarray(res.idata.posterior["b"].values).ravel()
    return {"lab": lab, "case": case, "variant": variant, "steps": steps,
            "b_median_pct": round(100 * (np.median(b) / p.b - 1), 2), "b_sd_pct": round(100 * np.std(b) / p.b, 2),
            "gains_pct": round(100 * (gain - 1), 2), "beyond_gains_pct": round(100 * (np.median(b) / (p.b * gain) - 1), 2),
            "tau_max": round(float(np.nanmax(res.tau)), 1)}


def summary(rows: list[dict]) -> list[str]:
    by = {}
    for r in rows:
        by.setdefault((r["lab"], r["case"]), {})[r["variant"]] = float(r["beyond_gains_pct"])
    pairs = [v for v in by.values() if len(v) == len(VARIANTS)]
    lines = [f"{len(pairs)} records with both variants; b's error beyond the sensor gains:"]
    for name in VARIANTS:
        x = [v[name] for v in pairs]
        if x:
            lines.append(f"  {name:15s} mean {statistics.mean(x):+.2f} %, mean absolute "
                         f"{statistics.mean(map(abs, x)):.2f} %, largest {max(x, key=abs):+.2f} %")
    better = sum(abs(v["beyond-coulomb"]) < abs(v["default"]) for v in pairs)
    lines.append(f"  beyond-coulomb nearer the truth on {better} of {len(pairs)}")
    return lines


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--labs", type=int, nargs="+", default=[11, 12, 13, 14])
    ap.add_argument("--cases", nargs="+", default=list(CASES))
    ap.add_argument("--steps", type=int, default=8000)
    ap.add_argument("--force-delay", type=float, default=0.0, help="s")
    ap.add_argument("--accel-delay", type=float, default=0.0, help="s")
    ap.add_argument("--out", default=str(ROOT / "results" / "likelihood-candidates" / "law_viscous.csv"))
    args = ap.parse_args()
    write_manifest(Path(args.out).parent, script_configuration())
    out = Path(args.out)
    device = PaperLike(force_delay=args.force_delay, accel_delay=args.accel_delay)
    rows = list(csv.DictReader(out.open())) if out.exists() else []
    done = {(int(r["lab"]), r["case"], r["variant"]) for r in rows}
    jobs = [(lab, case, v) for lab in args.labs for case in args.cases for v in VARIANTS if (lab, case, v) not in done]
    for i, (lab, case, v) in enumerate(jobs, 1):
        row = fit_one(lab, case, v, args.steps, device)
        rows.append(row)
        out.parent.mkdir(parents=True, exist_ok=True)
        with out.open("w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=FIELDS)
            w.writeheader()
            w.writerows(rows)
        print(f"[{i}/{len(jobs)}] laboratory {lab} {case} {v}: b {row['b_median_pct']:+.2f} % "
              f"({row['beyond_gains_pct']:+.2f} % beyond the gains), tau {row['tau_max']}", flush=True)
    print("\n".join(summary(rows)))


if __name__ == "__main__":
    main()
