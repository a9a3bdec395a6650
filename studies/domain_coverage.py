"""Does a calibration hold its intervals once its devices are drawn from the prior the
fits assume? (issue 39, item 4.)

The fits walk the impedance coordinates, whose domain restricts the prior
(``bayes_inerter.inference.posterior.impedance``): a chain there cannot reach a device
outside it. A single-record calibration folder made before ``--domain`` existed drew its
devices from the whole prior box. Each device inside the domain is the one a ``--domain``
run draws too (the check draws nothing: ``study_calibration.StudyCalibration.domain``),
so the folder's replicates whose truth lies inside are a calibration under the
restricted prior, and those outside are what ``--domain`` would have drawn again.

For every finished replicate of ``--folder`` this remakes its device (no fit), says
whether it lies inside, and writes coverage_in_domain.csv into the folder: per ranked
parameter the 94 % and 50 % intervals held over the replicates inside (highest-density,
``held_``, and equal-tailed, ``central_``), beside the expected count and its binomial
se, and over all parameters with the se from the replicates' own spread of their
highest-density intervals (a replicate's intervals are not independent); the
replicates outside are listed on standard output.

    python studies/domain_coverage.py --folder results/coverage-sbc-likelihood-force-exact-s22
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

from bayes_inerter.cli.study_script import config_from_folder
from bayes_inerter.study.replicate_store import load_replicates
from bayes_inerter.study.study_calibration import Config, in_domain, replicate_device

from _table import write_table

LEVELS = ("94", "50")


def held_rows(replicates: list[dict]) -> list[dict]:
    """Held counts per parameter and over all of them (see module docstring), of the
    highest-density intervals (``held_``) and the equal-tailed ones (``central_``)."""
    n = len(replicates)
    names = list(replicates[0]["hdi"]["94"])
    rows = []
    for name in names:
        row = {"parameter": name, "replicates": n}
        for lv in LEVELS:
            p = int(lv) / 100
            row[f"held_{lv}"] = sum(r["hdi"][lv][name] for r in replicates)
            row[f"central_{lv}"] = sum(r["central"][lv][name] for r in replicates)
            row[f"expected_{lv}"] = round(n * p, 1)
            row[f"se_{lv}"] = round(math.sqrt(n * p * (1 - p)), 1)
        rows.append(row)
    row = {"parameter": "all", "replicates": n}
    for lv in LEVELS:
        row[f"held_{lv}"] = sum(r["hdi"][lv][m] for r in replicates for m in names)
        row[f"central_{lv}"] = sum(r["central"][lv][m] for r in replicates for m in names)
        row[f"expected_{lv}"] = round(n * len(names) * int(lv) / 100, 1)
        # the se from the replicates' own spread of their held shares
        shares = np.array([np.mean([r["hdi"][lv][m] for m in names]) for r in replicates])
        row[f"se_{lv}"] = round(float(np.std(shares, ddof=1) / math.sqrt(n)) * n * len(names), 1)
    rows.append(row)
    return rows


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--folder", required=True, help="a single-record calibration folder")
    args = ap.parse_args(argv)
    folder = Path(args.folder)
    if not (folder / "settings.json").is_file():
        print(f"error: {folder} holds no calibration (no settings.json); give a folder of study_calibration.py",
              file=sys.stderr)
        return 2
    cs = config_from_folder(Config, folder).settings()
    if not cs.single:
        print("error: the impedance domain is a single record's; this folder holds joint fits", file=sys.stderr)
        return 2
    found = load_replicates(folder)
    if not found:
        print(f"error: {folder} holds no finished replicate; run the calibration first", file=sys.stderr)
        return 2
    inside, outside = [], []
    for k in sorted(found):
        device = replicate_device(cs, k)
        held = in_domain(cs, device.records[0], device.theta)
        (inside if held else outside).append(found[k])
        print(f"replicate {k}: {'inside' if held else 'OUTSIDE'}", flush=True)
    print(f"{len(inside)} of {len(found)} devices inside the domain; outside: "
          f"{', '.join(str(r['replicate']) for r in outside) or 'none'}")
    write_table(folder / "coverage_in_domain.csv", held_rows(inside))
    return 0


if __name__ == "__main__":
    sys.exit(main())
