"""Benchmark: what the crash-safe checkpoint costs per sampler step.

Run by hand: ``python benchmarks/bench_checkpoint.py``.

Side by side in one run, per step of 24 walkers and 11 parameters (the two-port
model's defaults), median and mean over steps: emcee's own HDFBackend writing one file;
the twin checkpoint written at every step (each step written and sealed in chain.h5, the
twin caught up every 10 steps; ``write_seconds=0``); the twin checkpoint as runs use it
by default (steps written at most ``checkpoint.WRITE_SECONDS`` apart, the steps spaced
here by a pause as long as a step's evaluations); and one log-probability evaluation of
a 10 s record (a step costs 24 of them). Prints each checkpoint's cost as a share of a
step's evaluations. The machine is shared and noisy: read the ratios.
"""

import tempfile
import time
from pathlib import Path

import emcee
import numpy as np

from _timing import median_time, record_row, supported_theta

WALKERS, NDIM, STEPS = 24, 11, 300


def _per_step(make_backend, pause: float = 0.0):
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
            if pause:
                time.sleep(pause)  # the step's evaluations
            t0 = time.perf_counter()
            backend.save_step(state, np.ones(WALKERS, dtype=bool))
            times.append(time.perf_counter() - t0)
        return float(np.median(times)), float(np.mean(times))


def main():
    from bayes_inerter import paper_parameters
    from bayes_inerter.inference import PosteriorModel
    from bayes_inerter.inference.sampling.checkpoint import WRITE_SECONDS, new_checkpoint
    from bayes_inerter.records import generate_record

    def plain(path):
        b = emcee.backends.HDFBackend(str(path))
        b.reset(WALKERS, NDIM)
        return b

    shape = {"nwalkers": WALKERS, "ndim": NDIM}  # the identity's shape suffices: nothing continues these

    def twin(path):
        return new_checkpoint(path, identity=shape, write_seconds=0.0)

    def held(path):
        return new_checkpoint(path, identity=shape, write_seconds=WRITE_SECONDS)

    rec = generate_record(paper_parameters("A3"), 1.0, rng=0, setting_name="A3")
    model = PosteriorModel(rec)
    theta = supported_theta(model, paper_parameters("A3"))
    evaluation = median_time(lambda: model.log_prob(theta), repeats=30)
    step = WALKERS * evaluation
    single, single_mean = _per_step(plain)
    double, double_mean = _per_step(twin)
    batched, batched_mean = _per_step(held, pause=step)
    print(f"emcee HDFBackend, one file:  median {1e3 * single:6.2f} ms, mean {1e3 * single_mean:6.2f} ms per step")
    print(f"twin checkpoint, every step: median {1e3 * double:6.2f} ms, mean {1e3 * double_mean:6.2f} ms per step "
          f"(mean {double_mean / single_mean:.2f}x emcee's)")
    print(f"twin checkpoint, at most {WRITE_SECONDS:g} s apart (the default): median {1e3 * batched:6.2f} ms, "
          f"mean {1e3 * batched_mean:6.2f} ms per step")
    print(f"log-prob evaluations of a step: {1e3 * step:6.2f} ms (24 x {1e3 * evaluation:.2f} ms, 10 s record)")
    print("checkpoint share of a step (means): " + ", ".join(
        f"{name} {m / (m + step):.1%}" for name, m in (("every step", double_mean), ("default", batched_mean),
                                                        ("emcee's own backend", single_mean))))
    path = record_row("checkpoint", {
        "emcee_median_ms": round(1e3 * single, 3), "emcee_mean_ms": round(1e3 * single_mean, 3),
        "twin_every_step_median_ms": round(1e3 * double, 3), "twin_every_step_mean_ms": round(1e3 * double_mean, 3),
        "twin_default_median_ms": round(1e3 * batched, 3), "twin_default_mean_ms": round(1e3 * batched_mean, 3),
        "write_seconds": WRITE_SECONDS, "step_evaluations_ms": round(1e3 * step, 3),
        "twin_every_step_over_emcee": round(double_mean / single_mean, 3),
        "default_share_of_step": round(batched_mean / (batched_mean + step), 4)})
    print(f"wrote a row to {path}")


if __name__ == "__main__":
    main()
