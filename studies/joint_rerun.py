"""The joint model of a study's records sampled again with the package's default sampler,
from the study's own single-record fits, into a folder of its own: to measure how many
steps and minutes the joint chain takes to converge without re-running the fits.

    python studies/joint_rerun.py [results/full] [--out results/joint-rerun] [--processes 2]

It starts as the study's joint model does (``study.run.run_joint``: the two-port fits'
posterior means, the joint optimum Nelder-Mead reaches from them) with the study's seed
0, and writes what ``inference.fit.fit_joint`` writes (fit.json with its timings,
summary.csv, b_draws.npz, corner.png, trace.png; the checkpoint chain.h5 stays local: a
rerun continues it). Prints the wall time, steps and whether the chain converged.
"""

import argparse
import sys
import time
from pathlib import Path

from bayes_inerter.study.manifest import script_configuration, write_manifest


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("study", nargs="?", default="results/full")
    ap.add_argument("--out", default="results/joint-rerun")
    ap.add_argument("--processes", type=int, default=2)
    args = ap.parse_args()
    write_manifest(Path(args.out), script_configuration())

    from tqdm import tqdm

    from bayes_inerter.inference.fit import fit_joint
    from bayes_inerter.inference.posterior.model import PosteriorModel
    from bayes_inerter.records import read_record
    from bayes_inerter.study.analysis import collect

    study = Path(args.study)
    fits = sorted((f for f in collect(study / "fits") if f.model == "two-port"), key=lambda f: f.name)
    paths = [study / "records" / f"{f.name}.csv" for f in fits]
    if len(fits) < 2 or not all(p.exists() for p in paths):
        sys.exit(f"error: {study} holds no two-port fits with their records (run the study first)")
    records = [read_record(p) for p in paths]
    names = PosteriorModel(records[0]).names
    centres = [{n: f.stat(n, "mean") for n in names} for f in fits]
    bar = tqdm(desc="joint chain", unit="step")
    t0 = time.perf_counter()
    res = fit_joint(records, Path(args.out), centres=centres, seed=0, processes=args.processes,
                    progress=lambda i, _target: bar.update(i - bar.n))
    bar.close()
    print(f"{args.out}: {res.iterations} steps, {res.reason}, {time.perf_counter() - t0:.0f} s")
    return 0 if res.converged else 1


if __name__ == "__main__":
    sys.exit(main())
