"""Where the walkers move, and what it changes: the same record sampled from the same
start and seed three ways, side by side:

- ``physical``: in the model's parameters theta, emcee's moves alone;
- ``physical+ridge``: the same with the nut-ridge move (``inference.sampling.moves.NutRidgeMove``);
- ``impedance``: in the impedance coordinates (``inference.sampling.coordinates``, the default).

    python studies/walks.py [--record A3:1 ...] [--steps 3000] [--seed 0]
        [--processes 2] [--out runs/long-chain/walks.csv]

The walks compare where emcee's ensemble moves go, so none of them adds the fitted
independence move (``sampler.Adaptation``; ``benchmarks/bench_adaptation.py`` measures
that). Records are the full study's (the paper grid generated with seed 0), named
SETTING:FREQUENCY. Each (record, walk) pair is one chain on one process. Writes one row
per chain: acceptance, the largest autocorrelation time and b's (in theta, over the last
three quarters), R-hat and bulk ESS of the last three quarters, b's and log10 k_n's 3rd,
50th and 97th percentiles there, and whether b's generating value lies between them.
"""

import argparse
import tempfile
import time
from pathlib import Path

import numpy as np

from _table import map_rows, record_arg, write_rows

ROOT = Path(__file__).resolve().parents[1]


WALKS = ("physical", "physical+ridge", "impedance")


def _chain(job):
    setting, freq, walk, steps, seed, folder = job
    import emcee

    from bayes_inerter.inference.sampling.diagnostics import rhat_ess
    from bayes_inerter.inference.posterior.model import PosteriorModel
    from bayes_inerter.inference.sampling.sampler import DEFAULT_MOVES, default_moves, run_sampler
    from bayes_inerter.records.generator import paper_record

    rec = paper_record(setting, freq, seed=0)
    pm = PosteriorModel(rec)
    coordinates = walk.split("+")[0]
    moves = default_moves(pm) if walk == "physical+ridge" else list(DEFAULT_MOVES)
    t0 = time.perf_counter()
    run = run_sampler(pm, Path(folder) / f"{setting}_{freq:g}_{walk}.h5", steps=steps, seed=seed,
                      moves=moves, fresh=True, coordinates=coordinates, adaptation=None)
    minutes = (time.perf_counter() - t0) / 60
    half = run.chain(discard=steps // 4)
    tau = emcee.autocorr.integrated_time(half, tol=0)
    rhat, ess = rhat_ess(half)
    ib, ik = pm.names.index("b"), pm.names.index("k_n")
    b = np.percentile(np.exp(half[..., ib]), [3, 50, 97])
    lk = np.percentile(half[..., ik] / np.log(10), [3, 50, 97])
    truth = rec.metadata["true_parameters"]["b"]
    return {
        "record": f"{setting}_{freq:g}Hz", "walk": walk, "steps": steps,
        "minutes": round(minutes, 2), "acceptance": round(float(np.mean(run.sampler.acceptance_fraction)), 3),
        "max_tau": round(float(np.max(tau)), 1), "tau_b": round(float(tau[ib]), 1),
        "rhat_b": round(float(rhat[ib]), 3), "max_rhat": round(float(np.max(rhat)), 3),
        "ess_b": round(float(ess[ib]), 1),
        "b_3%": round(float(b[0]), 1), "b_50%": round(float(b[1]), 1), "b_97%": round(float(b[2]), 1),
        "b_truth": round(float(truth), 1), "covers": bool(b[0] <= truth <= b[2]),
        "log10_k_n_3%": round(float(lk[0]), 2), "log10_k_n_50%": round(float(lk[1]), 2),
        "log10_k_n_97%": round(float(lk[2]), 2),
        "log10_k_n_truth": round(float(np.log10(rec.metadata["true_parameters"]["k_n"])), 2),
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--record", action="append", default=None, help="SETTING:FREQUENCY (default A3:1)")
    ap.add_argument("--steps", type=int, default=3000)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--processes", type=int, default=2)
    ap.add_argument("--out", default=str(ROOT / "runs" / "long-chain" / "walks.csv"))
    args = ap.parse_args()
    jobs = []
    with tempfile.TemporaryDirectory() as folder:
        for item in args.record or ["A3:1"]:
            setting, freq = record_arg(item)
            jobs += [(setting, freq, walk, args.steps, args.seed, folder) for walk in WALKS]
        rows = map_rows(_chain, jobs, args.processes)
    write_rows(args.out, rows)


if __name__ == "__main__":
    main()
