"""Leave-one-frequency-out prediction: fit a setting's records at two drive frequencies
together, predict the third's acceleration with bands (``bayes_inerter.study.prediction``).

For the control (results/full/records, the model's own) and the paper-like laboratory
(results/full/paper-like/records), both written by ``python studies/study.py``, and
settings A3 and B2: three joint fits per setting, each leaving one of 0.5, 1 and 1.5 Hz
out (``fit_joint``, ``--steps`` steps, seed 0, into runs/lofo, not committed). Writes
results/leave-one-frequency-out/prediction.csv (per case: the joint b, how much of the
held-out record the 94 % predictive band covers, with and without the noise term, phi
of the median prediction beside the held-out record's own fit's) and prediction.png.

    python studies/leave_one_frequency_out.py [--steps 1500] [--processes 2] [--settings A3 B2]
"""

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

from bayes_inerter.executor import LocalProcesses
from bayes_inerter.inference import PosteriorModel
from bayes_inerter.inference.fit import ALL_DRAWS_FILE, fit_joint
from bayes_inerter.masses import resolve_masses
from bayes_inerter.records import read_record
from bayes_inerter.study.analysis import write_csv
from bayes_inerter.study.prediction import predict_record
from bayes_inerter.study.manifest import script_configuration, write_manifest

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "results" / "leave-one-frequency-out"
SOURCES = {"control": ROOT / "results" / "full", "paper-like": ROOT / "results" / "full" / "paper-like"}
FREQS = (0.5, 1.0, 1.5)


def _model(rec) -> PosteriorModel:
    masses = resolve_masses(rec)
    return PosteriorModel(rec, m_s=masses.m_s, m_B=masses.m_B)


def _own_phi(device: str, name: str) -> float:
    """The held-out record's own fit's posterior mean phi (the study's)."""
    import csv

    with open(SOURCES[device] / "inertance_records.csv", newline="") as f:
        row = next(r for r in csv.DictReader(f) if r["record"] == name)
    return float(row["phi_mean"])


def _finished(out: Path, steps: int):
    """(converged, steps) of a joint fit in ``out`` that ran ``steps`` steps and kept its
    draws; (None, None) where there is none."""
    try:
        info = json.loads((out / "fit.json").read_text())
    except (OSError, ValueError):
        return None, None
    if info.get("iterations") != steps or not (out / ALL_DRAWS_FILE).is_file():
        return None, None
    return bool(info.get("converged")), int(info["iterations"])


def _case(job) -> dict:
    device, setting, held, steps, out = job
    names = [f"{setting}_{f:g}Hz" for f in FREQS]
    recs = {f: read_record(SOURCES[device] / "records" / f"{setting}_{f:g}Hz.csv") for f in FREQS}
    fitted = [recs[f] for f in FREQS if f != held]
    t0 = time.perf_counter()
    converged, iterations = _finished(Path(out), steps)
    if converged is None:  # not fitted yet (a finished fit's draws are reused: the prediction is redone)
        res = fit_joint(fitted, out, steps=steps, seed=0, processes=1, plots=False, all_draws=True)
        converged, iterations = bool(res.converged), int(res.iterations)
    fit_seconds = json.loads((Path(out) / "fit.json").read_text())["timings_s"]["total"]
    t0 = time.perf_counter()
    with np.load(Path(out) / ALL_DRAWS_FILE) as npz:
        draws = {k: npz[k] for k in npz.files}
    pred = predict_record(_model(recs[held]), [_model(r) for r in fitted], draws, setting,
                          rng=np.random.default_rng(0))
    np.savez_compressed(Path(out) / "prediction.npz", time=pred.time, measured=pred.measured, lo=pred.lo,
                        median=pred.median, hi=pred.hi)
    b = np.ravel(draws[f"b_{setting}"])
    truth = recs[held].metadata["true_parameters"]["b"]
    lo, hi = np.quantile(b, [0.03, 0.97])
    return {"device": device, "setting": setting, "held_out_hz": held,
            "fitted_hz": " and ".join(f"{f:g}" for f in FREQS if f != held), "b_median": float(np.median(b)),
            "b_3%": float(lo), "b_97%": float(hi), "b_truth": truth, "covers_b": bool(lo <= truth <= hi),
            "band_covers": pred.coverage, "band_covers_model_only": pred.coverage_model, "phi_predicted": pred.phi,
            "phi_own_fit": _own_phi(device, names[FREQS.index(held)]), "noise_sd": pred.noise_sd,
            "converged": converged, "steps": iterations, "fit_seconds": fit_seconds,
            "predict_seconds": time.perf_counter() - t0}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--steps", type=int, default=1500)
    ap.add_argument("--processes", type=int, default=2)
    ap.add_argument("--settings", nargs="+", default=["A3", "B2"])
    ap.add_argument("--out", default=str(ROOT / "runs" / "lofo"))
    args = ap.parse_args()
    write_manifest(Path(args.out), script_configuration())
    for device, folder in SOURCES.items():
        missing = [s for s in args.settings for f in FREQS if not (folder / "records" / f"{s}_{f:g}Hz.csv").is_file()]
        if missing:
            print(f"error: {folder / 'records'} lacks records of {sorted(set(missing))}; run python studies/study.py "
                  "first", file=sys.stderr)
            return 1
    jobs = [(d, s, f, args.steps, str(Path(args.out) / d / s / f"without_{f:g}Hz"))
            for d in SOURCES for s in args.settings for f in FREQS]
    rows, t0 = [], time.perf_counter()
    with LocalProcesses(args.processes) as pool:
        for k, end in enumerate(pool.as_completed(_case, jobs), 1):
            d, s, f = jobs[end.index][:3]
            if not end.ok:
                print(f"[{k}/{len(jobs)}] {d} {s} without {f:g} Hz: failed: {end.error}", flush=True)
                continue
            r = end.value
            rows.append(r)
            print(f"[{k}/{len(jobs)}] {d} {s} without {f:g} Hz: band covers {r['band_covers']:.2f}, phi "
                  f"{r['phi_predicted']:.3f} (own fit {r['phi_own_fit']:.3f}), b {r['b_median']:.1f} "
                  f"({r['b_3%']:.1f} to {r['b_97%']:.1f}), fit {r['fit_seconds']:.0f} s", flush=True)
    order = {(d, s, f): i for i, (d, s, f, _, _) in enumerate(jobs)}
    rows.sort(key=lambda r: order[(r["device"], r["setting"], r["held_out_hz"])])
    write_csv(RESULTS / "prediction.csv", rows)
    _figure(rows, Path(args.out))
    (RESULTS / "SECTION.md").write_text(_section(rows))
    commit = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=ROOT, capture_output=True,
                            text=True).stdout.strip()
    (RESULTS / "run.json").write_text(json.dumps({"commit": commit, "steps": args.steps, "seed": 0,
                                                  "processes": args.processes, "settings": args.settings,
                                                  "seconds": time.perf_counter() - t0}, indent=2) + "\n")
    print(f"wrote {RESULTS}")
    return 0


def _section(rows) -> str:
    """REPORT.md's section on this study, written from its rows."""
    from bayes_inerter.study.markdown import table

    shown = [{"device": r["device"], "setting": r["setting"], "held out (Hz)": f"{r['held_out_hz']:g}",
              "94 % band covers": f"{r['band_covers']:.2f}", "parameters alone": f"{r['band_covers_model_only']:.2f}",
              "phi predicted": f"{r['phi_predicted']:.3f}", "phi own fit": f"{r['phi_own_fit']:.3f}",
              "joint b (kg)": f"{r['b_median']:.1f} ({r['b_3%']:.1f} to {r['b_97%']:.1f})",
              "holds b": r["covers_b"], "converged": r["converged"]} for r in rows]
    lines = ["## Leave one frequency out: does the model predict a frequency it was not fitted at?", "",
             "Each setting's records at two drive frequencies fitted together (the joint model), the third "
             "record's low-passed acceleration predicted from its measured force, draw by draw, with the fitted "
             "records' residual sd as its noise (`study.prediction`, results/leave-one-frequency-out)."]
    for device in dict.fromkeys(r["device"] for r in rows):
        mine = [r for r in rows if r["device"] == device]
        cov = [r["band_covers"] for r in mine]
        lost = [r["phi_predicted"] - r["phi_own_fit"] for r in mine]
        worst = min(mine, key=lambda r: r["band_covers"])
        lines.append(f"- {device}: the 94 % band covers {min(cov):.2f} to {max(cov):.2f} of the held-out records "
                     f"(least: {worst['setting']} without {worst['held_out_hz']:g} Hz); the prediction's phi minus the "
                     f"record's own fit's: {min(lost):+.3f} to {max(lost):+.3f}.")
    lines += ["", table(shown, list(shown[0])), "", "![leave one frequency out](prediction.png)", ""]
    return "\n".join(lines)


def _figure(rows, runs: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = plt.figure(figsize=(12, 6.5))
    top = fig.add_subplot(2, 1, 1)
    labels = [f"{r['device']}\n{r['setting']} w/o {r['held_out_hz']:g}" for r in rows]
    x = np.arange(len(rows))
    top.bar(x - 0.2, [r["band_covers"] for r in rows], 0.4, label="94 % predictive band (noise included)")
    top.bar(x + 0.2, [r["band_covers_model_only"] for r in rows], 0.4, label="parameters' spread alone")
    top.plot(x, [r["phi_predicted"] for r in rows], "kD", ms=5, label="phi of the prediction")
    top.plot(x, [r["phi_own_fit"] for r in rows], "k_", ms=14, mew=2, label="phi of the record's own fit")
    top.axhline(0.94, color="k", lw=0.8, ls="--")
    top.set_xticks(x, labels, fontsize=7)
    top.set_ylim(0, 1.3)
    top.set_ylabel("share of the held-out record / phi")
    top.legend(fontsize=7, loc="upper center", ncol=4)
    for j, device in enumerate(("control", "paper-like")):
        case = next((r for r in rows if r["device"] == device and r["held_out_hz"] == 0.5), None)
        if case is None:
            continue
        ax = fig.add_subplot(2, 2, 3 + j)
        with np.load(runs / device / case["setting"] / "without_0.5Hz" / "prediction.npz") as p:
            t, keep = p["time"], slice(0, len(p["time"]))
            ax.fill_between(t[keep], p["lo"][keep], p["hi"][keep], color="C0", alpha=0.3, lw=0, label="94 % band")
            ax.plot(t[keep], p["median"][keep], "C0", lw=1, label="median prediction")
            ax.plot(t[keep], p["measured"][keep], "k", lw=0.7, label="held-out record (low-passed)")
        ax.set_title(f"{device} {case['setting']} at 0.5 Hz, predicted from 1 and 1.5 Hz", fontsize=9)
        ax.set_xlabel("time (s)")
        ax.set_ylabel("acceleration (m/s^2)")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(RESULTS / "prediction.png", dpi=100)
    plt.close(fig)


if __name__ == "__main__":
    sys.exit(main())
