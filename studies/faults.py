"""Fault injection: a fit killed (SIGKILL) many times at random moments, run again each
time, and compared with the same fit never interrupted.

    python studies/faults.py [--kills 30] [--steps 400] [--seed 0] [--out results/faults]

Each round starts ``bayes-inerter fit`` on a short generated record, with the
time-domain likelihood (``--residual ar1``: it simulates the record at every evaluation,
so a step takes long enough to be killed within it; the default likelihood needs three
steady periods and takes milliseconds a step) and the checkpoint written at every step
(``--checkpoint-seconds 0``: each write is a moment to be killed in; the default holds
steps for up to 2 s and writes them together, through the same code), waits until the
run has written a new step, sleeps a seeded random 0-0.3 s and kills it. After every kill it records how many steps a continued run would keep and whether a file was
damaged (moved aside as ``*.damaged``); at the end it finishes the run and checks the
chain equals an uninterrupted run's, bit for bit. Writes ``kills.csv`` and ``REPORT.md``
into ``--out``; exits 1 if any check failed.
"""

import argparse
import csv
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from bayes_inerter.study.manifest import script_configuration, write_manifest

ROOT = Path(__file__).resolve().parents[1]



def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--kills", type=int, default=30)
    ap.add_argument("--steps", type=int, default=400)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--out", default=str(ROOT / "results" / "faults"))
    args = ap.parse_args()

    from tqdm import tqdm

    from bayes_inerter import paper_parameters
    from bayes_inerter.inference.sampling.checkpoint import read_chain, steps_written
    from bayes_inerter.records import GeneratorSettings, generate_record, write_record

    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    write_manifest(out, script_configuration())
    rng = np.random.default_rng(args.seed)
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        rec = generate_record(paper_parameters("A4"), 1.5, settings=GeneratorSettings(duration=2.5, ramp=0.8),
                              rng=11, setting_name="A4")
        record, _ = write_record(tmp / "a4.csv", rec)
        fit = tmp / "killed"
        cmd = [sys.executable, "-m", "bayes_inerter.cli", "fit", str(record), "--out", str(fit), "--steps",
               str(args.steps), "--walkers", "24", "--processes", "1", "--seed", "3", "--residual", "ar1",
               "--checkpoint-seconds", "0"]
        chain_file = fit / "chain.h5"
        rows, before, problems = [], None, []
        for k in tqdm(range(args.kills), desc="kills", unit="kill", file=sys.stderr):
            start = 0 if before is None else len(before)
            proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
            while proc.poll() is None and steps_written(chain_file) <= start:
                time.sleep(0.005)  # until the run writes a new step
            delay = float(rng.uniform(0.0, 0.3))
            time.sleep(delay)
            if proc.poll() is not None:  # finished (or failed) before the kill
                err = proc.stderr.read().strip()
                if proc.returncode != 0:
                    problems.append(f"round {k}: the continued run failed: {err.splitlines()[-1] if err else ''}")
                break
            os.kill(proc.pid, signal.SIGKILL)
            proc.wait()
            proc.stderr.close()
            damaged = sorted(p.name for p in fit.glob("*.damaged*"))
            now = read_chain(chain_file)
            kept = before is None or (len(now) >= len(before) and np.array_equal(now[: len(before)], before))
            if not kept:
                problems.append(f"round {k}: steps written before this kill were lost or changed")
            rows.append({"kill": k, "delay_s": round(delay, 4), "steps_kept": len(now),
                         "damaged_files_so_far": len(damaged), "earlier_steps_intact": kept})
            before = now
        if len(rows) < args.kills and not problems:
            problems.append(f"the run finished after {len(rows)} of {args.kills} kills: give more --steps")
        done = subprocess.run(cmd, capture_output=True, text=True)
        ref = tmp / "uninterrupted"
        clean = subprocess.run(cmd[:6] + [str(ref)] + cmd[7:], capture_output=True, text=True)
        same = (done.returncode == 0 and clean.returncode == 0
                and np.array_equal(read_chain(chain_file), read_chain(ref / "chain.h5")))
        if not same:
            problems.append("the finished chain differs from the uninterrupted one (or a run failed)")
        damaged = sorted(p.name for p in fit.glob("*.damaged*"))

    with open(out / "kills.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]) if rows else ["kill"])
        w.writeheader()
        w.writerows(rows)
    lines = ["# Fault injection: killed fits", "",
             f"A {args.steps}-step fit (24 walkers, a 2.5 s A4 record at 1.5 Hz, the time-domain likelihood, the "
             f"checkpoint written at every step) killed with SIGKILL {len(rows)} "
             f"times at seeded random moments (seed {args.seed}: 0-0.3 s after the run wrote a new step), run "
             "again each time.", "",
             f"- Files found damaged and moved aside over all kills: {len(damaged)} ({', '.join(damaged) or 'none'}).",
             f"- Steps written before a kill and lost or changed afterwards: "
             f"{sum(not r['earlier_steps_intact'] for r in rows)} kills out of {len(rows)}.",
             f"- Finished chain equal, bit for bit, to an uninterrupted run's: {'yes' if same else 'NO'}.", ""]
    if problems:
        lines += ["Problems:", ""] + [f"- {p}" for p in problems] + [""]
    (out / "REPORT.md").write_text("\n".join(lines))
    print(f"wrote {out}/kills.csv and REPORT.md: {len(rows)} kills, {len(damaged)} damaged files, "
          f"{'same chain' if same else 'DIFFERENT chain'}")
    sys.exit(1 if problems else 0)


if __name__ == "__main__":
    main()
