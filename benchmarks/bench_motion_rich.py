"""Benchmark: one evaluation of the richer models under the default (motion-in) likelihood.

Run by hand from the project root: ``python benchmarks/bench_motion_rich.py [--setting A3]
[--seed 0] [--freqs 0.5 1.0 1.5] [--repeats 30]``.

On the paper-like records of ``--setting`` (laboratory ``--seed``,
``records.paper_like.paper_like_record``: full network, Stribeck friction, nut backlash)
at each frequency, the log posterior of the two-port model and of the three richer ones
(``two-port-stribeck``, ``two-port-backlash``, ``two-port-rich``) is evaluated at Table
I's parameters with the plate mode damped 2 % (``_timing.supported_theta``) and, for the
richer models, break-away 1.3 times the Coulomb force over 10 mm/s and a 10 um nut
backlash; each model with its normaliser and deviations taken at that point
(``PosteriorModel.with_reference``, as a fit takes them at its start). The calls
alternate between the models, and the medians of ``--repeats`` calls are printed with
their ratio to the two-port model's, and one row a frequency is written to
results/performance/motion_rich.csv. The time-domain form of the same effects is
``bench_kernel_rich.py`` (the plate's mode and its chatter simulated); here the plate's
motion is measured and only the drivetrain behind it is simulated. The machine is
shared and noisy: read the ratios, not the absolutes.
"""

import argparse
import math
import statistics
import time

from _timing import record_row, supported_theta

from bayes_inerter import paper_parameters
from bayes_inerter.inference import PosteriorModel
from bayes_inerter.records.paper_like import paper_like_record

MODELS = ("two-port", "two-port-stribeck", "two-port-backlash", "two-port-rich")
#: The effects at the point timed (m/s and m where they have units).
EFFECTS = {"r_s": 1.3, "v_s": 0.01, "gap": 1e-5}


def timed_models(record, setting):
    """Each model of :data:`MODELS` on ``record`` with its reference at the point timed,
    and that point."""
    out = {}
    for name in MODELS:
        model = PosteriorModel(record, name)
        theta = supported_theta(model, paper_parameters(setting))
        for effect, value in EFFECTS.items():
            if effect in model.names:
                log_scale = model.all_priors[effect].log_scale
                theta[model.names.index(effect)] = math.log(value) if log_scale else value
        model = model.with_reference(theta)
        if not math.isfinite(model.log_prob(theta)[0]):
            raise SystemExit(f"error: the {name} model's log posterior is not finite at the point timed")
        out[name] = (model, theta)
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--setting", default="A3")
    ap.add_argument("--seed", type=int, default=0, help="the paper-like laboratory's seed")
    ap.add_argument("--freqs", type=float, nargs="+", default=[0.5, 1.0, 1.5])
    ap.add_argument("--repeats", type=int, default=30)
    args = ap.parse_args()

    print(f"paper-like {args.setting}, laboratory {args.seed}; effects at the point timed {EFFECTS}; "
          f"{args.repeats} alternating repeats")
    for freq in args.freqs:
        models = timed_models(paper_like_record(args.setting, freq, seed=args.seed), args.setting)
        times = {name: [] for name in models}
        for model, theta in models.values():
            model.log_prob(theta)  # compile
        for _ in range(args.repeats):
            for name, (model, theta) in models.items():
                t0 = time.perf_counter()
                model.log_prob(theta)
                times[name].append(time.perf_counter() - t0)
        base = statistics.median(times["two-port"])
        ratios = {name: statistics.median(ts) / base for name, ts in times.items()}
        print(f"{freq:g} Hz: " + "; ".join(f"{name} {statistics.median(times[name]) * 1e3:.2f} ms "
                                           f"(x{ratios[name]:.2f})" for name in models))
        path = record_row("motion_rich", {"setting": args.setting, "seed": args.seed, "freq_hz": freq,
                                          "repeats": args.repeats, "two_port_ms": round(base * 1e3, 3),
                                          **{f"ratio_{n.removeprefix('two-port-')}": round(ratios[n], 2)
                                             for n in MODELS[1:]}})
    print(f"wrote rows to {path}")


if __name__ == "__main__":
    main()
