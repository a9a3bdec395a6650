"""How fast the joint model's chain mixes under different emcee moves, side by side.

    python studies/joint_mixing.py [--settings A0 A3 B2] [--steps 2500] [--seed 0]
        [--variants default blocks] [--centres results/full] [--out results/joint-mixing]

The joint model (``inference.posterior.joint``) of the paper grid's records of ``--settings`` at
0.5, 1 and 1.5 Hz (generated with seed 0 and the default generator, as the full study
does) is sampled once per move set from the same start (the joint optimum Nelder-Mead
reaches from the medians of the records' own optima, or with ``--centres STUDY`` of the
posterior means of that study's two-port fits of the same records, as the study's joint
model starts) with the same seed, walkers and
coordinates (impedance). Move sets:

- ``default``: the sampler's default ensemble moves (DE 0.6, DE snooker 0.1, stretch
  0.3), without adaptation;
- ``adaptive``: the default moves with the fitted independence move, one t in the
  sampler's coordinates (``Adaptation(knots=None, blocks=0)``, the package's default on
  2026-11-25 until normal scores and block moves replaced it);
- ``scores``: the same with the independence proposal's t fitted in the chain's
  normal scores (``Adaptation(knots=200, blocks=0)``,
  :mod:`bayes_inerter.inference.sampling.marginals`);
- ``blocks``: the same, half of the fitted share to block moves of random coordinates
  from a normal in those scores (``Adaptation(knots=200, blocks=0.5,
  block_partners="random")``, ``moves.BlockMove``: the default since);
- ``correlated``: those block moves made of a coordinate and its most correlated
  partners (``Adaptation(block_partners="correlated")``, an option).

(Move sets measured earlier and since removed with their code, differential evolution
in random subspaces and a mixture of t's as the proposal: docs/inference.md, "Moves
tried and not kept".)

Writes ``tau.csv`` (integrated autocorrelation time per parameter and move set, emcee's
estimator on the chain after its first fifth) and ``summary.csv`` (largest tau, which
parameter, acceptance, steps per tau) into ``--out`` and prints the table. Each move set's
checkpoint is kept in ``--out``/<variant>/chain.h5: a rerun continues it.
"""

import argparse
import csv
import sys
from pathlib import Path

import numpy as np
from _table import ADAPTATIONS

from bayes_inerter.study.manifest import script_configuration, write_manifest

ROOT = Path(__file__).resolve().parents[1]

VARIANTS = ("default", "adaptive", "scores", "blocks")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--settings", nargs="+", default=["A0", "A3", "B2"])
    ap.add_argument("--steps", type=int, default=2500)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--variants", nargs="+", default=["default", "blocks"], choices=VARIANTS)
    ap.add_argument("--centres", default=None, help="a study folder whose two-port fits give the start's centres")
    ap.add_argument("--out", default=str(ROOT / "results" / "joint-mixing"))
    args = ap.parse_args()
    write_manifest(Path(args.out), script_configuration())

    import emcee
    from tqdm import tqdm

    from bayes_inerter.inference.posterior.joint import JointModel
    from bayes_inerter.inference.sampling.optimize import NM_RESTARTS, find_start, local_optimum
    from bayes_inerter.inference.sampling.sampler import DEFAULT_MOVES, Adaptation, run_sampler
    from bayes_inerter.records import paper_grid

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    records = [rec for _, _, rec in paper_grid(seed=0, names=tuple(args.settings))]
    records.sort(key=lambda r: (r.metadata["setting"], r.drive_frequency))
    jm = JointModel(tuple(records))
    start_file = out / "start.npy"
    if start_file.exists():
        theta = np.load(start_file)
        start = (theta, jm.log_prob(theta)[0])
    else:
        if args.centres:
            from bayes_inerter.study.analysis import collect
            from bayes_inerter.study.plan import record_name

            fits = {f.name: f for f in collect(Path(args.centres) / "fits") if f.model == "two-port"}
            names = [record_name(r.metadata["setting"], r.drive_frequency) for r in records]
            missing = [n for n in names if n not in fits]
            if missing:
                sys.exit(f"error: {args.centres} has no two-port fit of {', '.join(missing)}")
            given = [{n: fits[name].stat(n, "mean") for n in jm.parts[0].names} for name in names]
        else:
            rng = np.random.default_rng(args.seed)
            given = [part.values(find_start(part, rng)[0]) for part in tqdm(jm.parts, desc="record optima")]
        start = local_optimum(jm, jm.start(given), restarts=NM_RESTARTS)
        np.save(start_file, start[0])

    rows, table = [], []
    for variant in args.variants:
        (out / variant).mkdir(exist_ok=True)
        bar = tqdm(total=args.steps, desc=variant, unit="step")
        adaptation = Adaptation(**ADAPTATIONS[variant]) if variant in ADAPTATIONS else None
        run = run_sampler(jm, out / variant / "chain.h5", steps=args.steps, seed=args.seed, moves=list(DEFAULT_MOVES),
                          adaptation=adaptation, start=start, progress=lambda i, _t: bar.update(i - bar.n))
        bar.close()
        chain = run.chain(discard=run.iteration // 5)  # in theta: tau of what the user reads
        tau = emcee.autocorr.integrated_time(chain, tol=0)
        rows.append({"variant": variant, **{n: f"{t:.1f}" for n, t in zip(jm.names, tau)}})
        worst = int(np.argmax(tau))
        table.append({"variant": variant, "steps": run.iteration, "tau_max": f"{tau[worst]:.1f}",
                      "slowest": jm.names[worst], "tau_median": f"{np.median(tau):.1f}",
                      "acceptance": f"{np.mean(run.sampler.acceptance_fraction):.3f}",
                      "steps_per_tau": f"{len(chain) / tau[worst]:.1f}"})
    for name, data in (("tau.csv", rows), ("summary.csv", table)):
        with open(out / name, "w", newline="") as fh:
            w = csv.DictWriter(fh, fieldnames=list(data[0]))
            w.writeheader()
            w.writerows(data)
    for r in table:
        print("  ".join(f"{k}={v}" for k, v in r.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main())
