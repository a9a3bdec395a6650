"""Which calibration records the untempered chain cannot cross: read by the device's forces.

For each single-record replicate of the given calibration folders (their committed
``replicates.jsonl`` and ``settings.json``; nothing is fitted), the drive's inertial force
amplitude b w^2 X over its dissipative one f_0 + c_f w X, at the replicate's frequency
(``frequencies[k % len(frequencies)]``, as ``study_calibration.replicate_device`` draws it)
and the generator's amplitude X, both from the truth. Writes one row per replicate and a
table of the share of chains that met the convergence rule, by bins of that ratio.

    python studies/capped_by_force_ratio.py results/coverage-sbc-lf-exact-s23-untempered \
        results/coverage-sbc-v6 --out results/capped-by-force-ratio
"""
from __future__ import annotations

import argparse
import csv
import json
import math
from pathlib import Path

#: Bin edges of the ratio (inertial over dissipative force amplitude), chosen as round
#: decades and halves before the table was read.
EDGES = (0.0, 0.1, 0.3, 1.0, 3.0, 10.0, math.inf)


def force_ratio(truth: dict, freq: float, amplitude: float) -> float:
    """b w^2 X / (f_0 + c_f w X): the inertial force amplitude over the dissipative one."""
    w = 2.0 * math.pi * freq
    return truth["b"] * w * w * amplitude / (truth["f_0"] + truth["c_f"] * w * amplitude)


def replicate_rows(folder: Path) -> list[dict]:
    settings = json.loads((folder / "settings.json").read_text())
    if not settings.get("single"):
        raise SystemExit(f"{folder}: not a single-record calibration; give single-record folders")
    freqs = settings["frequencies"]
    amplitude = settings["generator"]["amplitude"]
    rows = []
    with open(folder / "replicates.jsonl") as f:
        for line in f:
            r = json.loads(line)
            freq = freqs[r["replicate"] % len(freqs)]
            taus = r.get("tau_by_parameter") or {}
            rows.append({"folder": folder.name, "replicate": r["replicate"], "freq_hz": freq,
                         "ratio": force_ratio(r["truth"], freq, amplitude),
                         "converged": bool(r["converged"]), "steps": r["iterations"],
                         "tau_max": r["tau_max"],
                         "slowest": max(taus, key=taus.get) if taus else "",
                         "b_held_94": r["hdi"]["94"]["b"]})
    return rows


def binned(rows: list[dict]) -> list[dict]:
    out = []
    for folder in sorted({r["folder"] for r in rows}):
        for lo, hi in zip(EDGES[:-1], EDGES[1:]):
            sel = [r for r in rows if r["folder"] == folder and lo <= r["ratio"] < hi]
            if not sel:
                continue
            conv = [r for r in sel if r["converged"]]
            taus = sorted(r["tau_max"] for r in sel)
            out.append({"folder": folder, "ratio_from": lo, "ratio_to": hi, "replicates": len(sel),
                        "converged": len(conv), "share_converged": round(len(conv) / len(sel), 3),
                        "median_tau_max": round(taus[len(taus) // 2], 1),
                        "b_held_94_of_converged": sum(r["b_held_94"] for r in conv)})
    return out


def _write(path: Path, rows: list[dict]) -> None:
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("folders", nargs="+", type=Path)
    p.add_argument("--out", type=Path, default=None, help="write replicates.csv and by_ratio.csv here")
    a = p.parse_args(argv)
    rows = [row for folder in a.folders for row in replicate_rows(folder)]
    table = binned(rows)
    for t in table:
        print(f"{t['folder']:45s} ratio {t['ratio_from']:>4} to {t['ratio_to']:>4}: "
              f"{t['converged']:3d} of {t['replicates']:3d} converged, median largest tau {t['median_tau_max']}")
    if a.out is not None:
        a.out.mkdir(parents=True, exist_ok=True)
        _write(a.out / "replicates.csv", [{k: (round(v, 4) if isinstance(v, float) else v) for k, v in r.items()}
                                          for r in rows])
        _write(a.out / "by_ratio.csv", table)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
