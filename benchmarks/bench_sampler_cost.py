"""Benchmark: what a fit costs beyond its log-probability evaluations (issue 40, item 2).

One fit of a paper-like record (``records.paper_like``, laboratory ``--seed``) for a fixed
``--steps`` on one process, ``fit_record`` as ``bayes-inerter fit`` runs it, timed in
phases from its own callbacks:

- **start search**: from the call to the sampler's first report (the start search and the
  likelihood's reference point);
- **first step**: from there to the first step (the initial ensemble and one step);
- of the start, as the fit reports it (``SamplerRun.start_seconds``, fit.json's
  ``timings_s``): the search, the modes the walkers are shared among (the friction
  split's mirror and the held ladder) and the initial ensemble, each on its own line;
- **sampling**: the remaining steps, wall time, and in it
  - the evaluations: every ``PosteriorModel.log_prob`` call, counted and timed in the run;
  - the adaptation: ``Adaptation.fit``, the fitted moves' refits;
  - the rest: emcee, the moves' proposals, the checkpoint, the callbacks and the
    convergence checks, these also on their own line (``Monitor.check``: tau every 250
    steps, and R-hat and ESS where tau says they could decide; the CSV's ``checks_s``);
- **outputs**: the posterior draws and files after sampling (no figures).

Then the same evaluations at the log-probability's own speed: every 50th point the
sampler evaluated, timed again alone (median of 5 passes), times the count. The ratio
sampling / that is what the sampler costs per evaluation (target: at most 1.25); on a
loaded machine the speed alone can differ from the run's, so the ratio to the
evaluations as timed in the run is printed beside. One row per run goes to
results/performance/sampler_cost.csv.

    python benchmarks/bench_sampler_cost.py [--setting A3] [--freq 1.0] [--steps 1000] [--seed 0]

``--steps 0`` runs the fit until the convergence rule holds (at most its cap), so the
start search's and the adaptation's shares are those of a converged fit (issue 40, item
2: under 15 % of it); the row's ``steps`` is then the steps taken and ``converged`` says
whether the rule held.

The machine is shared and noisy: the ratios within a run are what to read.
"""

import argparse
import math
import tempfile
import time
from pathlib import Path

import numpy as np

from _timing import record_row

from bayes_inerter.inference import Adaptation, PosteriorModel, fit_record
from bayes_inerter.inference.sampling.convergence import Monitor
from bayes_inerter.inference.sampling.sampler import START_PHASES
from bayes_inerter.records.paper_like import PaperLike, paper_like_record

TARGET_RATIO = 1.25
KEEP_EVERY = 50


class _Clock:
    """Wraps PosteriorModel.log_prob, Adaptation.fit and Monitor.check for one run: counts
    and times them while ``on`` is set, and keeps every KEEP_EVERY-th point evaluated."""

    def __init__(self):
        self.on = False
        self.calls = 0
        self.eval_s = 0.0
        self.adapt_s = 0.0
        self.check_s = 0.0
        self.kept = []
        self.model = None
        self._log_prob = PosteriorModel.log_prob
        self._fit = Adaptation.fit
        self._check = Monitor.check

    def __enter__(self):
        clock = self

        def log_prob(model, theta):
            if not clock.on:
                return clock._log_prob(model, theta)
            t0 = time.perf_counter()
            got = clock._log_prob(model, theta)
            clock.eval_s += time.perf_counter() - t0
            if clock.calls % KEEP_EVERY == 0:
                clock.kept.append(np.array(theta, dtype=float))
                clock.model = model
            clock.calls += 1
            return got

        PosteriorModel.log_prob = log_prob
        Adaptation.fit = self._timed(self._fit, "adapt_s")
        Monitor.check = self._timed(self._check, "check_s")
        return self

    def _timed(self, method, seconds: str):
        """``method`` wrapped to add its seconds to the attribute ``seconds`` while ``on``."""
        clock = self

        def timed(obj, *args):
            t0 = time.perf_counter()
            got = method(obj, *args)
            if clock.on:
                setattr(clock, seconds, getattr(clock, seconds) + time.perf_counter() - t0)
            return got

        return timed

    def __exit__(self, *exc):
        PosteriorModel.log_prob = self._log_prob
        Adaptation.fit = self._fit
        Monitor.check = self._check


def _alone(model, thetas, passes: int = 5) -> float:
    """Median seconds per log_prob over ``thetas``, timed alone."""
    per = []
    for _ in range(passes):
        t0 = time.perf_counter()
        for theta in thetas:
            model.log_prob(theta)
        per.append((time.perf_counter() - t0) / len(thetas))
    return float(np.median(per))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--setting", default="A3")
    ap.add_argument("--freq", type=float, default=1.0)
    ap.add_argument("--steps", type=int, default=1000, help="steps of the fit (0: until converged)")
    ap.add_argument("--seed", type=int, default=0, help="the paper-like laboratory's seed and the fit's")
    args = ap.parse_args()
    record = paper_like_record(args.setting, args.freq, seed=args.seed, device=PaperLike())
    marks = {}

    def report(status):
        marks.setdefault("reported", time.perf_counter())

    def progress(iteration, target):
        now = time.perf_counter()
        if "first" not in marks:
            marks["first"] = now
            clock.on = True
        marks["last"] = now

    with tempfile.TemporaryDirectory() as tmp, _Clock() as clock:
        t0 = time.perf_counter()
        res = fit_record(record, Path(tmp) / "fit", steps=args.steps or None, seed=args.seed, processes=1,
                         plots=False, report=report, progress=progress)
        t_end = time.perf_counter()
        clock.on = False
        alone = _alone(clock.model, clock.kept)
    start_s = marks["reported"] - t0
    first_s = marks["first"] - marks["reported"]
    sampling_s = marks["last"] - marks["first"]
    outputs_s = t_end - marks["last"]
    at_own_speed = clock.calls * alone
    ratio = sampling_s / at_own_speed
    rest_s = sampling_s - clock.eval_s - clock.adapt_s
    total = t_end - t0
    steps = int(res.iterations)
    print(f"{args.setting} {args.freq:g} Hz paper-like (seed {args.seed}), {steps} steps"
          + ("" if args.steps else f" ({'converged' if res.converged else 'not converged'})") + ", "
          f"{res.idata.posterior.sizes['chain']} walkers, one process")
    print(f"  start search      {start_s:8.1f} s  ({start_s / total:.1%} of the run)")
    print(f"  first step        {first_s:8.1f} s")
    start = {phase: res.timings.get(f"start_{phase}", math.nan) for phase in START_PHASES}
    print(f"    of the start: search {start['search']:.1f} s, modes (mirror and held ladder) "
          f"{start['modes']:.1f} s, initial ensemble {start['ensemble']:.1f} s "
          f"({sum(start.values()) / total:.1%} of the run together)")
    print(f"  sampling          {sampling_s:8.1f} s  ({clock.calls} evaluations)")
    print(f"    evaluations     {clock.eval_s:8.1f} s  (in the run: {1e3 * clock.eval_s / clock.calls:.3f} ms each)")
    print(f"    adaptation      {clock.adapt_s:8.1f} s  ({clock.adapt_s / total:.1%} of the run)")
    print(f"    the rest        {rest_s:8.1f} s  (emcee, moves, checkpoint, callbacks, checks)")
    print(f"      of which checks {clock.check_s:6.1f} s  ({clock.check_s / total:.1%} of the run)")
    print(f"  outputs           {outputs_s:8.1f} s")
    print(f"  alone: {1e3 * alone:.3f} ms per evaluation ({len(clock.kept)} of the run's points, median of 5 "
          f"passes); the evaluations at that speed {at_own_speed:.1f} s")
    print(f"  sampling / evaluations at their own speed: {ratio:.2f} (target at most {TARGET_RATIO}); "
          f"/ the evaluations as timed in the run: {sampling_s / clock.eval_s:.2f}")
    path = record_row("sampler_cost", {
        "record": f"{args.setting}_{args.freq:g}Hz", "truth": "paper-like", "seed": args.seed, "steps": steps,
        "walkers": int(res.idata.posterior.sizes["chain"]), "evaluations": clock.calls,
        "start_search_s": round(start_s, 2), "first_step_s": round(first_s, 2), "sampling_s": round(sampling_s, 2),
        "evaluations_s": round(clock.eval_s, 2), "adaptation_s": round(clock.adapt_s, 2), "rest_s": round(rest_s, 2),
        "outputs_s": round(outputs_s, 2), "ms_per_eval_alone": round(1e3 * alone, 4),
        "ratio": round(ratio, 3), "ratio_in_run": round(sampling_s / clock.eval_s, 3),
        "start_share": round(start_s / total, 3), "met": ratio <= TARGET_RATIO,
        "converged": bool(res.converged) if not args.steps else "", "checks_s": round(clock.check_s, 2),
        **{f"phase_{phase}_s": round(v, 2) for phase, v in start.items()}})
    print(f"wrote a row to {path}")


if __name__ == "__main__":
    main()
