"""The ``identify`` command: the paper's own eq. (4) least-squares fit of one record,
with phi (eq. 5) on the record as measured and an interval for b."""

from __future__ import annotations

import json
from pathlib import Path

__all__ = ["cmd_identify"]


def cmd_identify(args) -> int:
    from ..inference.summaries.end_state import PHI_WARNING
    from ..inference.identify import LEAST_SQUARES, identify
    from ..inference.posterior.model import PosteriorModel
    from ..inference.summaries.plots import UNITS
    from .status import EXIT_OK, CliError
    from .records import load_record

    rec, device, masses, drive = load_record(args, need_masses=True)  # refused here, before any work
    if args.bootstrap and args.bootstrap < 50:
        raise CliError(f"--bootstrap {args.bootstrap} replicates are too few for a 94 % interval; give 50 or more")
    if args.seed < 0:
        raise CliError(f"--seed {args.seed}: give a whole number of 0 or more")
    if args.out:
        _check_writable(Path(args.out))
    print(f"masses: {masses.describe()}", flush=True)
    print(f"drive frequency: {drive.describe()}", flush=True)
    model = PosteriorModel(rec, args.model, m_s=masses.m_s, m_B=masses.m_B, likelihood=LEAST_SQUARES)
    how = (f"a bootstrap over drive cycles, {args.bootstrap} refits" if args.bootstrap
           else "the least-squares Jacobian, clustered over drive cycles")
    print(f"least squares from {args.starts} starts; b's interval from {how} ...", flush=True)
    got = identify(model, starts=args.starts, seed=args.seed, bootstrap=args.bootstrap)
    if got.b_interval is not None:
        lo, hi = got.b_interval
        source = "bootstrap refits" if got.interval == "bootstrap" else "the Jacobian"
        print(f"b = {got.b:.6g} kg (least squares; {got.level * 100:.0f} % interval {lo:.6g} to {hi:.6g}, "
              f"from {source} over {got.cycles} drive cycles)")
    else:
        print(f"b = {got.b:.6g} kg (least squares; no interval: {got.why})")
    print(f"phi = {got.phi:.2%}: the fit accuracy of eq. 5, 1 - |a_fit - a| / |a - mean a|, on the record as "
          f"measured ({got.phi_filtered:.2%} on the low-passed one)")
    if device is not None and device.theoretical_inertance is not None:
        theory = device.theoretical_inertance
        print(f"theory (device file geometry): b = {theory:.6g} kg ({(got.b - theory) / theory:+.1%} identified)")
    print("parameters: " + ", ".join(f"{k} {v:.4g}{_unit(k, UNITS)}" for k, v in got.values.items()))
    print("  (f_0, c_f: the frictions' sums, f_share, c_share: the plate's shares of them; f1_0, c_f1 the plate's, "
          "f2_0, c_f2 the rotation's; b_app: the inertance seen through the nut; docs/inference.md)")
    if not got.phi_filtered >= PHI_WARNING:
        print(f"warning: the model reproduces {got.phi_filtered:.0%} of the low-passed record (below "
              f"{PHI_WARNING:.0%}): friction and what the model lacks can pose as inertance, so b may be far off "
              "whatever its interval says; bayes-inerter fit reports such a record's b as not identified")
    for name in got.at_bounds:
        print(f"warning: {name} ended on a bound of its prior; the least-squares point is not an optimum there "
              "and b may move with it")
    print("note: a point estimate and how far the record's own noise and misfit move it; "
          "bayes-inerter fit gives the posterior and the honest interval")
    if args.out:
        info = {"record": str(args.record), "model": args.model, "seed": args.seed, **got.as_dict(),
                "masses": {"m_s": masses.m_s, "m_B": masses.m_B}}
        Path(args.out).write_text(json.dumps(info, indent=2) + "\n")
        print(f"wrote {args.out}")
    return EXIT_OK


def _unit(name: str, units: dict) -> str:
    if name in units or name == "b_app":
        return " " + units.get(name, "kg")
    return ""  # a share: a fraction


def _check_writable(path: Path) -> None:
    """Refuse an --out that cannot be written, before the fit (which takes seconds)."""
    from .status import CliError

    if path.suffix.lower() != ".json":
        raise CliError(f"--out {path}: give a .json file name")
    import os

    try:
        path.parent.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise CliError(f"--out {path}: cannot make its folder ({exc.strerror}); give a file in a folder you can "
                       "write to") from None
    if path.is_dir() or not os.access(path.parent, os.W_OK):
        raise CliError(f"--out {path}: cannot write there; give a file in a folder you can write to")
