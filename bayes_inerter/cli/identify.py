"""The ``identify`` command: the paper's own eq. (4) least-squares fit of one record,
with phi (eq. 5) on the record as measured and an interval for b."""

from __future__ import annotations

import json
from pathlib import Path

__all__ = ["cmd_identify"]


def cmd_identify(args) -> int:
    from ..inference.identify import identify
    from ..inference.model import PosteriorModel
    from . import EXIT_OK
    from .records import load_record

    rec, device, masses = load_record(args, need_masses=True)  # refused here, before any work
    if args.bootstrap and args.bootstrap < 50:
        raise ValueError(f"--bootstrap {args.bootstrap} replicates are too few for a 94 % interval; give 50 or more")
    if args.out and Path(args.out).suffix.lower() != ".json":
        raise ValueError(f"--out {args.out}: give a .json file name")
    print(f"masses: {masses.describe()}", flush=True)
    model = PosteriorModel(rec, args.model, m_s=masses.m_s, m_B=masses.m_B)
    how = f"bootstrap over cycles, {args.bootstrap} refits" if args.bootstrap else "Hessian, cycle-clustered"
    print(f"least squares from {args.starts} starts; b's interval: {how} ...", flush=True)
    got = identify(model, starts=args.starts, seed=args.seed, bootstrap=args.bootstrap)
    if got.b_interval is not None:
        lo, hi = got.b_interval
        print(f"b = {got.b:.6g} kg (least squares; {got.level * 100:.0f} % interval {lo:.6g} to {hi:.6g}, "
              f"{got.interval} over {got.cycles} drive cycles)")
    else:
        print(f"b = {got.b:.6g} kg (least squares; no interval: {got.why})")
    print(f"phi = {got.phi:.2%} (eq. 5 on the record as measured; {got.phi_filtered:.2%} on the low-passed one)")
    if device is not None and device.theoretical_inertance is not None:
        theory = device.theoretical_inertance
        print(f"theory (device file geometry): b = {theory:.6g} kg ({(got.b - theory) / theory:+.1%} identified)")
    print("parameters: " + ", ".join(f"{k} {v:.4g}" for k, v in got.values.items()))
    print("note: a point estimate and how far the record's own noise and misfit move it; "
          "bayes-inerter fit gives the posterior and the honest interval")
    if args.out:
        info = {"record": str(args.record), "model": args.model, "b": got.b, "b_interval": got.b_interval,
                "level": got.level, "interval": got.interval, "cycles": got.cycles, "why_no_interval": got.why,
                "phi": got.phi, "phi_filtered": got.phi_filtered, "sse": got.sse, "starts": got.starts,
                "seed": args.seed, "values": got.values, "b_draws": list(got.b_draws),
                "masses": {"m_s": masses.m_s, "m_B": masses.m_B}}
        Path(args.out).parent.mkdir(parents=True, exist_ok=True)
        Path(args.out).write_text(json.dumps(info, indent=2) + "\n")
        print(f"wrote {args.out}")
    return EXIT_OK
