"""The ``fit`` command: one record's posterior, and what it says in a few lines."""

from __future__ import annotations

from pathlib import Path

__all__ = ["cmd_fit"]

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
    from ..inference.sampling.convergence import Convergence
    from ..inference.posterior.model import LikelihoodSettings
    from ..inference.summaries.results import every_nth
    from ..inference.sampling.sampler import Adaptation, Tempering
    from ..inference.sampling.tempering import default_convergence
    from .status import EXIT_OK, CliError, check_interrupt
    from .records import load_record

    if args.steps is not None and args.max_steps is not None:
        raise CliError("give --steps (exactly that many) or --max-steps (until converged, at most that many), "
                       "not both")
    if args.no_tempering and (args.tempering is not None or args.hottest_beta is not None):
        raise CliError("--no-tempering fits without the tempering ladder that --tempering and --hottest-beta set: "
                       "give one or the other")
    # --hottest-beta alone asks for the measured ladder's 4 temperatures down to it
    temps = args.tempering or (Tempering.temps if args.hottest_beta is not None else None)
    tempering = None if args.no_tempering else Tempering.of(temps, args.hottest_beta)
    convergence = default_convergence(tempering) if args.max_steps is None else Convergence(max_steps=args.max_steps)
    # refused here, before the output folder is touched
    rec, device, masses, drive = load_record(args, need_masses=True)
    print(f"masses: {masses.describe()}", flush=True)
    print(f"drive frequency: {drive.describe()}", flush=True)
    processes = args.processes or min(2, os.cpu_count() or 1)
    options = dict(masses=masses, device=device, walkers=args.walkers, steps=args.steps,
                   seed=args.seed, fresh=args.fresh, processes=processes,
                   likelihood=LikelihoodSettings(residual=args.residual, upsample=args.upsample, delay_sd=args.delay_sd,
                                                 form_sd=args.form_sd, form_friction=args.form_friction),
                   coordinates=args.coordinates,
                   adaptation=None if args.no_adaptation else Adaptation(block_partners=args.block_partners),
                   checkpoint_seconds=args.checkpoint_seconds, plots=not args.no_plots, interval=args.interval,
                   name=Path(args.record).name, convergence=convergence, tempering=tempering)
    if args.model == "compare":
        return _compare(rec, args, options)
    bar = StepProgress("sampling", total=args.steps, check_interrupt=check_interrupt, cap=convergence.max_steps)
    try:
        result = fit_record(rec, args.out, model=args.model, progress=bar.step, report=bar.status, **options)
    except BaseException:
        bar.close(done=False)
        raise
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
    print(f"kept: the draws after step {result.burn_in} (a warm-up of {result.warmup} steps, then 2 tau), "
          f"{every_nth(result.thin)}")
    if result.tempering is not None:
        rates = ", ".join(f"{r:.0%}" for r in result.tempering["swap_rates"])
        print(f"{result.tempering['ladder']}; swaps accepted between neighbours: {rates}")
        if result.tempering.get("replica_tau"):
            print(f"tau read on the replicas too: largest {max(result.tempering['replica_tau'].values()):.0f} steps")
    for w in result.warnings:  # fit.json keeps the same lines
        print(f"warning: {w.message}")
    if result.converged:
        print("converged")
    figures = "".join(f"{n}, " for n in result.figures)  # what this fit drew, not what the folder holds
    print(f"wrote {args.out}/summary.csv, posterior.nc, loo.json, chain.h5 (and its twin), {figures}fit.json")
    return EXIT_OK


def _compare(rec, args, options) -> int:
    """``fit --model compare``: every model the likelihood knows, compared by LOO."""
    from ..cli_progress import StepProgress
    from ..inference.compare import PARETO_K_LIMIT, compare_models
    from .status import EXIT_OK, check_interrupt

    bars = []

    def progress_for(model):
        if bars:
            bars[-1].close()
        bars.append(StepProgress(f"sampling {model}", total=args.steps, check_interrupt=check_interrupt,
                                 cap=options["convergence"].max_steps))
        return bars[-1].step, bars[-1].status

    def on_model(model, reason):
        if reason:
            print(f"{model}: left out ({reason})", flush=True)

    try:
        c = compare_models(rec, args.out, on_model=on_model, progress_for=progress_for, **options)
    except BaseException:
        if bars:
            bars[-1].close(done=False)
        raise
    if bars:
        bars[-1].close()
    residual = options["likelihood"].residual
    print(f"models compared by PSIS-LOO under the {residual} likelihood, stacked by their LOO weights:")
    width = max(len(f.model) for f in c.fitted)
    for f in c.fitted:
        flags = "" if f.loo_reliable else f"; Pareto k {f.pareto_k_max:.2f} > {PARETO_K_LIMIT:g}: its LOO is unreliable"
        flags += "" if f.converged else f"; not converged after {f.steps} steps"
        print(f"  {f.model:<{width}}  b = {f.b_median:.6g} kg (94 % HDI {f.b_lo:.6g} to {f.b_hi:.6g}), "
              f"elpd_loo {f.elpd_loo:.1f} (se {f.elpd_se:.1f}), weight {f.weight:.2f}{flags}")
    print(f"stacked: b = {c.b_median:.6g} kg (94 % HDI {c.b_lo:.6g} to {c.b_hi:.6g})")
    unreliable = [f.model for f in c.fitted if not f.loo_reliable or not f.converged]
    if unreliable:
        print(f"warning: {len(unreliable)} of {len(c.fitted)} models' LOO is unreliable or their chain unconverged "
              f"({', '.join(unreliable)}): the weights and the stacked b are indicative only; quote b under a "
              f"converged model")
    print(f"wrote {args.out}/compare.csv, compare.json, and each model's fit in {args.out}/<model>/")
    return EXIT_OK
