"""Benchmark: how far one block move carries each coordinate, with blocks of random
coordinates against blocks of a coordinate and its most correlated partners, on a
converged chain.

Run by hand on the checkpoint of a single-record fit of a paper-like record (not
committed: a fit's folder keeps it)::

    python benchmarks/bench_block_partners.py CHAIN --record A0:1 --paper-like 0
        [--last 20000] [--states 12] [--repeats 6] [--seed 1]

The block moves (``moves.BlockMove``, the default sizes 1 to 3) are fitted as
``Adaptation`` fits them, in the chain's normal scores (200 knots), to its last
``--last`` steps; the walkers of ``--states`` steps drawn from those are the states
proposed from, each ``--repeats`` times by each move, and every proposal is accepted
with its Metropolis-Hastings probability under the posterior (the fit's own, checked
against the log-probabilities the chain stored). Per coordinate, the mean of acceptance
times the squared jump in normal scores (the expected squared jump distance, ESJD) says
how far one application of the move carries it: in units of its posterior variance, so
a coordinate moved 0.006 a step needs hundreds of such steps to cross its posterior.
Both moves see the same states and seed. One row per choice of partners to
results/performance/block_partners.csv; the ratios are printed.
"""

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from _timing import record_row

from bayes_inerter.device import setting_and_frequency
from bayes_inerter.inference import Adaptation, PosteriorModel
from bayes_inerter.inference.sampling.checkpoint import read_chain, stored_identity
from bayes_inerter.inference.sampling.coordinates import continue_at, default_coordinates, reference_tolerance
from bayes_inerter.inference.sampling.moves.block import PARTNERS
from bayes_inerter.inference.sampling.target import Target
from bayes_inerter.records.paper_like import PaperLike, paper_like_record


def _esjd(move, target, x, lp, repeats: int, seed: int):
    """(acceptance, per-coordinate ESJD in its normal scores) of ``move`` from the states ``x``."""
    random = np.random.RandomState(seed)
    scores = move.scores
    z = scores.forward(x)[0]
    accepted, jumps = [], np.zeros(x.shape[1])
    for _ in range(repeats):
        q, factors = move.get_proposal(x, random)
        new = np.array([v for v, _ in target.batch(q)])
        a = np.where(np.isfinite(new), np.exp(np.minimum(0.0, np.nan_to_num(new - lp + factors, nan=-np.inf))), 0.0)
        jumps += np.mean(a[:, None] * (scores.forward(q)[0] - z) ** 2, axis=0)
        accepted.append(a.mean())
    return float(np.mean(accepted)), jumps / repeats


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("chain", help="a single-record fit's chain.h5")
    ap.add_argument("--record", required=True, help="SETTING:FREQUENCY of the record it sampled")
    ap.add_argument("--paper-like", type=int, required=True, metavar="LAB", help="the paper-like laboratory's seed")
    ap.add_argument("--last", type=int, default=20_000, help="the chain's last steps the moves are fitted to")
    ap.add_argument("--states", type=int, default=12, help="steps whose walkers are proposed from")
    ap.add_argument("--repeats", type=int, default=6)
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()
    try:
        setting, freq = setting_and_frequency(args.record)
    except ValueError as exc:
        sys.exit(f"error: --record {args.record!r} is not a record of the paper grid ({exc})")
    identity = stored_identity(args.chain)
    if identity is None:
        sys.exit(f"error: {args.chain} holds no checkpoint of a fit")
    rec = paper_like_record(setting, freq, seed=args.paper_like, device=PaperLike())
    masses = identity["masses"][0]
    pm = PosteriorModel(rec, m_s=masses["m_s"], m_B=masses["m_B"]).with_reference(np.array(identity["reference"]))
    coords = continue_at(default_coordinates(pm), identity["coordinates"], reference_tolerance(pm))
    target = Target(pm, coords)
    chain, log_p = read_chain(args.chain, log_prob=True)
    chain, log_p = chain[-args.last:], log_p[-args.last:]
    if not np.isclose(target(chain[-1, 0])[0], log_p[-1, 0], rtol=1e-9, atol=0):
        sys.exit(f"error: {args.chain} was not sampled from {args.record} of laboratory {args.paper_like} "
                 "with this model")
    rng = np.random.default_rng(args.seed)
    steps = rng.integers(0, len(chain), args.states)
    x, lp = chain[steps].reshape(-1, chain.shape[-1]), log_p[steps].ravel()
    results = {}
    for partners in PARTNERS:
        _, move = Adaptation(block_partners=partners).fit(chain, log_p)
        if move is None:
            sys.exit(f"error: {args.chain} holds too few steps to fit a block move")
        results[partners] = _esjd(move, target, x, lp, args.repeats, args.seed)
        acc, esjd = results[partners]
        record_row("block_partners", {
            "chain": Path(args.chain).parent.name, "record": f"{setting}_{freq:g}Hz", "laboratory": args.paper_like,
            "steps_fitted": len(chain), "states": len(x), "repeats": args.repeats, "partners": partners,
            "acceptance": round(acc, 3), "min_esjd": round(float(esjd.min()), 4),
            "slowest": pm.names[int(np.argmin(esjd))], "esjd": json.dumps(dict(zip(pm.names, np.round(esjd, 4))))})
    print(f"{args.record} of laboratory {args.paper_like}: one block move's ESJD in normal scores "
          f"({len(x)} walkers' states x {args.repeats})")
    print(f"  {'coordinate':10s} " + " ".join(f"{p:>11s}" for p in PARTNERS) + "   ratio")
    for i, name in enumerate(pm.names):
        a, b = (results[p][1][i] for p in PARTNERS)
        print(f"  {name:10s} {a:11.4f} {b:11.4f}   {b / a:5.2f}")
    (a_acc, a), (b_acc, b) = (results[p] for p in PARTNERS)
    print(f"  acceptance {a_acc:.3f} and {b_acc:.3f}; the slowest coordinate's ESJD {a.min():.4f} "
          f"({pm.names[int(np.argmin(a))]}) and {b.min():.4f} ({pm.names[int(np.argmin(b))]}): "
          f"{b.min() / a.min():.2f} x")


if __name__ == "__main__":
    main()
