"""Benchmark: how often the adaptive sampler's independence proposals would be accepted,
one t fitted in the sampler's coordinates or in the chain's normal scores, on a converged
joint chain.

Run by hand after a full study whose joint chain converged (its checkpoint stays in the
study folder; it is not committed): ``python benchmarks/bench_proposal.py
[results/full] [--knots 0 200] [--wide W] [--proposals 400]
[--fit-from 130] [--fit-to STEP] [--seed 0]``.

For each proposal (fitted, like ``sampler.Adaptation``'s, to the chain's steps from
``--fit-from`` to ``--fit-to`` (default its last), in the sampler's coordinates, with
its default dof, scale and wide part), ``--proposals`` draws y are evaluated under the joint posterior and paired with
the chain's own stationary draws x (its second half): the independence move accepts y
from x with probability min(1, w(y) / w(x)), w = p / q, so the mean over the pairs is
its acceptance rate at equilibrium. The spread of the log weights log w(x) over the
chain's draws is printed too: a walker where w is e^s times its median accepts about
e^-s of the proposals, so the upper quantiles say how long the stickiest places hold a
walker. One core; the proposals share the machine alike.
"""

import argparse
import sys
import time
from pathlib import Path

import numpy as np


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("study", nargs="?", default="results/full")
    ap.add_argument("--proposals", type=int, default=400)
    ap.add_argument("--fit-from", type=int, default=130, help="first step the proposals are fitted to")
    ap.add_argument("--fit-to", type=int, default=None, help="last step they are fitted to (default: the chain's)")
    ap.add_argument("--knots", type=int, nargs="+", default=[0],
                    help="knots of the normal-scores map (0: none, the t's in the sampler's coordinates)")
    ap.add_argument("--wide", type=float, default=None, help="the wide part's share (default: Adaptation's)")
    ap.add_argument("--seed", type=int, default=0)
    args = ap.parse_args()

    import h5py

    from bayes_inerter.inference.sampling.coordinates import default_coordinates
    from bayes_inerter.inference.posterior.joint import JointModel
    from bayes_inerter.inference.sampling.moves import IndependenceMove
    from bayes_inerter.inference.sampling.sampler import Adaptation
    from bayes_inerter.inference.sampling.target import Target
    from bayes_inerter.records import read_record

    study = Path(args.study)
    chain_file = study / "joint" / "chain.h5"
    if not chain_file.exists():
        sys.exit(f"error: {chain_file} not found (the joint chain's checkpoint is not committed: run the study)")
    records = [read_record(p) for p in sorted((study / "records").glob("*.csv"))]
    jm = JointModel(tuple(records))
    target = Target(jm, default_coordinates(jm))
    with h5py.File(chain_file, "r") as f:
        chain, log_p = f["mcmc/chain"][:], f["mcmc/log_prob"][:]
    if not np.isclose(target(chain[-1, 0])[0], log_p[-1, 0], rtol=1e-12, atol=0):
        sys.exit(f"error: {chain_file} was not sampled from {study}/records with this model")
    d = chain.shape[-1]
    fit_to = len(chain) if args.fit_to is None else args.fit_to
    fit_draws = chain[args.fit_from:fit_to].reshape(-1, d)
    half = len(chain) // 2
    x, lx = chain[half:].reshape(-1, d), log_p[half:].reshape(-1)
    rng = np.random.default_rng(args.seed)
    pairs = rng.integers(len(x), size=20_000)
    adapt = Adaptation()
    wide = adapt.wide if args.wide is None else args.wide
    print(f"{chain_file}: {len(chain)} steps x {chain.shape[1]} walkers; proposals fitted to steps "
          f"{args.fit_from}-{fit_to}, paired with steps {half}-{len(chain)}")
    for knots in args.knots:
        t0 = time.perf_counter()
        move = IndependenceMove.fit(fit_draws, knots=knots or None, dof=adapt.dof, scale=adapt.scale, wide=wide,
                                    wide_scale=adapt.wide_scale)
        t_fit = time.perf_counter() - t0
        y = move.draw(args.proposals, np.random.RandomState(args.seed))
        t0 = time.perf_counter()
        ly = np.array([target(u)[0] for u in y])
        t_eval = (time.perf_counter() - t0) / len(y)
        lwx = lx[pairs] - move.log_density(x[pairs])
        lwy = ly - move.log_density(y)
        acc = np.mean([np.mean(np.exp(np.minimum(0.0, v - lwx))) if np.isfinite(v) else 0.0 for v in lwy])
        spread = np.quantile(lwx - np.median(lwx), [0.99, 0.999, 1.0])
        where = f"in normal scores ({knots} knots)" if knots else "in the sampler's coordinates"
        print(f"  one t {where}: acceptance {acc:.3f}; log weight p/q of the chain's "
              f"draws above its median: {spread[0]:.1f} (99 %), {spread[1]:.1f} (99.9 %), {spread[2]:.1f} (max); "
              f"fit {t_fit:.1f} s, {1e3 * t_eval:.0f} ms an evaluation, {np.sum(~np.isfinite(ly))} proposals "
              f"outside the domain")


if __name__ == "__main__":
    main()
