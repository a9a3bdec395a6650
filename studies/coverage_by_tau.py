"""Does a calibration hold its intervals whatever its chains' autocorrelation time?
(issue 39, item 4.)

An exact posterior holds its level given the data, so also given anything computed
from the data alone: the coverage over the replicates whose chain mixed slowly must be
the coverage over those that mixed fast. The chain's slowest integrated
autocorrelation time (``tau_max``: the sampler's randomness aside, a function of the
record) splits a single-record calibration folder's finished replicates into
``--groups`` groups of equal size, by tau; for each, coverage_by_tau.csv gives the
94 % and 50 % intervals held over all ranked parameters (highest-density and
equal-tailed), the expected count, and its se from the replicates' own spread
(``domain_coverage.held_rows``). ``--outside`` leaves out replicates by number (the
devices outside the impedance domain that ``domain_coverage.py`` lists, for a folder
drawn from the whole prior box).

    python studies/coverage_by_tau.py --folder results/coverage-sbc-likelihood-force-exact-s22 \\
        --outside 17 24 34 63 67 68 78 93 125 126 133 134
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from bayes_inerter.study.replicate_store import load_replicates

from _table import write_table
from domain_coverage import held_rows


def tau_rows(replicates: list[dict], groups: int) -> list[dict]:
    """One row per group of replicates by ``tau_max`` (see module docstring)."""
    ordered = sorted(replicates, key=lambda r: r["tau_max"])
    rows = []
    for i, part in enumerate(np.array_split(np.arange(len(ordered)), groups)):
        chosen = [ordered[j] for j in part]
        pooled = held_rows(chosen)[-1]
        rows.append({"group": i + 1, "tau_from": round(chosen[0]["tau_max"], 2),
                     "tau_to": round(chosen[-1]["tau_max"], 2),
                     "median_steps": int(np.median([r["iterations"] for r in chosen])),
                     **{k: v for k, v in pooled.items() if k != "parameter"}})
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--folder", required=True, help="a single-record calibration folder")
    ap.add_argument("--groups", type=int, default=3, help="groups of equal size by tau (default 3)")
    ap.add_argument("--outside", type=int, nargs="*", default=[], help="replicates to leave out, by number")
    args = ap.parse_args(argv)
    folder = Path(args.folder)
    found = load_replicates(folder) if (folder / "settings.json").is_file() else {}
    kept = [r for k, r in sorted(found.items()) if k not in set(args.outside) and "tau_max" in r]
    if not kept:
        print(f"error: {folder} holds no finished single-record replicate; run study_calibration.py into it "
              "first", file=sys.stderr)
        return 2
    if not 1 <= args.groups <= len(kept) // 5:
        print(f"error: --groups must be 1 to {len(kept) // 5} (at least 5 replicates a group), got {args.groups}",
              file=sys.stderr)
        return 2
    rows = tau_rows(kept, args.groups)
    path = write_table(folder / "coverage_by_tau.csv", rows)
    ranked = len(kept[0]["hdi"]["94"])
    for r in rows:
        print(f"tau {r['tau_from']:g} to {r['tau_to']:g}: 94 % held {r['held_94']} of {r['replicates'] * ranked} "
              f"(expected {r['expected_94']}, se {r['se_94']}); 50 % held {r['held_50']}")
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
