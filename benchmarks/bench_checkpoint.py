"""Benchmark: what the crash-safe checkpoint costs per sampler step.

Run by hand: ``python benchmarks/bench_checkpoint.py``.

Side by side in one run, per step of 24 walkers and 11 parameters (the two-port
model's defaults), median and mean over steps: emcee's own HDFBackend writing one file;
the twin checkpoint (each step written and sealed in chain.h5, the twin caught up every
10 steps); and one log-probability evaluation of a
10 s record (a step costs 24 of them). Prints the checkpoint's cost as a share of a
step's evaluations. The machine is shared and noisy: read the ratios.
"""

import tempfile
import time
from pathlib import Path

import emcee
import numpy as np

from _timing import median_time

WALKERS, NDIM, STEPS = 24, 11, 300


def _per_step(make_backend):
    """Median seconds to save one step (a twin checkpoint: write and seal), over STEPS
    steps; the mean too, as the twin's catch-up every TWIN_EVERY steps is not in the
    median."""
    with tempfile.TemporaryDirectory() as tmp:
        backend = make_backend(Path(tmp) / "chain.h5")
        rng = np.random.default_rng(0)
        state = emcee.State(rng.normal(size=(WALKERS, NDIM)), log_prob=rng.normal(size=WALKERS),
                            blobs=rng.normal(size=WALKERS), random_state=np.random.RandomState(0).get_state())
        backend.grow(STEPS, state.blobs)
        times = []
        for _ in range(STEPS):
            t0 = time.perf_counter()
            backend.save_step(state, np.ones(WALKERS, dtype=bool))
            times.append(time.perf_counter() - t0)
        return float(np.median(times)), float(np.mean(times))


def main():
    from bayes_inerter import paper_parameters
    from bayes_inerter.inference import PosteriorModel
    from bayes_inerter.inference.checkpoint import new_checkpoint
    from bayes_inerter.records import generate_record

    def plain(path):
        b = emcee.backends.HDFBackend(str(path))
        b.reset(WALKERS, NDIM)
        return b

    def twin(path):
        return new_checkpoint(path, nwalkers=WALKERS, ndim=NDIM, attrs={})

    single, single_mean = _per_step(plain)
    double, double_mean = _per_step(twin)
    rec = generate_record(paper_parameters("A3"), 1.0, rng=0, setting_name="A3")
    model = PosteriorModel(rec)
    theta = model.to_theta(paper_parameters("A3"), 3e-3, 0.5)
    evaluation = median_time(lambda: model.log_prob(theta), repeats=30)
    step = WALKERS * evaluation
    print(f"emcee HDFBackend, one file:  median {1e3 * single:6.2f} ms, mean {1e3 * single_mean:6.2f} ms per step")
    print(f"twin checkpoint, sealed:     median {1e3 * double:6.2f} ms, mean {1e3 * double_mean:6.2f} ms per step "
          f"(mean {double_mean / single_mean:.2f}x emcee's)")
    print(f"log-prob evaluations of a step: {1e3 * step:6.2f} ms (24 x {1e3 * evaluation:.2f} ms, 10 s record)")
    print(f"checkpoint share of a step (means): {double_mean / (double_mean + step):.1%} "
          f"(emcee's own backend: {single_mean / (single_mean + step):.1%})")


if __name__ == "__main__":
    main()
