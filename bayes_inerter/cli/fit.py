"""The ``fit`` command: one record's posterior, and what it says in a few lines."""

from __future__ import annotations

import json
import math
from pathlib import Path

__all__ = ["cmd_fit"]


def _mixing(b_row: dict, tau: dict) -> str:
    """What an unconverged chain says of b itself and which parameters hold it back: on
    a real device these are often ones the record leaves unidentified (docs/studies.md)."""
    slow = sorted(((t, n) for n, t in tau.items() if math.isfinite(t)), reverse=True)[:3]
    rhat, ess = b_row.get("r_hat", math.nan), b_row.get("ess_bulk", math.nan)
    own = (f"R-hat {rhat:.3f}, bulk ESS {ess:.0f}" if math.isfinite(rhat) and math.isfinite(ess)
           else "too short to judge")
    return (f"b's own chain: {own}; slowest to mix: "
            + (", ".join(f"{n} (tau {t:.0f} steps)" for t, n in slow) or "not known yet"))


def _percent_interval(lo: float, hi: float) -> str:
    """'lo % to hi %' with the fewest decimals (2 to 8) that tell the two apart."""
    for d in range(2, 9):
        a, b = f"{lo * 100:.{d}f}", f"{hi * 100:.{d}f}"
        if a != b:
            break
    return f"{a} % to {b} %"


def cmd_fit(args) -> int:
    import os

    from ..cli_progress import StepProgress
    from ..inference import fit_record
    from ..inference.coordinates import EDGE_WARNING, MAX_SENSITIVITY_CHANGE
    from ..inference.model import LikelihoodSettings
    from ..inference.sampler import Adaptation
    from . import EXIT_OK, _check_interrupt
    from .records import load_record

    # refused here, before the output folder is touched
    rec, device, masses, drive = load_record(args, need_masses=True)
    print(f"masses: {masses.describe()}", flush=True)
    print(f"drive frequency: {drive.describe()}", flush=True)
    bar = StepProgress("sampling", total=args.steps, check_interrupt=_check_interrupt)
    processes = args.processes or min(2, os.cpu_count() or 1)
    try:
        result = fit_record(
            rec, args.out, model=args.model, m_s=args.m_s, m_B=args.m_b, device=device, walkers=args.walkers,
            steps=args.steps, seed=args.seed, fresh=args.fresh, processes=processes,
            likelihood=LikelihoodSettings(residual=args.residual, upsample=args.upsample), progress=bar.step,
            report=bar.status, coordinates=args.coordinates, adaptation=None if args.no_adaptation else Adaptation(),
            checkpoint_seconds=args.checkpoint_seconds, plots=not args.no_plots, interval=args.interval,
        )
    finally:
        bar.close()
    if result.recovered:
        print(f"note: checkpoint damaged, recovered: {result.recovered}")
    b, iv = result.row("b"), result.b_interval
    print(f"b = {iv.median:.6g} kg ({iv.describe()}: {iv.lo:.6g} to {iv.hi:.6g}), {result.iterations} steps")
    if iv.method != "posterior":
        print(f"  the posterior alone: 94 % HDI {b['hdi_3%']:.6g} to {b['hdi_97%']:.6g}")
    if result.b_theory is not None:
        print(f"theory (device file geometry): b = {result.b_theory:.6g} kg "
              f"({(iv.median - result.b_theory) / result.b_theory:+.1%} identified against it)")
    phi = result.row("phi")
    print(f"phi = {phi['mean']:.2%} (94 % HDI {_percent_interval(phi['hdi_3%'], phi['hdi_97%'])})")
    for w in result.warnings:
        print(f"warning: {w.message}")
    info = json.loads((Path(args.out) / "fit.json").read_text())
    edge = info.get("coordinates_domain_edge")
    if edge is not None and edge > EDGE_WARNING:
        print(f"warning: the posterior reaches |dZ/dZ_theta - 1| = {edge:.2f}, near the edge of the impedance "
              f"coordinates' domain ({MAX_SENSITIVITY_CHANGE:g}), which may cut it; compare with "
              "--coordinates unconstrained")
    if result.converged:
        print("converged")
    else:
        print(f"warning: {result.reason}; do not trust these intervals yet "
              "(run again with more --steps, or without --steps)")
        print(f"  {_mixing(b, info.get('tau') or {})}")
    figures = "" if args.no_plots else "corner.png, bands.png, trace.png, phi.png, "
    print(f"wrote {args.out}/summary.csv, posterior.nc, loo.json, chain.h5 (and its twin), {figures}fit.json")
    return EXIT_OK
