"""The held-out device families side by side (``bayes_inerter.study.held_out``): b's
and b / gain's coverage on each family's converged, identified chains and on their
pool, from the folders ``studies/paper_like_coverage.py --family NAME`` wrote.

    python studies/held_out_families.py [--out results/held-out-families] [FOLDER ...]

Writes table.csv into --out (and the run into its manifest.json) and prints the rows.
Without folders: the four families under the untempered default with an 80,000-step
cap. Exit codes: 0 done, 2 a folder missing or without replicates.
"""

import argparse
import sys
from pathlib import Path

from _table import write_rows

from bayes_inerter.study.held_out import families_table

ROOT = Path(__file__).resolve().parents[1]
FOLDERS = [ROOT / "results" / f"coverage-{name}-untempered-80k" for name in ("backlash", "breakaway", "corner20",
                                                                             "delays")]


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("folders", nargs="*", type=Path, help="paper_like_coverage output folders, one family each")
    parser.add_argument("--out", type=Path, default=ROOT / "results" / "held-out-families")
    args = parser.parse_args(argv)
    try:
        rows = families_table(args.folders or FOLDERS)
    except (ValueError, OSError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    write_rows(args.out / "table.csv", rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
