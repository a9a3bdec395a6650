"""Does the accelerometer's noise pull b's optimum under the motion-in likelihood, and
which of its parts carries the pull? (issue 39, item 5: the held-out families' b low.)

A probe of the posterior's mode, not of a chain: for each record, the start search's
optimum (``find_start``, as ``fit`` runs it), then the likelihood's reference set there
(``PosteriorModel.with_reference``, as the sampler does) and the point polished again
(``local_optimum``); the row keeps that mode's b. The records are paper-like
(``records.paper_like``, the default device) with the load cell's noise and the sensors'
calibration errors off, and the accelerometer's noise at ``--levels`` times the
default's (0.01 m/s^2, coloured at 50 Hz; the same draw scaled, so a row differs from
its neighbours only in the noise's size). Each record is fitted under the default
likelihood and under ``--variant`` changes of it (by default ``reversals=false``: the
plate's reversal windows' deviations not marginalised).

``--device`` takes the device apart: each item a JSON object of changes of
``PaperLike`` (``{"ratio": [1.5, 1.5]}``: a 1.5x break-away; ``{"backlash": [0, 0]}``
... ``[1e-12, 1e-12]``: none) and ``"network"`` (the generator's network in place of
the paper-like device's "full" one: "reduced" is the network the model fits); each
device's records are fitted at every level.

    python studies/accel_noise_bias.py [--records A1:0.5 A4:0.5 B1:0.5 A1:1 A4:1 B1:1]
        [--levels 0 0.5 1 2 4] [--variant reversals=false] [--seed0 24100]
        [--device '{}' ...] [--processes 2] [--out results/accel-noise-bias]
        [--table table.csv]

Record i is of laboratory ``seed0 + i`` (laboratories 24100 and up were used for
nothing before). Writes table.csv (one row per record, level and likelihood) into
--out and prints the rows. Exit codes: 0 done, 2 bad input.
"""

import argparse
import dataclasses
import json
import sys
from pathlib import Path

from _table import map_rows, record_arg, write_rows

ROOT = Path(__file__).resolve().parents[1]
ACCEL_NOISE = 0.01  # m/s^2: the paper-like device's default accelerometer noise (PaperLike.accel_noise)


def _device(changes: dict, level: float):
    """The paper-like device with ``changes`` (module docstring), the load cell's noise
    and the calibration errors off, the accelerometer's noise at ``level`` times the default."""
    from bayes_inerter.records.paper_like import PaperLike
    from bayes_inerter.records.sensitivity import SensorCalibration

    changes = dict(changes)
    network = changes.pop("network", None)
    fields = {name: tuple(value) if isinstance(value, list) else value for name, value in changes.items()}
    device = PaperLike(**{**fields, "force_noise": 0.0, "accel_noise": level * ACCEL_NOISE,
                          "calibration": SensorCalibration(0.0, 0.0)})
    if network is None:
        return device

    class WithNetwork(PaperLike):
        def draw(self, rng):
            return dataclasses.replace(PaperLike.draw(self, rng), network=network)

    return WithNetwork(**{f.name: getattr(device, f.name) for f in dataclasses.fields(PaperLike)})


def _mode(job):
    i, setting, freq, seed, level, likelihood, changes = job
    import json
    import math
    import time

    import numpy as np

    from bayes_inerter.device import paper_parameters
    from bayes_inerter.inference.posterior.likelihood import settings_changes
    from bayes_inerter.inference.posterior.model import LikelihoodSettings, PosteriorModel
    from bayes_inerter.inference.sampling.optimize import find_start, local_optimum
    from bayes_inerter.masses import resolve_masses
    from bayes_inerter.records.drive import resolve_drive, with_drive
    from bayes_inerter.records.paper_like import paper_like_record

    t0 = time.perf_counter()
    rec = paper_like_record(setting, freq, seed=seed, device=_device(changes, level))
    rec = with_drive(rec, resolve_drive(rec, None))
    masses = resolve_masses(rec)
    model = PosteriorModel(rec, "two-port", m_s=masses.m_s, m_B=masses.m_B,
                           likelihood=LikelihoodSettings(**settings_changes(likelihood)))
    start, _ = find_start(model, np.random.default_rng(seed))
    referenced = model.with_reference(start)
    theta, lp = local_optimum(referenced, start, restarts=6)
    b_true = paper_parameters(setting).b
    values = referenced.values(theta)
    return {"record": i, "setting": setting, "freq_hz": freq, "seed": seed, "device": json.dumps(changes),
            "accel_noise": level * ACCEL_NOISE,
            "likelihood": likelihood, "b_error_pct": round(100.0 * (values["b"] / b_true - 1.0), 3),
            "start_b_error_pct": round(100.0 * (model.values(start)["b"] / b_true - 1.0), 3),
            "f_share": round(values["f_share"], 4), "log_posterior": round(float(lp), 2) if math.isfinite(lp) else None,
            "seconds": round(time.perf_counter() - t0, 1)}


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--records", nargs="+", default=["A1:0.5", "A4:0.5", "B1:0.5", "A1:1", "A4:1", "B1:1"])
    parser.add_argument("--levels", nargs="+", type=float, default=[0.0, 0.5, 1.0, 2.0, 4.0],
                        help="accelerometer noise, times the paper-like default's 0.01 m/s^2")
    parser.add_argument("--variant", nargs="*", default=["reversals=false"],
                        help="likelihood changes fitted beside the default (name=value,...)")
    parser.add_argument("--seed0", type=int, default=24100)
    parser.add_argument("--device", nargs="+", default=["{}"],
                        help="JSON changes of the paper-like device, one device each (module docstring)")
    parser.add_argument("--processes", type=int, default=2)
    parser.add_argument("--table", default="table.csv", help="the table's file name in --out")
    parser.add_argument("--out", type=Path, default=ROOT / "results" / "accel-noise-bias")
    args = parser.parse_args(argv)
    if any(level < 0 for level in args.levels):
        print("error: --levels must be at least 0 (a multiple of the default noise)", file=sys.stderr)
        return 2
    records = [record_arg(item) for item in args.records]
    try:
        devices = [json.loads(text) for text in args.device]
        for changes in devices:
            if not isinstance(changes, dict):
                raise ValueError(f"{changes!r} is not a JSON object")
            _device(changes, 0.0)
    except (ValueError, TypeError) as exc:
        print(f"error: --device: {exc} (give JSON objects of PaperLike fields, such as "
              "'{\"ratio\": [1.5, 1.5]}')", file=sys.stderr)
        return 2
    jobs = [(i, setting, freq, args.seed0 + i, level, likelihood, changes)
            for changes in devices for i, (setting, freq) in enumerate(records) for level in args.levels
            for likelihood in ["default", *args.variant]]
    print(f"{len(jobs)} optima on {args.processes} processes", flush=True)
    rows = map_rows(_mode, jobs, args.processes)
    write_rows(args.out / args.table, rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
