"""Benchmark: how the sampler deals a batch of walkers to its worker processes.

Run by hand from the project root: ``python benchmarks/bench_pool_chunks.py [--processes 2]
[--repeats 7]``.

The joint model's walkers are evaluated on worker processes (``target.Target.batch`` on
``executor.LocalProcesses``, which deals one walker per task),
one batch per move: 21 walkers for the ensemble moves (half of 42), all 42 for the fitted
independence move. ``Pool.map`` deals its items in chunks of about a quarter of a worker's
share by default, so at the end of a batch one worker may still have a chunk to go while
the other waits; one walker per task deals them evenly. On the 27-record joint model of the
paper's grid (generated records, seed 0), at points drawn around its start from the
paper's parameters, the script times one batch of 21 and one of 42 both ways, alternating,
and prints the medians and the ratios. The machine is shared and noisy: read the ratios.
"""

import argparse
import multiprocessing
import statistics
import time

import numpy as np
from _timing import record_row, supported_theta

from bayes_inerter.device import paper_parameters
from bayes_inerter.executor import Executor
from bayes_inerter.inference.sampling.coordinates import default_coordinates
from bayes_inerter.inference.posterior.joint import JointModel
from bayes_inerter.inference.posterior.model import PosteriorModel
from bayes_inerter.inference.sampling.target import Target, log_prob_at
from bayes_inerter.records.generator import paper_grid

_TARGET = None  # the target each worker of this script's pool was given


def _install(target):
    global _TARGET
    _TARGET = target


def _evaluate(theta):
    return log_prob_at(_TARGET, theta)


class _Chunks(Executor):
    """An executor over ``pool`` whose map deals items in ``chunksize`` (None: Pool.map's
    default chunks)."""

    def __init__(self, pool, chunksize, workers):
        self.pool, self.chunksize, self.workers = pool, chunksize, workers

    def map_state(self, fn, items):
        kw = {} if self.chunksize is None else {"chunksize": self.chunksize}
        return self.pool.map(_evaluate, list(items), **kw)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--processes", type=int, default=2)
    ap.add_argument("--repeats", type=int, default=7)
    args = ap.parse_args()

    records = [r for _, _, r in paper_grid(seed=0)]
    jm = JointModel(tuple(records))
    medians = []
    for r in records:
        pm = PosteriorModel(r)
        t = supported_theta(pm, paper_parameters(r.metadata["setting"]), 0.003, 0.3)
        medians.append(dict(zip(pm.names, pm.to_values(t))))
    theta = jm.start(medians)
    coords = default_coordinates(jm)
    u0 = coords.to_u(theta)
    rng = np.random.default_rng(0)
    batches = {n: u0 + 1e-3 * rng.standard_normal((n, len(u0))) for n in (21, 42)}
    target = Target(jm, coords)
    times = {(n, c): [] for n in batches for c in ("default", "one")}
    with multiprocessing.get_context("fork").Pool(args.processes, initializer=_install, initargs=(target,)) as pool:
        ways = {label: _Chunks(pool, chunks, args.processes) for label, chunks in (("default", None), ("one", 1))}
        for n, us in batches.items():
            for executor in ways.values():
                target.batch(us, executor)  # warm-up
        for _ in range(args.repeats):
            for n, us in batches.items():
                for label, executor in ways.items():
                    t0 = time.perf_counter()
                    target.batch(us, executor)
                    times[(n, label)].append(time.perf_counter() - t0)
    for n in batches:
        d = statistics.median(times[(n, "default")])
        o = statistics.median(times[(n, "one")])
        print(f"batch of {n} walkers on {args.processes} processes: default chunks {d * 1e3:.1f} ms, "
              f"one walker per task {o * 1e3:.1f} ms, ratio {d / o:.2f} (medians of {args.repeats})")
        path = record_row("pool_chunks", {"walkers": n, "processes": args.processes, "repeats": args.repeats,
                                          "default_chunks_ms": round(d * 1e3, 2), "one_per_task_ms": round(o * 1e3, 2),
                                          "ratio": round(d / o, 3)})
    print(f"wrote rows to {path}")


if __name__ == "__main__":
    main()
