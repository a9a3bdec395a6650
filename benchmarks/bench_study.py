"""Benchmark: the full study's wall time on this machine, its split, and what converging
every chain would take.

Run by hand after a study: ``python benchmarks/bench_study.py [results/full]``.

1. Measured, from the study's own records (``study.json`` and every ``fit.json``):
   wall time of the fits, the joint model and the analysis; per fit, the time in
   sampling (the start-up optimiser and Laplace start included), in posterior draws (predictive simulations, LOO) and in writing plots
   and files.
2. Measured here, side by side on one of the study's records: one log-probability
   evaluation against one simulation (medians of 30): the simulator's share of the
   sampler's time.
3. Projected: each chain needs 50 times its largest autocorrelation time after its
   warm-up (a third of the chain, or its transient) to meet the convergence criteria;
   the sampling time scaled to that length, summed, over the study's worker processes,
   against the 30-minute target. A projection from tau
   estimated on unconverged chains (which underestimates it), not a measurement.

The machine is shared and noisy: read the ratios.
"""

import json
import sys
from pathlib import Path

import numpy as np

from _timing import median_time

from bayes_inerter import simulate
from bayes_inerter.inference import Convergence
from bayes_inerter.inference.posterior.model import PosteriorModel
from bayes_inerter.records import read_record

TARGET_S = 30 * 60.0


def main():
    out = Path(sys.argv[1] if len(sys.argv) > 1 else "results/full")
    study = json.loads((out / "study.json").read_text())
    fits = [json.loads(p.read_text()) | {"_dir": p.parent} for p in sorted(out.glob("fits/*/*/fit.json"))]
    if not fits:
        sys.exit(f"{out}: no fits")
    # the last run into the folder that sampled fits (a later one that only reused them
    # took seconds); study.json files older than the list have one run, "seconds"
    sampled = [r for r in study.get("runs", []) if r.get("sampled")]
    run = sampled[-1] if sampled else {"seconds": study["seconds"], "processes": study.get("processes"),
                                       "finished": None}
    sec = run["seconds"]
    procs = run.get("processes") or 1
    print(f"study {out}: {len(fits)} fits on {procs} processes")
    print(f"1. measured wall time (s) of the run that sampled{' (finished ' + run['finished'] + ')' if run.get('finished') else ''}: "
          + ", ".join(f"{k} {v:.0f}" for k, v in sec.items()))
    def sampling(f):  # over every run that built the chain (a resumed chain's runs add up)
        return f["timings_s"].get("sampling_all_runs", f["timings_s"]["sampling"])

    def timed_steps(f):  # the steps that time covers (a run killed before fit.json is not timed)
        return int(f["timings_s"].get("steps_timed", f["iterations"]))

    samp = sum(sampling(f) for f in fits)
    post = sum(f["timings_s"].get("posterior_draws", 0.0) for f in fits)
    total = sum(sampling(f) + f["timings_s"]["total"] - f["timings_s"]["sampling"] for f in fits)
    print(f"   summed over fits (CPU-process s): sampling {samp:.0f} ({100 * samp / total:.0f} %), posterior draws "
          f"{post:.0f} ({100 * post / total:.0f} %), plots and files {total - samp - post:.0f} "
          f"({100 * (total - samp - post) / total:.0f} %)")

    rec_path = next(iter(sorted((out / "records").glob("*.csv"))), None)
    if rec_path is not None:
        rec = read_record(rec_path)
        model = PosteriorModel(rec)
        f2p = next(f for f in fits if f["model"] == "two-port")
        summ = {r.split(",")[0]: float(r.split(",")[1]) for r in
                (f2p["_dir"] / "summary.csv").read_text().splitlines()[1:]}
        theta = np.array([np.log(summ[n]) if lg else summ[n] for n, lg in zip(model.names, [model.all_priors[n].log_scale for n in model.names])])
        params = model.parameters(theta)
        t_lp = median_time(lambda: model.log_prob(theta))
        t_sim = median_time(lambda: simulate(params, rec.time, rec.force, sampling="mean"))
        print(f"2. {rec_path.name}: log_prob {1e3 * t_lp:.2f} ms, simulate {1e3 * t_sim:.2f} ms "
              f"(simulator share {t_sim / t_lp:.2f})")

    conv_rule = Convergence()

    def rule_steps(f, tau):
        """Steps the convergence rule needs at this tau: ``n_tau`` tau after the warm-up,
        which is the transient or the rule's share of the chain, whichever is longer."""
        return max(conv_rule.n_tau * tau / (1.0 - conv_rule.warmup), f.get("transient", 0) + conv_rule.n_tau * tau)

    need = []
    for f in fits:
        tau = [t for t in f["tau"].values() if np.isfinite(t)]
        it = int(f["iterations"])
        steps = max(rule_steps(f, max(tau)), it) if tau else float("nan")
        need.append(sampling(f) * steps / timed_steps(f) if timed_steps(f) else float("nan"))
    proj = np.nansum(need) / procs + sec.get("analysis_and_report", 0.0)
    conv = sum(bool(f["converged"]) for f in fits)
    print(f"3. converged chains: {conv} of {len(fits)}. Projected wall time with every chain as long as the rule "
          f"needs ({conv_rule.n_tau:g} tau after a warm-up of {100 * conv_rule.warmup:.0f} %; single-record fits "
          f"only): {proj / 60:.0f} min, {proj / TARGET_S:.1f} x the 30-minute target")
    if (out / "joint" / "fit.json").exists():
        j = json.loads((out / "joint" / "fit.json").read_text())
        tau = max(t for t in j["tau"].values() if np.isfinite(t))
        t, n = sampling(j), timed_steps(j)
        if n == 0:
            print(f"   joint model: {j['iterations']} steps, largest tau {tau:.0f}; none of its steps were timed "
                  "(its runs were stopped before writing fit.json)")
        else:
            print(f"   joint model: {j['iterations']} steps, {n} of them timed in {t:.0f} s, largest tau {tau:.0f}: "
                  f"the rule's {rule_steps(j, tau):.0f} steps would take {t * rule_steps(j, tau) / n / 60:.0f} min")


if __name__ == "__main__":
    main()
