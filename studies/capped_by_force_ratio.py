"""Which calibration records the untempered chain cannot cross: read by the device's forces.

For each single-record replicate of the given calibration folders (their committed
packed replicates and ``settings.json``; nothing is fitted), the drive's inertial force
amplitude b w^2 X over its dissipative one f_0 + c_f w X, at the replicate's frequency
(``frequencies[k % len(frequencies)]``, as ``study_calibration.replicate_device`` draws it)
and the generator's amplitude X, both from the truth. Writes one row per replicate and a
table of the share of chains that met the convergence rule, by bins of that ratio.

    python studies/capped_by_force_ratio.py results/coverage-sbc-lf-exact-s23-untempered \
        results/coverage-sbc-v6 --out results/capped-by-force-ratio

``--misfit CSV`` also reads benchmarks/bench_misfit.py's rows of paper-like records (the
"ensemble" sampler's) and writes each record's ratio, from the truth its record carries,
beside whether its chain converged (paper_like.csv).
"""
from __future__ import annotations

import argparse
import csv
import json
import math
from pathlib import Path

from _table import write_table
from bayes_inerter.study.replicate_store import finished

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
    for r in finished(folder):
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


def paper_like_rows(misfit: Path) -> list[dict]:
    """The ratio of each paper-like record fitted in ``misfit`` (bench_misfit's CSV) by the
    untempered sampler, with its chain's outcome."""
    from bayes_inerter.records.generator import GeneratorSettings
    from bayes_inerter.records.paper_like import PaperLike, paper_like_record

    device = PaperLike(base=GeneratorSettings(duration=10.0))  # bench_misfit's records
    out = []
    with open(misfit) as f:
        for r in csv.DictReader(f):
            if r["sampler"] != "ensemble" or r["truth"] != "paper-like":
                continue
            freq = float(r["freq_hz"])
            rec = paper_like_record(r["setting"], freq, seed=int(r["seed"]), device=device)
            t = rec.metadata["true_parameters"]
            truth = {"b": t["b"], "f_0": t["f1_0"] + t["f2_0"], "c_f": t["c_f1"] + t["c_f2"]}
            out.append({"setting": r["setting"], "freq_hz": freq, "laboratory": r["seed"],
                        "ratio": round(force_ratio(truth, freq, device.base.amplitude), 3),
                        "converged": r["converged"], "steps": r["steps"], "max_tau": r["max_tau"],
                        "wall_s": r["wall_s"]})
    return sorted(out, key=lambda r: r["ratio"])


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("folders", nargs="+", type=Path)
    p.add_argument("--out", type=Path, default=None, help="write replicates.csv and by_ratio.csv here")
    p.add_argument("--misfit", type=Path, default=None, help="bench_misfit's CSV: also the paper-like records' ratios")
    a = p.parse_args(argv)
    rows = [row for folder in a.folders for row in replicate_rows(folder)]
    table = binned(rows)
    for t in table:
        print(f"{t['folder']:45s} ratio {t['ratio_from']:>4} to {t['ratio_to']:>4}: "
              f"{t['converged']:3d} of {t['replicates']:3d} converged, median largest tau {t['median_tau_max']}")
    if a.out is not None:
        write_table(a.out / "replicates.csv", [{k: (round(v, 4) if isinstance(v, float) else v) for k, v in r.items()}
                                          for r in rows])
        write_table(a.out / "by_ratio.csv", table)
    if a.misfit is not None:
        paper = paper_like_rows(a.misfit)
        for r in paper:
            print(f"paper-like {r['setting']} at {r['freq_hz']:g} Hz, laboratory {r['laboratory']}: "
                  f"ratio {r['ratio']}, converged {r['converged']}, largest tau {float(r['max_tau']):.0f}")
        if a.out is not None:
            write_table(a.out / "paper_like.csv", paper)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
