"""The ``study`` command (many records' posteriors, their tables, figures and report)
and the ``report`` command (the per-fit figures drawn again)."""

from __future__ import annotations

import sys
from pathlib import Path

__all__ = ["cmd_study", "cmd_report"]


def _plan(args):
    """The quick or full plan with the command line's changes; CliError for a bad one."""
    from dataclasses import replace

    from ..study import full_plan, quick_plan
    from .status import CliError

    plan = quick_plan() if args.quick else full_plan()
    changes = {}
    if args.steps is not None and args.max_steps is not None:
        raise CliError("--steps fixes each chain's length and --max-steps caps a chain run until converged: "
                       "give one of them")
    if args.steps is not None:
        changes["steps"] = args.steps
    if args.max_steps is not None:  # until converged, also where the plan fixes the steps (quick)
        changes.update(steps=None, max_steps=args.max_steps)
    if args.seed is not None:
        changes["seed"] = args.seed
    if args.joint_steps is not None:
        changes["joint_steps"] = args.joint_steps
    if args.no_joint:
        changes["joint"] = False
    if args.tempering is not None:
        changes["tempering"] = args.tempering
    if args.sensor_uncertainty is not None:
        from ..records.sensitivity import SensorCalibration

        u_force, u_accel = args.sensor_uncertainty
        if not (u_force < 50 and u_accel < 50):
            raise CliError(f"--sensor-uncertainty takes two percentages from 0 to below 50, got {u_force:g} "
                           f"and {u_accel:g}")
        changes["calibration"] = SensorCalibration(force=u_force / 100, accel=u_accel / 100)
    if args.records:
        if not Path(args.records).is_dir():
            raise CliError(f"--records {args.records}: not a folder of CSV records")
        changes["records_dir"] = args.records
    if args.skip_check:
        changes["skip_checks"] = tuple(args.skip_check)
    if args.figures:
        changes["figures"] = True
    if args.identify is not None:
        changes["identify"] = args.identify
    return replace(plan, **changes)


class _StudyProgress:
    """A study's progress on stderr: a bar of its fits on a terminal, a line per fit
    otherwise (a log file); then a bar of the joint model's steps. Its methods are
    ``run_study``'s callbacks; each raises a Ctrl-C that came (``check_interrupt``)."""

    def __init__(self, name: str, out: Path, check_interrupt):
        from tqdm import tqdm

        self.name, self.out, self.check_interrupt = name, out, check_interrupt
        self.tty = sys.stderr.isatty()
        self.bar = tqdm(desc=f"study {name}", unit="fit", file=sys.stderr, disable=not self.tty)
        self.done = 0
        self.joint = None

    def on_jobs(self, n: int) -> None:
        self.bar.total = n
        self.bar.refresh()
        if not self.tty:
            print(f"study {self.name}: {n} fits into {self.out}", file=sys.stderr, flush=True)

    def on_done(self, outcome: dict) -> None:
        self.check_interrupt()
        self.bar.update(1)
        self.done += 1
        if outcome["status"] == "failed":
            self.bar.write(f"failed: {outcome['key']}: {outcome.get('error', '')}", file=sys.stderr)
        elif not self.tty:
            state = "reused" if outcome["status"] == "skipped" else (
                "converged" if outcome.get("converged") else "not converged")
            print(f"study {self.name}: fit {self.done} of {self.bar.total} done: {outcome['key']} ({state})",
                  file=sys.stderr, flush=True)

    def on_identified(self, name: str) -> None:
        self.check_interrupt()
        if self.joint is not None:
            self.joint.close()
            self.joint = None
        self.bar.close()
        print(f"study {self.name}: least squares of {name} done", file=sys.stderr, flush=True)

    def on_joint_step(self, iteration: int, target) -> None:
        from ..cli_progress import StepProgress

        if self.joint is None:
            self.bar.close()
            self.joint = StepProgress("joint model", total=target, check_interrupt=self.check_interrupt)
        self.joint.step(iteration, target)

    def close(self) -> None:
        self.bar.close()
        if self.joint is not None:
            self.joint.close()


def _say_result(result, out: Path) -> int:
    """Print the study's answer and what to know about its fits; the exit status."""
    from .status import EXIT_FAIL, EXIT_OK

    for row in result.tables["inertance"]:
        honest = ""
        if "b_honest_3%" in row:
            honest = (f"; honest {row['b_honest_3%']:.6g} to {row['b_honest_97%']:.6g}" if row["honest_identified"]
                      else "; honest: not identified")
        print(f"{row['setting']}: b = {row['b_median']:.6g} kg (94 % {row['b_hdi_3%']:.6g} to "
              f"{row['b_hdi_97%']:.6g}{honest}); theory {row['b_theory']:.6g}, paper {row['b_paper']:.6g}")
    reused = sum(o["status"] == "skipped" for o in result.outcomes)
    if reused:
        print(f"reused {reused} of {len(result.outcomes)} fits finished earlier in {out} "
              "(their chains were not sampled again; another --out samples every chain)")
    done = [o for o in result.outcomes if o["status"] != "failed"]
    n_conv = sum(bool(o.get("converged")) for o in done)
    if n_conv < len(done):
        print(f"warning: {len(done) - n_conv} of {len(done)} chains not converged; the report says which")
    print(f"wrote {result.report} and the tables and figures beside it ({result.seconds['total']:.0f} s)")
    failed = [o for o in result.outcomes if o["status"] == "failed"]
    if failed:
        print(f"error: {len(failed)} of {len(result.outcomes)} fits failed: "
              + ", ".join(o["key"] for o in failed), file=sys.stderr)
        return EXIT_FAIL
    return EXIT_OK


def cmd_study(args) -> int:
    import os

    from ..study import run_study
    from .status import check_interrupt

    plan = _plan(args)
    out = Path(args.out or Path("runs") / plan.name)
    processes = args.processes or min(2, os.cpu_count() or 1)
    progress = _StudyProgress(plan.name, out, check_interrupt)
    try:
        result = run_study(plan, out, processes=processes, scheduler=args.scheduler, on_done=progress.on_done,
                           on_jobs=progress.on_jobs, on_joint_step=progress.on_joint_step,
                           on_identified=progress.on_identified)
    finally:
        progress.close()
    return _say_result(result, out)


def cmd_report(args) -> int:
    from ..study.redraw import redraw_fits
    from .status import EXIT_FAIL, EXIT_OK

    done = redraw_fits(args.folder, on_fit=lambda folder, status: print(f"{folder}: {status}", flush=True))
    drawn = sum(status == "drawn" for _, status in done)
    print(f"drew the figures of {drawn} of {len(done)} fits")
    return EXIT_OK if drawn == len(done) else EXIT_FAIL
