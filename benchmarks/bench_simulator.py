"""Benchmark: the exact kernel against scipy's Radau on the same record.

Run by hand: ``python benchmarks/bench_simulator.py``. Prints medians and ratios measured
side by side in one run (this machine is shared and noisy: read ratios, not absolutes),
and appends a row to results/performance/simulator.csv (commit, machine, date).
"""

import argparse
import statistics
import time

import numpy as np
from _timing import record_row

from bayes_inerter import paper_parameters, simulate
from bayes_inerter.networks import build_network
from bayes_inerter.network import compile_network
from bayes_inerter.simulate import contacts, run_piecewise_linear
from bayes_inerter.simulate.reference import hybrid_reference, inverse_dynamics_force


def timed(fn, repeats):
    out, times = None, []
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return out, statistics.median(times)


def rel_error(a, ref):
    return np.linalg.norm(a - ref) / np.linalg.norm(ref - ref.mean())


def main():
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("--setting", default="A1")
    ap.add_argument("--freq", type=float, default=1.0)
    ap.add_argument("--duration", type=float, default=10.0)
    ap.add_argument("--repeats", type=int, default=20)
    ap.add_argument("--reference", action="store_true", help="also run the slow hybrid reference")
    args = ap.parse_args()

    p = paper_parameters(args.setting)
    t, f = inverse_dynamics_force(p, args.freq, duration=args.duration, ramp=1.0)
    compiled = compile_network(build_network("reduced", p))
    A, B = compiled.state_space()
    h = t[1] - t[0]
    print(f"record: {args.setting}, {args.freq} Hz, {args.duration} s at {1 / h:.0f} Hz "
          f"({len(t)} samples); contacts: {len(contacts(compiled.coulomb_bounds, compiled.masses)[0])}")

    simulate(p, t, f)  # compile the kernel
    a, t_api = timed(lambda: simulate(p, t, f), args.repeats)
    _, t_kernel = timed(lambda: run_piecewise_linear(compiled, A, B, f, h), args.repeats)

    a_radau, t_radau = timed(lambda: simulate(p, t, f, method="stiff", v_eps=1e-4, rtol=1e-6), 3)
    print(f"exact kernel, simulate():         median {t_api * 1e3:8.3f} ms")
    print(f"exact kernel, without API checks: median {t_kernel * 1e3:8.3f} ms")
    print(f"scipy Radau rtol 1e-6, tanh 1e-4: median {t_radau * 1e3:8.1f} ms")
    print(f"speed-up (Radau / simulate()): {t_radau / t_api:,.0f}x")
    print(f"Radau's difference from the exact kernel: {rel_error(a_radau, a):.2e} (eq. 5 norm)")
    if args.reference:
        ref, t_ref = timed(lambda: hybrid_reference(compiled, t, f), 1)
        print(f"hybrid reference ({t_ref:.1f} s): kernel error {rel_error(a, ref):.2e}, "
              f"Radau error {rel_error(a_radau, ref):.2e}")

    print("\ncost against record length (simulate(), median):")
    per_sample = {}
    for duration in (1.0, 10.0, 100.0, 600.0):
        tt, ff = inverse_dynamics_force(p, args.freq, duration=duration, ramp=1.0)
        _, tm = timed(lambda: simulate(p, tt, ff), max(3, args.repeats // 4))
        per_sample[duration] = tm / len(tt)
        print(f"  {duration:6.0f} s ({len(tt):7d} samples): {tm * 1e3:9.3f} ms, "
              f"{tm / len(tt) * 1e9:6.0f} ns/sample")
    path = record_row("simulator", {
        "setting": args.setting, "freq_hz": args.freq, "duration_s": args.duration, "repeats": args.repeats,
        "simulate_ms": round(t_api * 1e3, 4), "kernel_ms": round(t_kernel * 1e3, 4),
        "radau_ms": round(t_radau * 1e3, 1), "speedup_radau": round(t_radau / t_api, 1),
        "radau_difference": f"{rel_error(a_radau, a):.3e}",
        **{f"ns_per_sample_{d:g}s": round(v * 1e9, 1) for d, v in per_sample.items()}})
    print(f"wrote a row to {path}")


if __name__ == "__main__":
    main()
