"""Benchmark: this checkout's log-probability evaluations and sampler steps against an
earlier commit's, side by side in one run.

Run by hand from the project root: ``python benchmarks/bench_versions.py [--before f6b0f7d]
[--rounds 5]``.

The earlier commit is checked out with ``git worktree`` into a temporary folder (the
project's git history is needed). Each round runs, for each version in turn, one fresh
Python process that imports that version and times on generated records (A3 at 1 Hz, and
the paper's 27-record grid for the joint model):

- ``single``: one single-record two-port evaluation in the sampler's coordinates (the
  target emcee calls, ``target.Target``), median of 300 points drawn around the
  paper's parameters;
- ``joint``: one 27-record joint evaluation, median of 20 points;
- ``steps``: 150 sampler steps of a single-record fit from a fixed start (no start-up
  search), seconds per step.

The versions alternate within every round, so the machine's drift falls on both; the
table gives the median over the rounds of each and the ratio before / now. The machine
is shared and noisy: read the ratios. The first round also compiles each version's
kernels (numba's cache), so it is left out.
"""

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from _timing import record_row

ROOT = Path(__file__).resolve().parents[1]

PROBE = r'''
import json, time, sys, tempfile
import numpy as np
from bayes_inerter.device import paper_parameters
from bayes_inerter.records.generator import paper_grid, paper_record
from bayes_inerter.inference import PosteriorModel, run_sampler
try:
    from bayes_inerter.inference.posterior.joint import JointModel
    from bayes_inerter.inference.sampling.target import Target
    from bayes_inerter.inference.sampling.coordinates import default_coordinates
except ImportError:  # a commit from before inference/ was split into its three layers
    from bayes_inerter.inference.joint import JointModel
    from bayes_inerter.inference.target import Target
    from bayes_inerter.inference.coordinates import default_coordinates

def med(fn, xs):
    fn(xs[0])
    ts = []
    for x in xs:
        t0 = time.perf_counter(); fn(x); ts.append(time.perf_counter() - t0)
    return float(np.median(ts))

rng = np.random.default_rng(0)
rec = paper_record("A3", 1.0, seed=0)
pm = PosteriorModel(rec)
coords = default_coordinates(pm)
target = Target(pm, coords)
def supported(model, params):
    """theta at params, the plate's damping ratio at 2 % where sampled (Table I's lies outside its prior)."""
    t = model.to_theta(params, 0.003, 0.3)
    if "zeta_B" in model.names:
        t[model.names.index("zeta_B")] = np.log(0.02)
    assert np.isfinite(model.log_prob(t)[0])
    return t

theta = supported(pm, paper_parameters("A3"))
u0 = coords.to_u(theta)
us = [u0 + 0.01 * rng.standard_normal(len(u0)) for _ in range(300)]
out = {"single": med(target, us)}

records = [r for _, _, r in paper_grid(seed=0)]
jm = JointModel(tuple(records))
medians = []
for r in records:
    p = paper_parameters(r.metadata["setting"])
    t = supported(PosteriorModel(r), p)
    medians.append(dict(zip(jm.parts[0].names, PosteriorModel(r).to_values(t))))
jt = jm.start(medians)
out["joint"] = med(jm.log_prob, [jt + 0.001 * rng.standard_normal(len(jt)) for _ in range(20)])

with tempfile.TemporaryDirectory() as d:
    start = (theta, pm.log_prob(theta)[0])
    run_sampler(pm, d + "/c.h5", steps=10, start=start, seed=1)  # warm-up: compile, first steps
    t0 = time.perf_counter()
    run_sampler(pm, d + "/c2.h5", steps=150, start=start, seed=1)
    out["steps"] = (time.perf_counter() - t0) / 150
print(json.dumps(out))
'''


def run_probe(src: Path) -> dict:
    env = {"PYTHONPATH": str(src), "PATH": "/usr/bin:/bin", "HOME": str(Path.home())}
    res = subprocess.run([sys.executable, "-c", PROBE], cwd=src, env=env, capture_output=True, text=True)
    if res.returncode != 0:
        sys.exit(f"error: the probe failed in {src}:\n{res.stderr[-2000:]}")
    return json.loads(res.stdout.strip().splitlines()[-1])


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--before", default="f6b0f7d", help="the earlier commit (default f6b0f7d)")
    ap.add_argument("--rounds", type=int, default=5)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        old = Path(tmp) / "before"
        subprocess.run(["git", "worktree", "add", "--detach", str(old), args.before], cwd=ROOT, check=True,
                       capture_output=True)
        try:
            results = {"before": [], "now": []}
            for r in range(args.rounds + 1):
                for label, src in (("before", old), ("now", ROOT)):
                    got = run_probe(src)
                    if r > 0:  # round 0 compiles
                        results[label].append(got)
                    print(f"round {r} {label}: " + ", ".join(f"{k} {v * 1e3:.3f} ms" for k, v in got.items()),
                          flush=True)
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(old)], cwd=ROOT, check=False)
    print(f"\nmedians over {args.rounds} rounds (before = {args.before}):")
    for key in results["now"][0]:
        b = statistics.median(x[key] for x in results["before"])
        n = statistics.median(x[key] for x in results["now"])
        print(f"  {key:7s} before {b * 1e3:9.3f} ms   now {n * 1e3:9.3f} ms   ratio {b / n:.2f}")
        record_row("versions", {"measure": key, "before": args.before, "rounds": args.rounds,
                                "before_ms": round(b * 1e3, 3), "now_ms": round(n * 1e3, 3), "ratio": round(b / n, 3)})


if __name__ == "__main__":
    main()
