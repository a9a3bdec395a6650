"""Where does the truth sit in the posterior of the model's own physics, with and without
the drivetrain's noise transfer counted (``LikelihoodSettings(input_noise=)``)?

Devices of simulation-based calibration (``study.study_calibration``, the seed's
replicates as ``results/coverage-sbc-v2`` draws them) recorded again at their replicate's
frequency with other noise (seeds 1000 and up), with the study's noise on both channels
or on one. On each record: the likelihood's reference at the truth, tau and the delay
optimised there, then Nelder-Mead with restarts from the truth (``optimize.local_optimum``).
A row per record: twice the log posterior's rise from the truth to that optimum (about
the number of parameters where the posterior is calibrated, fewer where one sits on its
bound), f_share there and b's error. A row is written after every record, and a rerun
skips the rows already there. Design seeds only: coverage is measured on others.

``--joint F1 F2 ...`` records each device at those frequencies and takes the truth's
place in the joint model's posterior (``inference.posterior.joint.JointModel``: one device, its
frictions and deformations shared, the likelihood's tau per frequency), as the joint
calibration (results/coverage-sbc-joint) fits it; ``freq_hz`` then lists them.

    python studies/input_noise.py [--seed 4] [--replicates 18 25 17 43 9] [--records 6]
        [--variants input_noise=0 input_noise=16] [--noise both] [--joint 0.5 1.5]
        [--out results/likelihood-candidates/input_noise.csv]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
from pathlib import Path

import numpy as np
from scipy.optimize import minimize

from bayes_inerter.inference import PosteriorModel
from bayes_inerter.inference.posterior.joint import JointModel
from bayes_inerter.inference.posterior.likelihood import LikelihoodSettings
from bayes_inerter.inference.sampling.optimize import NM_RESTARTS, local_optimum
from bayes_inerter.records import GeneratorSettings, generate_record
from bayes_inerter.study.study_calibration import STUDY_SBC_PRIORS, StudyCalibration, replicate_device

from _table import append_row, likelihood_changes, read_rows

ROOT = Path(__file__).resolve().parents[1]
SETTINGS = ROOT / "results" / "coverage-sbc-v2" / "settings.json"
NOISES = {"both": {}, "force only": {"accel_noise": 0.0, "disp_noise": 0.0}, "acceleration only": {"force_noise": 0.0}}
FIELDS = ("seed", "replicate", "freq_hz", "noise", "variant", "realisation", "twice_deficit", "f_share",
          "f_share_true", "b_error_pct")


def variant_settings(base: dict, variant: str) -> LikelihoodSettings:
    """"default" (the study's likelihood settings as its settings.json holds them, the
    library's defaults for what it does not name), or "name=value" changes of them."""
    return LikelihoodSettings(**{**base, **likelihood_changes(variant)})


def _deficit(model, theta: np.ndarray, hyper: list) -> tuple[dict, float]:
    """(the sampled values at the optimum, twice the log posterior's rise to it): from
    ``theta`` (the truth) with the ``hyper`` parameters, which have no true value,
    optimised there first, then Nelder-Mead with restarts from it."""
    theta = np.array(theta, dtype=float)

    def neg(x):
        t = theta.copy()
        t[hyper] = x
        lp = model.log_prob(t)[0]
        return -lp if math.isfinite(lp) else 1e10

    found = minimize(neg, theta[hyper], method="Nelder-Mead")
    theta[hyper] = found.x
    best, lp_best = local_optimum(model, theta, restarts=NM_RESTARTS)
    return dict(zip(model.names, model.to_values(best))), 2 * (lp_best + found.fun)


def one(cs: StudyCalibration, k: int, noise: str, variant: str, j: int, base: dict) -> dict:
    device = replicate_device(cs, k)
    freq = cs.frequencies[k % len(cs.frequencies)]
    gain = device.truth.get("gain", 1.0)
    settings = dataclasses.replace(cs.generator, **NOISES[noise])
    record = generate_record(device.params, freq, settings=settings, rng=1000 + j, setting_name=cs.setting)
    record = dataclasses.replace(record, accel=record.accel * gain)
    model = PosteriorModel(record, priors=STUDY_SBC_PRIORS, likelihood=variant_settings(base, variant))
    theta = model.to_theta(device.params)
    if "gain" in model.names:
        theta[model.names.index("gain")] = math.log(gain) if model.all_priors["gain"].log_scale else gain
    model = model.with_reference(theta)
    hyper = [i for i, n in enumerate(model.names) if n in ("tau", "alpha", "delay")]
    values, twice = _deficit(model, theta, hyper)
    return {"seed": cs.seed, "replicate": k, "freq_hz": freq, "noise": noise, "variant": variant, "realisation": j,
            "twice_deficit": round(twice, 1), "f_share": round(values["f_share"], 4),
            "f_share_true": round(device.truth["f_share"], 4),
            "b_error_pct": round(100 * (values["b"] / device.truth["b"] - 1), 3)}


def one_joint(cs: StudyCalibration, k: int, noise: str, variant: str, j: int, base: dict) -> dict:
    """:func:`one` for the joint model of the device's records at ``cs.frequencies``."""
    device = replicate_device(cs, k)
    gain = device.truth.get("gain", 1.0)
    settings = dataclasses.replace(cs.generator, **NOISES[noise])
    rng = np.random.default_rng(1000 + j)
    records = [generate_record(device.params, f, settings=settings, rng=rng, setting_name=cs.setting)
               for f in cs.frequencies]
    records = [dataclasses.replace(r, accel=r.accel * gain) for r in records]
    model = JointModel(tuple(records), priors=STUDY_SBC_PRIORS, likelihood=variant_settings(base, variant))
    truth = {f"b_{cs.setting}": device.truth["b"], **{n: device.truth[n] for n in model.shared}, "gain": gain}
    hyper = [i for i, n in enumerate(model.names) if n not in truth]
    theta = np.array([(math.log(truth[n]) if model.all_priors[n].log_scale else truth[n]) if n in truth
                      else 0.0 if n == "delay" else float(np.mean(model.all_priors[n].bounds))
                      for n in model.names])  # tau mid-prior, the delay 0: no truth of their own
    model = model.with_reference(theta)
    values, twice = _deficit(model, theta, hyper)
    return {"seed": cs.seed, "replicate": k, "freq_hz": "+".join(f"{f:g}" for f in cs.frequencies), "noise": noise,
            "variant": variant, "realisation": j, "twice_deficit": round(twice, 1),
            "f_share": round(values["f_share"], 4), "f_share_true": round(device.truth["f_share"], 4),
            "b_error_pct": round(100 * (values[f"b_{cs.setting}"] / device.truth["b"] - 1), 3)}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=4)
    ap.add_argument("--replicates", type=int, nargs="+", default=[18, 25, 17, 43, 9])
    ap.add_argument("--records", type=int, default=6)
    ap.add_argument("--variants", nargs="+", default=["input_noise=0", "input_noise=16"])
    ap.add_argument("--noise", choices=list(NOISES), default="both")
    ap.add_argument("--joint", type=float, nargs="+", default=None, metavar="F",
                    help="the joint model of each device's records at these frequencies, Hz")
    ap.add_argument("--out", type=Path, default=ROOT / "results" / "likelihood-candidates" / "input_noise.csv")
    args = ap.parse_args(argv)
    study = json.loads(SETTINGS.read_text())
    cs = StudyCalibration(setting=study["setting"], frequencies=tuple(args.joint or study["frequencies"]),
                          generator=GeneratorSettings(**study["generator"]), steps=None, seed=args.seed,
                          single=not args.joint, likelihood=LikelihoodSettings(**study["likelihood"]))
    fit_one = one_joint if args.joint else one
    done = {(int(r["seed"]), int(r["replicate"]), r["freq_hz"], r["noise"], r["variant"], int(r["realisation"]))
            for r in read_rows(args.out)}
    for k in args.replicates:
        for variant in args.variants:
            for j in range(args.records):
                freq = ("+".join(f"{f:g}" for f in cs.frequencies) if args.joint
                        else str(float(cs.frequencies[k % len(cs.frequencies)])))
                if (args.seed, k, freq, args.noise, variant, j) not in done:
                    append_row(args.out, fit_one(cs, k, args.noise, variant, j, study["likelihood"]), FIELDS)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
