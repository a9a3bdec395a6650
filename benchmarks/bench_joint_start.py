"""Benchmark: the joint model's start-up search, its records on one process or shared.

Run by hand: ``python benchmarks/bench_joint_start.py [--study results/full]
[--iterations 150] [--repeats 3] [--processes 2]``.

The joint model of the study's records (the paper grid generated with seed 0, as the
full study does) and its start (``JointModel.start`` of the posterior means of the
study's two-port fits, as ``study.run_joint`` gives ``fit_joint``): Nelder-Mead
(``optimize.local_optimum``, ``--iterations`` iterations, no restarts) with
``model.log_prob`` on one process and with ``joint.pooled_log_prob`` on ``--processes``,
alternating, ``--repeats`` times each. Prints the median seconds of each, their ratio,
and whether the two searches ended on the same point (they must: the pooled sum is the
same sum, bit for bit).
"""

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np
from _timing import record_row

ROOT = Path(__file__).resolve().parents[1]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--study", default=str(ROOT / "results" / "full"))
    ap.add_argument("--iterations", type=int, default=150)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--processes", type=int, default=2)
    args = ap.parse_args()
    if args.iterations < 1 or args.repeats < 1 or args.processes < 2:
        sys.exit("error: --iterations and --repeats must be positive and --processes at least 2")

    from bayes_inerter.inference.posterior.joint import JointModel, pooled_log_prob
    from bayes_inerter.inference.sampling.optimize import local_optimum
    from bayes_inerter.records import paper_grid
    from bayes_inerter.study.analysis import collect
    from bayes_inerter.study.plan import record_name

    fits = {f.name: f for f in collect(Path(args.study) / "fits") if f.model == "two-port"}
    records = [rec for _, _, rec in paper_grid(seed=0)]
    records.sort(key=lambda r: record_name(r.metadata["setting"], r.drive_frequency))
    names = [record_name(r.metadata["setting"], r.drive_frequency) for r in records]
    missing = [n for n in names if n not in fits]
    if missing:
        sys.exit(f"error: {args.study} has no two-port fit of {', '.join(missing)}")
    jm = JointModel(tuple(records))
    theta = jm.start([{n: fits[name].stat(n, "mean") for n in jm.parts[0].names} for name in names])
    jm.log_prob(theta)  # compile the kernel before timing

    times = {"one process": [], f"{args.processes} processes": []}
    ends = {}
    with pooled_log_prob(jm, args.processes) as pooled:
        pooled(theta)
        for _ in range(args.repeats):
            for label, lp in (("one process", jm.log_prob), (f"{args.processes} processes", pooled)):
                t0 = time.perf_counter()
                ends[label] = local_optimum(jm, theta, maxiter=args.iterations, log_prob=lp)
                times[label].append(time.perf_counter() - t0)
    med = {k: statistics.median(v) for k, v in times.items()}
    for label, secs in times.items():
        print(f"{label}: median {med[label]:.2f} s over {len(secs)} searches of {args.iterations} iterations "
              f"({', '.join(f'{s:.2f}' for s in secs)})")
    (a, b) = med.values()
    same = np.array_equal(*(e[0] for e in ends.values()))
    print(f"ratio one / pooled: {a / b:.2f}; same end point: {same}; log posterior there "
          f"{next(iter(ends.values()))[1]:.3f}")
    path = record_row("joint_start", {"processes": args.processes, "iterations": args.iterations,
                                      "repeats": args.repeats, "one_process_s": round(a, 3),
                                      "pooled_s": round(b, 3), "ratio": round(a / b, 3), "same_end_point": bool(same)})
    print(f"wrote a row to {path}")


if __name__ == "__main__":
    main()
