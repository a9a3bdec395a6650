"""Benchmark: where the convergence rule stops a chain under its two judgements of tau's
growth, for the default sampler and parallel tempering.

Run by hand from the project root: ``python benchmarks/bench_tau_growth.py [--record
B1:22:1 ...] [--steps 4000] [--tempered-steps 2000] [--temps 4] [--samplers default
tempered] [--rtol 0.05 ...] [--out results/performance/tau_growth.csv]``.

Why: tempered chains of paper-like records reach 50 times their largest tau within a
few hundred steps (tau 5 to 13), yet ran to 1,250 to 3,750 steps
(results/performance/misfit_tempering.csv): the rule's other part, that no
parameter's tau grew by more than ``tau_rtol`` since the last check, held them, the
growth being that of parameters whose tau is a fraction of the largest.

Each record (``SETTING:LABORATORY:FREQ``, a 10 s paper-like record,
``records.paper_like.paper_like_record``) is sampled for ``--steps`` steps with the
default sampler and for ``--tempered-steps`` cold steps with ``--temps`` temperatures
(``run_sampler``, one process, seeded by the laboratory, from the start search); the
chains are kept in ``--work`` and reused. On each chain the checks of ``run_sampler``'s
open-ended loop are replayed (every ``check_every`` steps, ``bench_warmup.replay``)
under ``Convergence(growth="each")`` (the default) and ``growth="largest"``, each with
every ``--rtol`` as ``tau_rtol`` (default 0.05, the package's; ``inf`` drops the growth
test, keeping the length the last check's tau asks for): the same chain, so the rules
differ only in where they stop it (a prefix of a chain is the chain a shorter run makes:
the moves adapt from the past alone). Per stop: the step, the
evaluations of the log posterior to it (steps x walkers x temperatures; the start
search left out), the largest tau, and b's median and 3 to 97 % quantiles over the draws
the fit would keep (after the warm-up and 2 tau more), beside b's over the last half of
the whole chain (the reference). Rows go to ``--out`` with commit, machine and date.
"""

import argparse
import time
from pathlib import Path

import numpy as np
from _timing import record_row
from bench_warmup import replay

from bayes_inerter.inference import Convergence, PosteriorModel, Tempering, run_sampler
from bayes_inerter.inference.sampling.convergence import GROWTH
from bayes_inerter.records import GeneratorSettings
from bayes_inerter.records.paper_like import PaperLike, paper_like_record

ROOT = Path(__file__).resolve().parents[1]


def quantiles(values) -> tuple:
    return tuple(float(v) for v in np.percentile(values, [3, 50, 97]))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--record", nargs="+", default=["B1:22:1", "A3:21:1.5"], help="SETTING:LABORATORY:FREQ")
    ap.add_argument("--steps", type=int, default=4000, help="steps of the default chain")
    ap.add_argument("--tempered-steps", type=int, default=2000, help="cold steps of the tempered chain")
    ap.add_argument("--temps", type=int, default=4)
    ap.add_argument("--samplers", nargs="+", choices=("default", "tempered"), default=["default", "tempered"])
    ap.add_argument("--rtol", type=float, nargs="+", default=[Convergence().tau_rtol],
                    help="tau_rtol values to replay (inf: no growth test)")
    ap.add_argument("--work", default=str(ROOT / "runs" / "tau-growth"))
    ap.add_argument("--out", default="tau_growth", help="results/performance/<OUT>.csv")
    ap.add_argument("--no-row", action="store_true")
    args = ap.parse_args()
    if any(not r > 0 for r in args.rtol):
        raise SystemExit("error: --rtol values must be positive (inf: no growth test)")

    device = PaperLike(base=GeneratorSettings(duration=10.0))
    print(f"{'record':>12} {'sampler':>9} {'growth':>8} {'rtol':>5} {'stop':>6} {'evaluations':>11} {'max tau':>8} "
          f"{'b 3-50-97 % at the stop':>26} {'b 3-50-97 % last half':>26}")
    for spec in args.record:
        setting, lab, freq = spec.split(":")
        rec = paper_like_record(setting, float(freq), seed=int(lab), device=device)
        model = PosteriorModel(rec)
        ib = model.names.index("b")
        for sampler, tempering, steps in (("default", None, args.steps),
                                          ("tempered", Tempering(args.temps), args.tempered_steps)):
            if sampler not in args.samplers:
                continue
            path = Path(args.work) / f"{spec.replace(':', '_')}_{sampler}" / "chain.h5"
            path.parent.mkdir(parents=True, exist_ok=True)
            t0 = time.perf_counter()
            run = run_sampler(model, path, steps=steps, seed=int(lab), tempering=tempering)
            seconds = time.perf_counter() - t0
            chain, log_prob = run.chain(), run.sampler.get_log_prob()
            b = np.exp(chain[..., ib]) if model.all_priors["b"].log_scale else chain[..., ib]  # theta holds log b
            temps = 1 if tempering is None else tempering.temps
            ref = quantiles(b[len(chain) // 2:])
            for growth, rtol in ((g, r) for g in GROWTH for r in args.rtol):
                step, check = replay(chain, log_prob, Convergence(growth=growth, tau_rtol=rtol))
                got = (np.nan,) * 3
                if step is not None:
                    burn = check.warmup + int(2 * np.max(check.tau))
                    got = quantiles(b[burn:step])
                evaluations = None if step is None else step * run.sampler.nwalkers * temps
                print(f"{spec:>12} {sampler:>9} {growth:>8} {rtol:>5g} {step or '-':>6} {evaluations or '-':>11} "
                      f"{np.max(check.tau):>8.1f} {got[0]:>8.1f}-{got[1]:.1f}-{got[2]:<8.1f} "
                      f"{ref[0]:>8.1f}-{ref[1]:.1f}-{ref[2]:<8.1f}", flush=True)
                if not args.no_row:
                    record_row(args.out, {
                        "record": spec, "sampler": sampler, "temps": temps, "growth": growth,
                        "tau_rtol": rtol, "steps_run": len(chain), "seconds_run": round(seconds, 1), "stop": step or "",
                        "evaluations": evaluations or "", "max_tau": round(float(np.max(check.tau)), 1),
                        "b_3%": round(got[0], 1), "b_50%": round(got[1], 1), "b_97%": round(got[2], 1),
                        "ref_b_3%": round(ref[0], 1), "ref_b_50%": round(ref[1], 1),
                        "ref_b_97%": round(ref[2], 1),
                        "b_truth": round(float(rec.metadata["true_parameters"]["b"]), 1)})
    if not args.no_row:
        print(f"wrote rows to results/performance/{args.out}.csv")


if __name__ == "__main__":
    main()
