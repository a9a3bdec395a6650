"""Benchmark: would simulating on a coarser grid than the record's make the likelihood cheaper?

Run by hand: ``python benchmarks/bench_coarse_grid.py [results/full] [--factors 2 4 8]
[--repeats 15]``.

The likelihood simulates every record at its own rate (1 kHz) and compares the 30 Hz
low-passed accelerations. The idea tried here: decimate the force by q
(``scipy.signal.resample_poly``, its anti-alias FIR), simulate at fs / q, bring the
simulated velocity back to fs by the same polyphase filter and differentiate it there
(the "mean" sampling, as the likelihood uses). For each record of the study (the paper's
parameters of its setting) it prints the rms difference of the low-passed acceleration
from the full-rate one inside the likelihood's window, beside the residual of the
full-rate simulation against the record at the truth, and the median times of both
simulations, measured side by side in one run (the machine is shared: read ratios).
"""

import argparse
import sys
from pathlib import Path

import numpy as np
from _timing import median_time
from scipy import signal


def coarse_acceleration(params, time_s, force, q):
    """The driven terminal's mean acceleration at the record's rate, simulated at 1 / q of it."""
    from bayes_inerter.networks import build_network
    from bayes_inerter.network import compile_network
    from bayes_inerter.simulate import run_piecewise_linear

    h = time_s[1] - time_s[0]
    compiled = compile_network(build_network("reduced", params))
    A, B = compiled.state_space(viscous=True)
    _, states = run_piecewise_linear(compiled, A, B, signal.resample_poly(force, 1, q), h * q, store=True)
    velocity = signal.resample_poly(states[:, 0], q, 1)[: len(time_s)]
    return np.gradient(velocity, h)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("study", nargs="?", default="results/full")
    ap.add_argument("--records", nargs="+", default=["A0_0.5Hz", "A0_1.5Hz", "A3_1Hz", "B2_1.5Hz", "A6_0.5Hz"])
    ap.add_argument("--factors", type=int, nargs="+", default=[2, 4, 8])
    ap.add_argument("--repeats", type=int, default=15)
    args = ap.parse_args()

    from bayes_inerter import paper_parameters, simulate
    from bayes_inerter.inference.posterior.model import PosteriorModel
    from bayes_inerter.records import read_record
    from bayes_inerter.records.conditioning import lowpass

    for name in args.records:
        path = Path(args.study) / "records" / f"{name}.csv"
        if not path.exists():
            sys.exit(f"error: {path} not found (generate the study's records first)")
        rec = read_record(path)
        model = PosteriorModel(rec)
        params = paper_parameters(rec.metadata["setting"])
        w, fs, cut = model.window, rec.fs, model.likelihood.cutoff

        def full():
            return simulate(params, rec.time, rec.force, sampling="mean")

        ref = lowpass(full(), fs, cut)
        resid = np.sqrt(np.mean((ref[w] - model.measured_lp[w]) ** 2))
        t_full = median_time(full, args.repeats)
        parts = [f"{name}: residual at the truth {resid:.2e} m/s^2, full rate {1e3 * t_full:.2f} ms"]
        for q in args.factors:
            a = lowpass(coarse_acceleration(params, rec.time, rec.force, q), fs, cut)
            err = np.sqrt(np.mean((a[w] - ref[w]) ** 2))
            t_q = median_time(lambda: coarse_acceleration(params, rec.time, rec.force, q), args.repeats)
            parts.append(f"1/{q} rate: error {err:.1e}, {t_q / t_full:.2f} x the time")
        print("; ".join(parts))


if __name__ == "__main__":
    main()
