"""Benchmark: how the cost grows with record length and with the number of records.

Run by hand: ``python benchmarks/bench_scale.py [--out results/performance]``.

1. Record length (10 s to 10 minutes of 1 kHz data): for each length, in a fresh
   process, the time to generate the record, to build the posterior model, one
   log-probability evaluation (median of 5) and the process's peak resident memory,
   after generating the record and at the end.
2. Number of records (1, 3, 9, 27 records of 10 s): one log-probability evaluation of
   the joint model (median of 5); a study's single-record fits are independent, so
   their cost is the per-record cost times the records over the worker processes.

Writes scale_length.csv, scale_records.csv and scale.png into ``--out``, and prints
ratios to the 10 s record's cost. The machine is shared and noisy: read the ratios.
"""

import argparse
import csv
import json
import subprocess
import sys
from pathlib import Path

from _timing import median_time, supported_theta

LENGTHS_S = (10, 30, 60, 120, 300, 600)
RECORDS = (1, 3, 9, 27)

CHILD = r"""
import json, resource, sys, time
import numpy as np
from bayes_inerter import paper_parameters
from bayes_inerter.records import GeneratorSettings, generate_record
from bayes_inerter.inference import PosteriorModel
duration = float(sys.argv[1])
t0 = time.perf_counter()
rec = generate_record(paper_parameters("A3"), 1.0, settings=GeneratorSettings(duration=duration), rng=0,
                      setting_name="A3")
t1 = time.perf_counter()
rss_generate = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
model = PosteriorModel(rec)
theta = model.to_theta(paper_parameters("A3"), 3e-3, 0.5)
if "zeta_B" in model.names:  # Table I's c_B lies outside the damping prior (_timing.supported_theta)
    theta[model.names.index("zeta_B")] = np.log(0.02)
t2 = time.perf_counter()
assert np.isfinite(model.log_prob(theta)[0])  # the first evaluation: compiles, not timed
times = []
for _ in range(5):
    t = time.perf_counter(); model.log_prob(theta); times.append(time.perf_counter() - t)
print(json.dumps({"duration_s": duration, "samples": len(rec.time), "generate_s": t1 - t0, "model_s": t2 - t1,
                  "log_prob_s": float(np.median(times)), "peak_rss_generate_mb": rss_generate,
                  "peak_rss_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}))
"""


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default=str(Path(__file__).resolve().parents[1] / "results" / "performance"))
    args = ap.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)

    rows = []
    for d in LENGTHS_S:
        res = subprocess.run([sys.executable, "-c", CHILD, str(d)], capture_output=True, text=True)
        if res.returncode != 0:
            sys.exit(f"length {d} s failed: {res.stderr.strip().splitlines()[-1]}")
        row = json.loads(res.stdout.strip().splitlines()[-1])
        rows.append(row)
        base = rows[0]
        print(f"{d:5d} s: generate {row['generate_s']:.2f} s, log_prob {1e3 * row['log_prob_s']:.1f} ms "
              f"({row['log_prob_s'] / base['log_prob_s']:.1f}x the 10 s record's, length {d / LENGTHS_S[0]:.0f}x), "
              f"peak memory {row['peak_rss_generate_mb']:.0f} MB after generating, {row['peak_rss_mb']:.0f} MB in all")

    from bayes_inerter import paper_parameters
    from bayes_inerter.inference import PosteriorModel
    from bayes_inerter.inference.posterior.joint import JointModel
    from bayes_inerter.records import paper_grid

    grid = [rec for _, _, rec in paper_grid(seed=0)]
    joint_rows = []
    for n in RECORDS:
        recs = grid[:n] if n > 1 else grid[:1]
        if n == 1:
            pm = PosteriorModel(recs[0])
            theta = supported_theta(pm, paper_parameters(recs[0].metadata["setting"]))
            t = median_time(lambda: pm.log_prob(theta), repeats=5)
        else:
            jm = JointModel(recs)
            centres = []
            for rec in recs:
                pm = PosteriorModel(rec)
                centres.append(pm.values(supported_theta(pm, paper_parameters(rec.metadata["setting"]))))
            theta = jm.start(centres)
            t = median_time(lambda: jm.log_prob(theta), repeats=5)
        joint_rows.append({"records": n, "log_prob_s": t, "settings": len({r.metadata["setting"] for r in recs})})
        print(f"{n:3d} records: log_prob {1e3 * t:.1f} ms ({t / joint_rows[0]['log_prob_s']:.1f}x one record's)")

    for name, table in (("scale_length.csv", rows), ("scale_records.csv", joint_rows)):
        with open(out / name, "w", newline="") as f:
            w = csv.DictWriter(f, fieldnames=list(table[0]))
            w.writeheader()
            w.writerows(table)

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, (a, b, c) = plt.subplots(1, 3, figsize=(13, 4))
    x = [r["duration_s"] for r in rows]
    a.loglog(x, [1e3 * r["log_prob_s"] for r in rows], "o-", label="log_prob")
    a.loglog(x, [1e3 * r["generate_s"] for r in rows], "s-", label="generate record")
    a.loglog(x, [1e3 * rows[0]["log_prob_s"] * d / x[0] for d in x], "k:", label="linear in length")
    a.set_xlabel("record length (s, 1 kHz)")
    a.set_ylabel("time (ms)")
    a.legend()
    a.grid(alpha=0.3, which="both")
    b.plot(x, [r["peak_rss_generate_mb"] for r in rows], "s-", label="after generating the record")
    b.plot(x, [r["peak_rss_mb"] for r in rows], "o-", label="after model and log_prob")
    b.legend()
    b.set_xlabel("record length (s, 1 kHz)")
    b.set_ylabel("peak resident memory (MB)")
    b.set_ylim(bottom=0)
    b.grid(alpha=0.3)
    n = [r["records"] for r in joint_rows]
    c.loglog(n, [1e3 * r["log_prob_s"] for r in joint_rows], "o-", label="joint log_prob")
    c.loglog(n, [1e3 * joint_rows[0]["log_prob_s"] * k for k in n], "k:", label="linear in records")
    c.set_xlabel("records in the joint model")
    c.set_ylabel("time (ms)")
    c.legend()
    c.grid(alpha=0.3, which="both")
    fig.suptitle("Cost against record length and number of records (this machine, 2 cores, shared)")
    fig.tight_layout()
    fig.savefig(out / "scale.png", dpi=110)
    print(f"wrote {out}/scale_length.csv, scale_records.csv, scale.png")


if __name__ == "__main__":
    main()
