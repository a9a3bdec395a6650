"""How does the sensors' noise reach the motion-in likelihood's residual at the truth?
(results/coverage-sbc-v12; issue 39, item 4.)

A probe, not a calibration. For a few of SBC v12's devices (their true parameters, the
same records' settings, no deviations drawn) the device is recorded again N times with
fresh noise on both channels, on the force alone, or on the motion alone. On every
record, at the truth (the channels' delay at the value that fits the first records
best, the discrepancy tau at zero), the residual F_k - F^_k is formed and, across the
records, per harmonic k:

- ``residual``: its variance over the likelihood's noise variance V_k (the period
  scatter through the model's linear transfer; 1 if V_k is the residual's noise);
- ``sign``: the variance of the plate's Coulomb wave f1_0 S_k, whose switch times the
  likelihood reads from the noisy motion (no part of V_k: the reversal windows'
  deviations are to carry it);
- ``drivetrain``: the simulated drivetrain's response to the motion's noise beyond the
  linear term (the likelihood's input-noise shapes at the truth: the mean |d_k|^2);

each over V_k, and ``whitened``: the residual's mean square in the likelihood's full
covariance (V_k and every marginalised deviation), r' C^-1 r / 2K (1 if the
likelihood's covariance is the residual's on average over all directions).

    python studies/motion_noise_parts.py [--replicates 11 2 5 1] [--records 40] [--seed 31]
        [--out results/motion-noise-parts]

Writes parts.csv (replicate, frequency, noise, harmonic, the four ratios) and prints
one line per replicate and noise.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
from pathlib import Path

import numpy as np

from bayes_inerter.cli.study_script import config_from_folder
from bayes_inerter.inference.posterior.model import PosteriorModel
from bayes_inerter.inference.posterior.motion import (deviation_sd, input_noise_shapes, motion_variance,
                                                      predicted_force)
from bayes_inerter.records import generate_record
from bayes_inerter.study.manifest import script_configuration, write_manifest
from bayes_inerter.study.study_calibration import Config, replicate_device

from _table import write_table

ROOT = Path(__file__).resolve().parents[1]
V12 = ROOT / "results" / "coverage-sbc-v12"
NOISES = ("both", "force", "motion")
SHOWN = 8  # harmonics printed
DELAYS = np.linspace(-2e-4, 2e-4, 41)  # s: the channels' delay searched at the truth
DRAWS = 64  # the drivetrain's noise draws


def record_again(cs, device, freq, noise, rng):
    """The device recorded again with fresh noise on both channels, or one."""
    gen = cs.generator
    if noise == "force":
        gen = dataclasses.replace(gen, accel_noise=0.0, disp_noise=0.0)
    elif noise == "motion":
        gen = dataclasses.replace(gen, force_noise=0.0)
    rec = generate_record(device.params, freq, settings=gen, rng=rng, setting_name=cs.setting)
    return dataclasses.replace(rec, accel=rec.accel * device.truth.get("gain", 1.0))


def truth_theta(model, device, delay=0.0):
    value = {**device.truth, "tau": 1e-3, "delay": delay}
    return np.array([math.log(value[n]) if model.all_priors[n].log_scale else value[n] for n in model.names])


def parts(models, theta):
    """Per harmonic: the four ratios of the module docstring, over the records' models."""
    res, sign, V_all, white, drive = [], [], [], [], None
    for m in models:
        m = m.with_reference(theta)
        x, h, D = m.field_vector(theta), m.hyper(theta), m.motion
        F, _ = predicted_force(D, x, h["gain"], h["delay"])
        V, _ = motion_variance(D, x, 0.0, 0.0, h["gain"], h["delay"])
        r = D.harmonic.force - F
        res.append(r)
        sign.append(m.parameters(theta).f1_0 * D.sign)
        V_all.append(V)
        rr = np.concatenate([r.real, r.imag])
        C = np.diag(np.concatenate([V, V]) / 2.0) + (D.basis * deviation_sd(D, x) ** 2) @ D.basis.T
        white.append(float(rr @ np.linalg.solve(C, rr)) / rr.size)
        if drive is None:
            U = input_noise_shapes(D, x, h["gain"], h["delay"], draws=DRAWS)
            K = V.shape[0]
            drive = np.sum(U[:K] ** 2 + U[K:] ** 2, axis=1) if U.shape[1] else np.zeros(K)
    V = np.mean(V_all, axis=0)
    n = len(models)

    def spread(z):
        z = np.asarray(z)
        return np.sum(np.abs(z - z.mean(axis=0)) ** 2, axis=0) / (n - 1) / V

    return spread(res), spread(sign), drive / V, float(np.mean(white))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--replicates", type=int, nargs="+", default=[11, 2, 5, 1])
    ap.add_argument("--records", type=int, default=40)
    ap.add_argument("--seed", type=int, default=31)
    ap.add_argument("--out", default=str(ROOT / "results" / "motion-noise-parts"))
    args = ap.parse_args(argv)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    write_manifest(out, script_configuration())
    cs = dataclasses.replace(config_from_folder(Config, V12).settings(), draw_deviations=False)
    rows = []
    for k in args.replicates:
        device = replicate_device(cs, k)
        freq = cs.frequencies[k % len(cs.frequencies)]
        for j, noise in enumerate(NOISES):
            records = [record_again(cs, device, freq, noise, np.random.default_rng([args.seed, k, j, r]))
                       for r in range(args.records)]
            models = [PosteriorModel(r, priors=cs.priors(), likelihood=cs.likelihood) for r in records]
            theta = truth_theta(models[0], device)
            di = models[0].names.index("delay")
            first = models[: min(8, len(models))]

            def total(d):
                t = theta.copy()
                t[di] = d
                return sum(m.with_reference(t).log_likelihood(t)[0] for m in first)
            theta[di] = DELAYS[int(np.argmax([total(d) for d in DELAYS]))]
            residual, sign, drive, white = parts(models, theta)
            for h in range(residual.shape[0]):
                rows.append({"replicate": k, "frequency": freq, "noise": noise, "harmonic": h + 1,
                             "residual": f"{residual[h]:.3f}", "sign": f"{sign[h]:.3f}",
                             "drivetrain": f"{drive[h]:.3f}", "whitened": f"{white:.3f}",
                             "delay": f"{theta[di]:.3g}", "records": len(models)})
            print(f"replicate {k} ({freq:g} Hz), noise on {noise:6s}: residual / V at k=1..{SHOWN} "
                  f"{np.round(residual[:SHOWN], 2).tolist()} (mean {residual.mean():.2f}); sign / V "
                  f"{np.round(sign[:SHOWN], 2).tolist()}; drivetrain / V {np.round(drive[:SHOWN], 2).tolist()}; "
                  f"whitened {white:.2f}", flush=True)
            write_table(out / "parts.csv", rows)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
