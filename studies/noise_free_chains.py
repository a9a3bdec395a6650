"""Does the default fit's posterior hold b on the generator's noise-free records?

Issue 39, item 1's interval half, measured with chains: record k of the paper's grid
(``SETTINGS[k % 9]`` at ``FREQUENCIES[(k + k // 9) % 3]``; records 0 to 26 cover every
setting at every frequency once) is made by the project's own generator from Table I and
Table 2 with every noise off (``GeneratorSettings(force_noise=0, accel_noise=0,
disp_noise=0)``; the sensors' band limits kept), and fitted by ``fit_record`` as
``bayes-inerter fit`` runs it (the default likelihood, each chain to the convergence
rule, at most ``--max-steps``). ``--zeta-B Z`` gives the generator's plate mode the
damping ratio Z in place of Table I's c_B (a ratio of 8e-6, outside the fit's damping
prior of 0.5 to 10 %: ``priors.MODAL_PRIORS``).

One JSON per record in ``--out``/records (a run that stops continues where it stopped:
run the command again); ``--out``/chains.csv from all of them: b's posterior median and
its error, the 94 % highest-density interval and whether it holds the true b, the
chain's state and seconds, the commit the process loaded.

    python studies/noise_free_chains.py [--records 27] [--out results/noise-free-chains]
        [--zeta-B 0.02] [--max-steps 20000] [--processes 1] [--summarise]
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from _table import git_commit, grid_case, write_rows
from bayes_inerter import paper_parameters
from bayes_inerter.executor import make_executor
from bayes_inerter.inference import fit_record
from bayes_inerter.inference.sampling.convergence import Convergence
from bayes_inerter.inference.summaries.results import hdi
from bayes_inerter.records import GeneratorSettings, generate_record

ROOT = Path(__file__).resolve().parents[1]
NOISE_FREE = GeneratorSettings(force_noise=0.0, accel_noise=0.0, disp_noise=0.0)


def device(setting: str, zeta_b: float | None):
    """Table I and Table 2's device, its plate mode damped ``zeta_b`` (None: Table I's c_B)."""
    p = paper_parameters(setting)
    if zeta_b is None:
        return p
    return dataclasses.replace(p, c_B=2.0 * zeta_b * math.sqrt(p.k_B * p.m_B))


def one(job) -> dict:
    k, out, zeta_b, max_steps, commit = job
    path = Path(out) / "records" / f"{k:04d}.json"
    if path.exists():
        return json.loads(path.read_text())
    setting, freq = grid_case(k)
    p = device(setting, zeta_b)
    rec = generate_record(p, freq, settings=NOISE_FREE, setting_name=setting)
    t0 = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        res = fit_record(rec, Path(tmp) / "fit", seed=k, plots=False,
                         convergence=replace(Convergence(), max_steps=max_steps))
    b = np.asarray(res.idata.posterior["b"]).ravel()
    lo, hi = hdi(b)
    tau = np.asarray(res.tau, dtype=float)
    row = {"record": k, "setting": setting, "freq_hz": freq, "zeta_B": zeta_b, "b_true": p.b,
           "b_median": float(np.median(b)), "error_pct": 100.0 * (float(np.median(b)) / p.b - 1.0),
           "hdi94_lo": float(lo), "hdi94_hi": float(hi), "holds94": bool(lo <= p.b <= hi),
           "width94_pct": 100.0 * (hi - lo) / p.b, "identified": bool(res.b_interval.identified),
           "converged": bool(res.converged), "steps": int(res.iterations),
           "tau_max": float(np.nanmax(tau)) if np.any(np.isfinite(tau)) else None,
           "seconds": round(time.perf_counter() - t0, 1), "commit": commit}
    path.write_text(json.dumps(row, indent=1) + "\n")
    return row


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--records", type=int, default=27)
    ap.add_argument("--out", default=str(ROOT / "results" / "noise-free-chains"))
    ap.add_argument("--zeta-B", type=float, default=None, dest="zeta_b",
                    help="the plate mode's damping ratio (default: Table I's c_B)")
    ap.add_argument("--max-steps", type=int, default=20000)
    ap.add_argument("--processes", type=int, default=1)
    ap.add_argument("--summarise", action="store_true", help="only write chains.csv from the records there")
    args = ap.parse_args(argv)
    if not 1 <= args.records <= 27:
        print(f"error: --records must lie in 1 to 27 (the paper's grid), got {args.records}", file=sys.stderr)
        return 2
    if args.zeta_b is not None and not 0.0 < args.zeta_b < 1.0:
        print(f"error: --zeta-B is a damping ratio in (0, 1), got {args.zeta_b}", file=sys.stderr)
        return 2
    out = Path(args.out)
    if not args.summarise:
        (out / "records").mkdir(parents=True, exist_ok=True)
    kept = {json.loads(p.read_text())["zeta_B"] for p in (out / "records").glob("*.json")}
    if kept - {args.zeta_b}:
        print(f"error: {out} holds records of zeta_B {sorted(kept, key=str)}, not {args.zeta_b}; choose another --out",
              file=sys.stderr)
        return 2
    if not args.summarise:
        commit = git_commit(ROOT)  # the code this run loaded: HEAD may move while it runs
        jobs = [(k, out, args.zeta_b, args.max_steps, commit) for k in range(args.records)]
        with make_executor(max(1, args.processes)) as executor:
            for i, got in enumerate(executor.as_completed(one, jobs), 1):
                if not got.ok:  # one record's failure is reported, the others go on
                    print(f"record {jobs[got.index][0]} failed: {got.error}", file=sys.stderr, flush=True)
                    continue
                r = got.value
                print(f"[{i}/{len(jobs)}] {r['setting']} {r['freq_hz']:g} Hz: b {r['b_median']:.1f} (true "
                      f"{r['b_true']:.1f}, {r['error_pct']:+.3f} %), 94 % {'holds' if r['holds94'] else 'MISSES'}, "
                      f"converged {r['converged']} ({r['steps']} steps), {r['seconds']} s", flush=True)
    rows = [json.loads(p.read_text()) for p in sorted((out / "records").glob("*.json"))]
    if not rows:
        print(f"error: {out} holds no finished record; run without --summarise first", file=sys.stderr)
        return 2
    write_rows(out / "chains.csv", rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
