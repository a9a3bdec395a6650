"""The friction law's deviations' scale fixed (0.25 of the Coulomb forces, the default)
against sampled (``LikelihoodSettings(law_sampled=True)``), side by side on the same
replicates of the model's own physics (issue 39, items 2 and 4; a design measurement,
not a coverage).

Each replicate is fitted twice by ``studies/study_calibration.py --inspect K``, which
keeps the fit (chain run to the convergence rule) in ``WORK``/fixed or ``WORK``/sampled:

    python studies/study_calibration.py --seed 4 --single --residual motion --converge \\
        --max-steps 40000 --freqs 0.5 1 1.5 --inspect K --work WORK/fixed --out WORK/fixed
    python studies/study_calibration.py ... --inspect K --law-sampled --work WORK/sampled --out WORK/sampled

This script reads every replicate fitted both ways (their summary.csv and fit.json) and
writes one row per replicate and sampled parameter to ``--out``/law_scale.csv: each
fit's 94 % highest-density interval's width and their ratio, each chain's steps and
whether it met the rule, and the sampled scale's posterior median and interval.

    python studies/law_scale_pairs.py --work WORK [--out results/likelihood-candidates]
"""

import argparse
import csv
import json
import re
import sys
from pathlib import Path

from _table import write_rows

ROOT = Path(__file__).resolve().parents[1]


def _fit(folder: Path) -> tuple[dict, dict]:
    with open(folder / "summary.csv", newline="") as f:
        rows = {r["name"]: r for r in csv.DictReader(f) if r["kind"] == "sampled"}
    return rows, json.loads((folder / "fit.json").read_text())


def pairs(work: Path) -> list[dict]:
    """The rows of law_scale.csv from the fits in ``work``/fixed and ``work``/sampled."""
    out = []
    for fixed_dir in sorted((work / "fixed").glob("inspect_single_seed*_*")):
        sampled_dir = work / "sampled" / fixed_dir.name
        if not ((fixed_dir / "fit.json").exists() and (sampled_dir / "fit.json").exists()):
            continue
        seed, k = map(int, re.match(r"inspect_single_seed(\d+)_(\d+)_", fixed_dir.name).groups())
        (fixed, fj), (sampled, sj) = _fit(fixed_dir), _fit(sampled_dir)
        law = sampled["law"]
        for name, a in fixed.items():
            s = sampled[name]
            wa = float(a["hdi_97%"]) - float(a["hdi_3%"])
            ws = float(s["hdi_97%"]) - float(s["hdi_3%"])
            out.append({"seed": seed, "replicate": k, "freq_hz": fj["drive_frequency"]["hz"], "parameter": name,
                        "width_fixed": f"{wa:.6g}", "width_sampled": f"{ws:.6g}",
                        "ratio": f"{ws / wa:.3f}" if wa > 0 else "",
                        "steps_fixed": fj["iterations"], "converged_fixed": fj["converged"],
                        "steps_sampled": sj["iterations"], "converged_sampled": sj["converged"],
                        "law_mean": f"{float(law['mean']):.4g}", "law_hdi_3": f"{float(law['hdi_3%']):.4g}",
                        "law_hdi_97": f"{float(law['hdi_97%']):.4g}"})
    return out


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--work", required=True, help="the folder holding fixed/ and sampled/ (see above)")
    ap.add_argument("--out", default=str(ROOT / "results" / "likelihood-candidates"))
    args = ap.parse_args()
    rows = pairs(Path(args.work))
    if not rows:
        print(f"error: {args.work} holds no replicate fitted both ways (fixed/ and sampled/); "
              "run studies/study_calibration.py --inspect into it first", file=sys.stderr)
        return 2
    write_rows(Path(args.out) / "law_scale.csv", rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
