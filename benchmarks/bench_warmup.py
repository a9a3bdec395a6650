"""Benchmark: where the convergence rule stops a chain, with and without a warm-up share.

Run by hand: ``python benchmarks/bench_warmup.py [--record A3:1 ...] [--steps 4000]
[--seed 0] [--shares 0 0.3333] [--joint A0 A3 B2] [--out results/performance/warmup.csv]``.

Each record (the full study's: the paper grid generated with seed 0, named
SETTING:FREQUENCY) is sampled once for ``--steps`` steps with the package's default
sampler, from its restarted Nelder-Mead optimum (records two at a time, one process
each). ``--joint SETTINGS`` also samples the joint model of those settings' records at
0.5, 1 and 1.5 Hz from the start ``studies/joint_mixing.py`` saved
(``results/joint-mixing/blocks/start.npy``, the optimum reached from the full study's
fits), on two processes. On each stored chain the convergence checks of
``run_sampler`` are replayed (every ``check_every`` steps, the package's own
``_check_chain`` and ``_is_converged``) under ``Convergence(warmup=share)`` for every
share: the same chain, so the rules differ only in where they stop it. For each stop the
row gives the warm-up, the largest tau, and b's mean and 94 % interval from the draws the
fit would keep (after the warm-up and 2 tau more), beside b from the last half of the
whole chain, the reference: ``b_shift_sd`` is their difference in its sd.
"""

import argparse
import sys
import tempfile
import time
from multiprocessing import get_context
from pathlib import Path

import numpy as np

from bayes_inerter.device import setting_and_frequency
from bayes_inerter.study.analysis import write_csv

ROOT = Path(__file__).resolve().parents[1]

START = ROOT / "results" / "joint-mixing" / "blocks" / "start.npy"


def replay(chain, log_prob, conv):
    """(step, check) where ``run_sampler``'s open-ended loop would stop ``chain``
    (steps, walkers, ndim; theta) under ``conv``: its checks at every multiple of
    ``conv.check_every``, each against the one before; (None, last check) if none holds."""
    from bayes_inerter.inference.sampling.convergence import check_chain, is_converged, tau_settled

    previous, check = None, None
    for step in range(conv.check_every, len(chain) + 1, conv.check_every):
        check = check_chain(chain[:step], log_prob[:step], conv,
                             rhat_if=lambda n, t: tau_settled(n, t, previous, conv))
        if is_converged(step - check.warmup, check.tau, previous, check.rhat, check.ess, conv):
            return step, check
        previous = check.tau
    return None, check


def _b_stats(values):
    lo, hi = np.percentile(values, [3, 97])
    return float(np.mean(values)), float(np.std(values)), float(lo), float(hi)


def rows_for(name, chain, log_prob, names, shares, seconds):
    """One row per warm-up share: where the rule stops ``chain`` and b there (b of the
    first setting for a joint chain)."""
    from bayes_inerter.inference import Convergence

    i = next(k for k, n in enumerate(names) if n == "b" or n.startswith("b_"))
    ref_mean, ref_sd, _, _ = _b_stats(np.exp(chain[len(chain) // 2:, :, i]))
    rows = []
    for share in shares:
        step, check = replay(chain, log_prob, Convergence(warmup=share))
        row = {"chain": name, "parameter": names[i], "steps_run": len(chain), "seconds_run": round(seconds, 1),
               "warmup_share": round(share, 4), "stop": step if step is not None else "",
               "warmup": check.warmup, "tau_max": round(float(np.max(check.tau)), 1),
               "slowest": names[int(np.argmax(check.tau))]}
        if step is not None:
            burn = check.warmup + int(2 * np.max(check.tau))
            mean, sd, lo, hi = _b_stats(np.exp(chain[burn:step, :, i]))
            row.update({"b_mean": round(mean, 2), "b_hdi_3%": round(lo, 2), "b_hdi_97%": round(hi, 2),
                        "b_ref_mean": round(ref_mean, 2), "b_ref_sd": round(ref_sd, 2),
                        "b_shift_sd": round((mean - ref_mean) / ref_sd, 3)})
        else:
            row.update({k: "" for k in ("b_mean", "b_hdi_3%", "b_hdi_97%")})
            row.update({"b_ref_mean": round(ref_mean, 2), "b_ref_sd": round(ref_sd, 2), "b_shift_sd": ""})
        rows.append(row)
    return rows


def _record_chain(job):
    from bayes_inerter.inference.posterior.model import PosteriorModel
    from bayes_inerter.inference.sampling.optimize import find_start
    from bayes_inerter.inference.sampling.sampler import run_sampler
    from bayes_inerter.records.generator import paper_record

    item, steps, seed, folder = job
    setting, freq = setting_and_frequency(item)
    pm = PosteriorModel(paper_record(setting, freq, seed=0))  # checked in main() before any sampling
    start = find_start(pm, np.random.default_rng(seed))
    t0 = time.perf_counter()
    run = run_sampler(pm, Path(folder) / f"{setting}_{freq:g}.h5", steps=steps, seed=seed, start=start, fresh=True)
    return f"{setting} {freq:g} Hz", run.chain(), run.log_prob(), list(pm.names), time.perf_counter() - t0


def _joint_chain(settings, steps, seed, folder):
    from bayes_inerter.inference.posterior.joint import JointModel
    from bayes_inerter.inference.sampling.sampler import run_sampler
    from bayes_inerter.records import paper_grid

    if not START.exists():
        sys.exit(f"error: {START} is missing: run studies/joint_mixing.py --variants blocks --centres results/full")
    records = [rec for _, _, rec in paper_grid(seed=0, names=tuple(settings))]
    records.sort(key=lambda r: (r.metadata["setting"], r.drive_frequency))
    jm = JointModel(tuple(records))
    theta = np.load(START)
    if len(theta) != jm.ndim:
        sys.exit(f"error: {START} is the start of another joint model ({len(theta)} parameters, not {jm.ndim})")
    t0 = time.perf_counter()
    run = run_sampler(jm, Path(folder) / "joint.h5", steps=steps, seed=seed, processes=2, fresh=True,
                      start=(theta, jm.log_prob(theta)[0]))
    name = f"joint {'+'.join(settings)} ({len(records)} records)"
    return name, run.chain(), run.log_prob(), list(jm.names), time.perf_counter() - t0


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--record", action="append", default=None,
                    help="SETTING:FREQUENCY (default A0:1, A3:1, A6:0.5 and B2:1.5)")
    ap.add_argument("--steps", type=int, default=4000)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--shares", type=float, nargs="+", default=[0.0, 1 / 3])
    ap.add_argument("--joint", nargs="+", default=None, metavar="SETTING",
                    help="also the joint model of these settings' records (the start file's: A0 A3 B2)")
    ap.add_argument("--out", default=str(ROOT / "results" / "performance" / "warmup.csv"))
    args = ap.parse_args()
    if args.steps < 500:
        sys.exit("error: --steps must be at least 500")
    if any(not 0 <= s <= 0.5 for s in args.shares):
        sys.exit("error: --shares must lie in [0, 0.5]")
    items = args.record or ["A0:1", "A3:1", "A6:0.5", "B2:1.5"]
    from bayes_inerter.records.generator import paper_record

    for item in items:  # a bad name ends here, before any sampling
        try:
            paper_record(*setting_and_frequency(item), seed=0)
        except ValueError as exc:
            sys.exit(f"error: --record {item!r} is not a record of the paper grid ({exc})")
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        with get_context("fork").Pool(2) as pool:
            chains = pool.map(_record_chain, [(item, args.steps, args.seed, folder) for item in items])
        if args.joint:
            chains.append(_joint_chain(args.joint, args.steps, args.seed, folder))
        for name, chain, log_prob, names, seconds in chains:
            rows += rows_for(name, chain, log_prob, [str(n) for n in names], args.shares, seconds)
    write_csv(Path(args.out), rows)
    print(f"wrote {args.out}")
    base = args.shares[0]
    for name in dict.fromkeys(r["chain"] for r in rows):
        mine = {r["warmup_share"]: r["stop"] for r in rows if r["chain"] == name}
        ref = mine[round(base, 4)]
        for share, stop in mine.items():
            if share != round(base, 4) and ref and stop:
                print(f"{name}: warm-up {share:g} stops at {stop} steps, warm-up {base:g} at {ref}: "
                      f"{ref / stop:.2f} x fewer steps")


if __name__ == "__main__":
    main()
