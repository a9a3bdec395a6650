"""Does the records' noise pull b's optimum to one side? The optimum (``find_start``,
the sampler's start) of one setting's record at one frequency, with the generator's
noise on both sensors, on the load cell only or on the accelerometer only, over
several noise seeds.

    python studies/noise_bias.py [--setting A0] [--freq 1.5] [--seeds 0 1 2 3 4 5 6]
        [--processes 2] [--out results/sensitivity/noise_bias.csv]

The noise of each sensor is the same draw in every case (the generator draws both and
scales one by zero), so the cases differ only in which sensor is noisy. Writes one row
per (noise, seed): the optimum's b, b_app, and their relative offsets from the
generating values, and prints them.
"""

import argparse
import dataclasses
from pathlib import Path

from _table import map_rows, write_rows

ROOT = Path(__file__).resolve().parents[1]

CASES = ("both", "load cell only", "accelerometer only")


def _optimum(job):
    setting, freq, case, seed = job
    import numpy as np

    from bayes_inerter.device import apparent_inertance
    from bayes_inerter.inference.posterior.model import PosteriorModel
    from bayes_inerter.inference.sampling.optimize import find_start
    from bayes_inerter.records.generator import GeneratorSettings, paper_record

    g = GeneratorSettings()
    if case == "load cell only":
        g = dataclasses.replace(g, accel_noise=0.0)
    elif case == "accelerometer only":
        g = dataclasses.replace(g, force_noise=0.0)
    rec = paper_record(setting, freq, settings=g, seed=seed)
    pm = PosteriorModel(rec)
    theta, _ = find_start(pm, np.random.default_rng(0))
    v = pm.values(theta)
    t = rec.metadata["true_parameters"]
    app_truth = apparent_inertance(t["b"], t["k_n"], t["c_n"])
    return {"record": f"{setting}_{freq:g}Hz", "noise": case, "seed": seed, "b": round(v["b"], 2),
            "b_truth": t["b"], "b_offset_%": round(100 * (v["b"] / t["b"] - 1), 3),
            "b_app": round(v["b_app"], 2), "b_app_offset_%": round(100 * (v["b_app"] / app_truth - 1), 3)}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--setting", default="A0")
    ap.add_argument("--freq", type=float, default=1.5)
    ap.add_argument("--seeds", type=int, nargs="+", default=list(range(7)))
    ap.add_argument("--processes", type=int, default=2)
    ap.add_argument("--out", default=str(ROOT / "results" / "sensitivity" / "noise_bias.csv"))
    args = ap.parse_args()
    name = args.setting.upper()
    jobs = [(name, args.freq, case, args.seeds[0]) for case in CASES[:2]]
    jobs += [(name, args.freq, CASES[2], s) for s in args.seeds]
    rows = map_rows(_optimum, jobs, args.processes)
    write_rows(args.out, rows)


if __name__ == "__main__":
    main()
