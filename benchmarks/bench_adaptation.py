"""Benchmark: what the fitted independence move (``sampler.Adaptation``) buys, side by side.

Run by hand: ``python benchmarks/bench_adaptation.py [--record A3:1 ...] [--seed 0]
[--max-steps 20000] [--variants adaptive ensemble-only] [--out results/performance/adaptation.csv]``.

Each record (the full study's: the paper grid generated with seed 0, named
SETTING:FREQUENCY; default A3 at 1 Hz and B2 at 1 Hz; with ``--paper-like LAB`` the
paper-like device's records of laboratory LAB, ``records.paper_like``) is sampled until the package's
convergence criteria hold (``Convergence()``: 50 tau after the transient, tau settled,
R-hat < 1.05, bulk ESS >= 400), twice from the same start (one restarted Nelder-Mead
optimum per record) with the same seed, walkers and coordinates: with the one-t
adaptation (``adaptive``, an earlier default) and without it (the ensemble
moves alone), or with the variants named (``scores``: its t fitted in the chain's
normal scores, 200 knots; ``blocks``: the same with half the fitted share to block
moves of random coordinates, ``moves.BlockMove``, the default since;
``correlated``: those block moves made of a coordinate and its most correlated partners,
``Adaptation(block_partners="correlated")``, an option).
The two runs of a record run at the same time, one process each, so they
share the machine alike: read the ratios.
Writes one row per run (steps and seconds to converge, the largest autocorrelation
time, acceptance, b's 94 % interval), with the commit, machine and date, appended to
``--out`` where that lies in results/performance/, and prints the ratios.
"""

import argparse
import sys
import tempfile
import time
from multiprocessing import get_context
from pathlib import Path

import numpy as np

from _timing import PERFORMANCE, provenance, record_row

from bayes_inerter.device import setting_and_frequency
from bayes_inerter.inference.sampling.adaptation import NAMED
from bayes_inerter.study.analysis import write_csv

ROOT = Path(__file__).resolve().parents[1]

VARIANTS = ("adaptive", "ensemble-only", "scores", "blocks", "correlated")


def _record(setting, freq, lab):
    """The full study's record (``lab`` None) or the paper-like laboratory ``lab``'s."""
    if lab is None:
        from bayes_inerter.records.generator import paper_record

        return paper_record(setting, freq, seed=0)
    from bayes_inerter.records.paper_like import PaperLike, paper_like_record

    return paper_like_record(setting, freq, seed=lab, device=PaperLike())


def _run(job):
    setting, freq, variant, seed, max_steps, start, folder, lab = job
    from bayes_inerter.inference import Convergence
    from bayes_inerter.inference.posterior.model import PosteriorModel
    from bayes_inerter.inference.sampling.sampler import Adaptation, run_sampler

    rec = _record(setting, freq, lab)
    pm = PosteriorModel(rec)
    t0 = time.perf_counter()
    run = run_sampler(pm, Path(folder) / f"{setting}_{freq:g}_{variant}.h5", seed=seed, start=start, fresh=True,
                      convergence=Convergence(max_steps=max_steps),
                      adaptation=Adaptation(**NAMED[variant]) if variant in NAMED else None)
    seconds = time.perf_counter() - t0
    burn = run.warmup + int(2 * np.max(run.tau))
    b = np.percentile(np.exp(run.chain(discard=burn)[..., pm.names.index("b")]), [3, 50, 97])
    truth = rec.metadata["true_parameters"]["b"]
    return {
        "record": f"{setting}_{freq:g}Hz", "truth": "model" if lab is None else f"paper-like {lab}",
        "seed": seed, "variant": variant, "converged": run.converged,
        "steps": int(run.iteration), "walkers": run.sampler.nwalkers,
        "evaluations": int(run.iteration * run.sampler.nwalkers), "seconds": round(seconds, 1),
        "transient": run.transient, "warmup": run.warmup, "max_tau": round(float(np.max(run.tau)), 1),
        "slowest": pm.names[int(np.argmax(run.tau))],
        "acceptance": round(float(np.mean(run.sampler.acceptance_fraction)), 3),
        "b_3%": round(float(b[0]), 1), "b_50%": round(float(b[1]), 1), "b_97%": round(float(b[2]), 1),
        "b_truth": round(float(truth), 1), "covers": bool(b[0] <= truth <= b[2]),
    }


def _start(item, seed, lab):
    from bayes_inerter.inference.posterior.model import PosteriorModel
    from bayes_inerter.inference.sampling.optimize import find_start

    try:
        setting, freq = setting_and_frequency(item)
        rec = _record(setting, freq, lab)
    except ValueError as exc:
        sys.exit(f"error: --record {item!r} is not a record of the paper grid ({exc})")
    return setting, freq, find_start(PosteriorModel(rec), np.random.default_rng(seed))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--record", action="append", default=None, help="SETTING:FREQUENCY (default A3:1 and B2:1)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--max-steps", type=int, default=20_000)
    ap.add_argument("--paper-like", type=int, default=None, metavar="LAB",
                    help="the paper-like device's records of laboratory LAB (default: the full study's)")
    ap.add_argument("--variants", nargs=2, default=["adaptive", "ensemble-only"], choices=VARIANTS,
                    help="the two samplers compared (default adaptive ensemble-only)")
    ap.add_argument("--out", default=str(ROOT / "results" / "performance" / "adaptation.csv"))
    args = ap.parse_args()
    starts = [_start(item, args.seed, args.paper_like) for item in (args.record or ["A3:1", "B2:1"])]
    rows = []
    with tempfile.TemporaryDirectory() as folder, get_context("fork").Pool(2) as pool:
        for setting, freq, start in starts:
            jobs = [(setting, freq, v, args.seed, args.max_steps, start, folder, args.paper_like)
                    for v in args.variants]
            rows += pool.map(_run, jobs)
    out = Path(args.out)
    if out.resolve().parent == PERFORMANCE.resolve():  # appended, with the commit, machine and date
        for row in rows:
            record_row(out.stem, row)
    else:
        write_csv(out, [{**provenance(), **row} for row in rows])
    print(f"wrote {out}")
    for i in range(0, len(rows), 2):
        a, e = rows[i], rows[i + 1]
        print(f"{a['record']}: {e['variant']} / {a['variant']} = {e['steps'] / a['steps']:.2f} x the steps, "
              f"{e['seconds'] / a['seconds']:.2f} x the seconds"
              + ("" if a["converged"] and e["converged"] else " (not both converged: a lower bound at most)"))


if __name__ == "__main__":
    main()
