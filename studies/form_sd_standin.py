"""How wide a model-form uncertainty of b would the chains' coverage ask? A stand-in,
read from replicate tables already written, to choose ``LikelihoodSettings.form_sd``
before any chain runs with it.

A stand-in, not a chain: each converged, identified replicate's posterior of log b is
taken as normal, centred and scaled to reproduce its own 94 % (50 %) interval, and an
independent normal error of sd s in log b is added (what ``form_sd`` s does inside the
likelihood to first order, where the record pins b much more tightly than s: see
``tests/test_inference_motion.py``). At s = 0 the counts are the replicates' own.

The design set is the even replicates of results/coverage-paper-like-untempered-80k; s
is chosen there, on the grid ``--grid``, as the one whose larger |z| of the two levels
(the distance from 0.94 and 0.5 in binomial standard errors) is least. Every other
set (the odd replicates, the held-out families) is measured, not used to choose.

``--rho`` adds a second term that grows with the friction: an error of b's inertial
force at the fundamental of rho times the Coulomb force, so a further sd of rho r in
log b, r = f_0 / (b w^2 X) (the paper's Coulomb force over the inertial force's
amplitude, X the generator's drive amplitude; what a break-away does where the
friction is large against the inertia). Each pair (s, rho) of the two grids is a row,
and the pair is chosen as s alone is.

    python studies/form_sd_standin.py [--grid 0 0.0025 0.005 0.0075 0.01] [--rho 0]
        [--out results/form-sd-standin] [--table table.csv]

Writes the table (one row per set, s and rho) and prints the rows. Exit codes: 0 done,
2 a folder missing.
"""

import argparse
import csv
import json
import math
import sys
from pathlib import Path
from statistics import NormalDist

from _table import write_rows

ROOT = Path(__file__).resolve().parents[1]
DESIGN = "coverage-paper-like-untempered-80k"
FAMILIES = ("backlash", "breakaway", "corner20", "delays")
LEVELS = (0.94, 0.5)


def _replicates(folder: Path) -> list[dict]:
    """The converged, identified replicates of a folder's replicates.csv."""
    with open(folder / "replicates.csv", newline="") as f:
        return [r for r in csv.DictReader(f) if r["converged"] == "True" and r["identified"] == "True"]


def _friction_ratio(r: dict) -> float:
    """f_0 / (b w^2 X) of a replicate's setting and drive (module docstring)."""
    from bayes_inerter import paper_parameters
    from bayes_inerter.records.generator import GeneratorSettings

    p = paper_parameters(r["setting"])
    w = 2 * math.pi * float(r["freq_hz"])
    return (p.f1_0 + p.f2_0) / (p.b * w * w * GeneratorSettings().amplitude)


def _held(r: dict, level: float, s: float, rho: float = 0.0) -> bool:
    lo, hi = json.loads(r[f"hdi{round(100 * level)}"])
    q = NormalDist().inv_cdf(0.5 + level / 2)
    centre = 0.5 * (math.log(lo) + math.log(hi))
    sd = (math.log(hi) - math.log(lo)) / (2 * q)
    extra = math.hypot(s, rho * _friction_ratio(r)) if rho else s
    return abs(math.log(float(r["b_true"])) - centre) <= q * math.hypot(sd, extra)


def _z(held: int, n: int, level: float) -> float:
    return (held / n - level) / math.sqrt(level * (1 - level) / n) if n else math.nan


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--grid", nargs="+", type=float, default=[0.0, 0.0025, 0.005, 0.0075, 0.01])
    parser.add_argument("--rho", nargs="+", type=float, default=[0.0],
                        help="the friction-scaled term's shares of the Coulomb force (module docstring)")
    parser.add_argument("--out", type=Path, default=ROOT / "results" / "form-sd-standin")
    parser.add_argument("--table", default="table.csv", help="the table's file name in --out")
    args = parser.parse_args(argv)
    try:
        design = _replicates(ROOT / "results" / DESIGN)
        sets = {"design (even)": [r for r in design if int(r["replicate"]) % 2 == 0],
                "paper-like (odd)": [r for r in design if int(r["replicate"]) % 2 == 1]}
        for name in FAMILIES:
            sets[name] = _replicates(ROOT / "results" / f"coverage-{name}-untempered-80k")
    except OSError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    sets["families pooled"] = [r for name in FAMILIES for r in sets[name]]
    rows = []
    friction = args.rho != [0.0]
    for name, reps in sets.items():
        for s in args.grid:
            for rho in args.rho:
                row = {"set": name, "form_sd": s, **({"rho": rho} if friction else {}), "n": len(reps)}
                for level in LEVELS:
                    held = sum(_held(r, level, s, rho) for r in reps)
                    key = round(100 * level)
                    row.update({f"held{key}": held, f"rate{key}": round(held / len(reps), 3),
                                f"z{key}": round(_z(held, len(reps), level), 2)})
                rows.append(row)

    def pair(row):
        return (row["form_sd"], row.get("rho", 0.0))

    worst = {pair(row): max(abs(row["z94"]), abs(row["z50"])) for row in rows if row["set"] == "design (even)"}
    chosen = min(worst, key=lambda p: (worst[p], p))
    for row in rows:
        row["chosen"] = pair(row) == chosen
    write_rows(args.out / args.table, rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
