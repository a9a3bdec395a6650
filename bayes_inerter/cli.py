"""The command line: ``bayes-inerter COMMAND ...``.

Exit status: 0 success; 1 bad input or a failed run (one-line error, no traceback);
2 usage error (argparse); 130 interrupted; 141 the output's reader closed the pipe.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

__all__ = ["main"]

EXIT_OK, EXIT_FAIL, EXIT_USAGE, EXIT_INTERRUPTED, EXIT_PIPE = 0, 1, 2, 130, 141


class CliError(Exception):
    """An error reported as one line on stderr with exit status 1."""


#: Set by Ctrl-C (:func:`_on_sigint`) for the rest of the command.
_INTERRUPTED = False


def _on_sigint(signum, frame):
    """Ctrl-C: remembered, then raised as KeyboardInterrupt. Python drops an exception
    raised while it runs a weakref callback or a ``__del__`` ("Exception ignored in ..."):
    a fit on two processes, interrupted there, once ran on to its last step and exit
    status 0. The commands' per-step callbacks raise it again (:func:`_check_interrupt`)."""
    global _INTERRUPTED
    _INTERRUPTED = True
    raise KeyboardInterrupt


def _check_interrupt() -> None:
    """Raise KeyboardInterrupt if Ctrl-C came, even if its first raise was dropped."""
    if _INTERRUPTED:
        raise KeyboardInterrupt


def _number_type(convert, ok, requirement: str, noun: str = "number"):
    """An argparse type: ``convert`` the text, then demand ``ok(value)``."""

    def parse(text: str):
        try:
            value = convert(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a {noun}") from None
        if not ok(value):
            raise argparse.ArgumentTypeError(f"{text!r} must be {requirement}")
        return value

    return parse


_positive_float = _number_type(float, lambda v: 0 < v < float("inf"), "a positive number")
_non_negative_float = _number_type(float, lambda v: 0 <= v < float("inf"), "a non-negative number")
_positive_int = _number_type(int, lambda v: v >= 1, "at least 1", "whole number")
#: ``inference.checkpoint.WRITE_SECONDS``, written out for the same reason as the
#: coordinates below; a test keeps the two equal.
CHECKPOINT_SECONDS = 0.5
#: ``inference.coordinates.COORDINATES``, written out so that the parser does not import
#: the inference package (emcee, arviz) before it is needed; a test keeps the two equal.
FIT_COORDINATES = ("impedance", "unconstrained", "physical")


def _add_generator_options(p: argparse.ArgumentParser) -> None:
    from .records.generator import GeneratorSettings

    d = GeneratorSettings()
    g = p.add_argument_group("generator settings (assumptions; see README)")
    g.add_argument("--amplitude", type=_positive_float, default=d.amplitude, help="drive amplitude, m (%(default)s)")
    g.add_argument("--fs", type=_positive_float, default=d.fs, help="record sampling rate, Hz (%(default)s)")
    g.add_argument("--duration", type=_positive_float, default=d.duration, help="record length with the ramp, s (%(default)s)")
    g.add_argument("--ramp", type=_non_negative_float, default=d.ramp, help="ramp-in time, s (%(default)s)")
    g.add_argument("--force-noise", type=_non_negative_float, default=d.force_noise, help="load-cell noise, N rms (%(default)s)")
    g.add_argument("--accel-noise", type=_non_negative_float, default=d.accel_noise, help="accelerometer noise, m/s^2 rms (%(default)s)")
    g.add_argument("--force-gain", type=_positive_float, default=d.force_gain,
                   help="load cell's true over nominal sensitivity: a calibration error (%(default)s)")
    g.add_argument("--accel-gain", type=_positive_float, default=d.accel_gain,
                   help="accelerometer's true over nominal sensitivity (%(default)s)")
    g.add_argument("--noise-corner", type=_positive_float, default=d.noise_corner,
                   help="colour the sensor noise: low-pass corner, Hz (default: white noise)")
    g.add_argument("--antialias", choices=("fir", "none"), default=d.antialias, help="anti-alias filter (%(default)s)")
    g.add_argument("--truth-network", choices=("reduced", "full"), default=d.network, help="truth network (%(default)s)")
    g.add_argument("--truth-friction", choices=("coulomb", "stribeck", "smooth"), default=d.friction, help="truth friction law (%(default)s)")
    g.add_argument("--backlash", type=_non_negative_float, default=d.backlash, help="nut backlash half-width, m (%(default)s)")
    g.add_argument("--seed", type=int, default=0, help="noise seed (%(default)s)")


#: ``records.checks.CHECKS``, written out so that the parser does not import numpy's
#: world before it is needed; a test keeps the two equal.
RECORD_CHECKS = ("time-unit", "flat", "clipped", "accel-vs-disp", "apparent-mass")


def _add_record_options(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("your record and device")
    g.add_argument("--columns", metavar="Q=NAME,...",
                   help="the file's columns: time=NAME,force=NAME,accel=NAME[,disp=NAME]; a quantity not named keeps "
                        "the project's name (time_s, force_N, accel_m_s2, disp_m); other columns are then ignored")
    g.add_argument("--units", metavar="Q=UNIT,...",
                   help="units of the file's columns: time s|ms, force N|kN|lbf, accel m/s^2|g|mm/s^2, disp m|mm "
                        "(default SI), e.g. time=ms,force=kN,accel=g")
    g.add_argument("--m-s", type=_positive_float, help="screw mass m_s, kg (else metadata, then --device)")
    g.add_argument("--m-b", type=_positive_float,
                   help="plate mass m_B, kg (else metadata, then --device, then the paper's 57.2)")
    g.add_argument("--device", metavar="DEVICE.toml", help="your device: masses and geometry (see README)")
    g.add_argument("--skip-check", action="append", default=[], choices=RECORD_CHECKS, metavar="CHECK",
                   help=f"skip a physical-sense check you know to be wrong for your record ({', '.join(RECORD_CHECKS)})")


def _settings_from(args):
    from .records.generator import GeneratorSettings

    return GeneratorSettings(
        amplitude=args.amplitude, fs=args.fs, duration=args.duration, ramp=args.ramp,
        force_noise=args.force_noise, accel_noise=args.accel_noise, noise_corner=args.noise_corner,
        force_gain=args.force_gain, accel_gain=args.accel_gain,
        antialias=args.antialias, network=args.truth_network, friction=args.truth_friction, backlash=args.backlash,
    )


def _progress(iterable, total, desc):
    from tqdm import tqdm

    return tqdm(iterable, total=total, desc=desc, unit="record", file=sys.stderr, disable=None)


def cmd_generate(args) -> int:
    from .device import FREQUENCIES_HZ, SETTINGS, paper_parameters
    from .records import generate_record, paper_grid, write_record

    settings = _settings_from(args)
    out = Path(args.out)
    if args.paper_grid:
        if out.suffix.lower() == ".csv":
            raise CliError(f"--paper-grid writes a folder of records; {out} looks like a file name")
        total = len(SETTINGS) * len(FREQUENCIES_HZ)
        for name, freq, rec in _progress(paper_grid(settings=settings, seed=args.seed), total, "generating"):
            path, _ = write_record(out / f"{name}_{freq:g}Hz.csv", rec)
            print(f"wrote {path}")
        return EXIT_OK
    if args.setting is None or args.freq is None:
        raise CliError("give --setting and --freq for one record, or --paper-grid for all 27")
    if out.suffix.lower() != ".csv":
        raise CliError(f"--out must name a .csv file for one record, got {out}")
    rec = generate_record(
        paper_parameters(args.setting), args.freq, settings=settings, rng=args.seed,
        setting_name=args.setting.upper(),
    )
    path, side = write_record(out, rec)
    print(f"wrote {path} ({len(rec.time)} samples, {rec.duration:g} s at {rec.fs:g} Hz) and {side}")
    return EXIT_OK


def _load_record(args, *, need_masses: bool):
    """The record of ``args`` (read with --columns and --units), its device file, its
    masses (None when m_s is unknown and not ``need_masses``), checked for physical
    sense (--skip-check)."""
    from .device_file import read_device
    from .masses import resolve_masses
    from .records import read_record
    from .records.checks import b_range_for, require_physical

    rec = read_record(args.record, columns=args.columns, units=args.units)
    device = read_device(args.device) if args.device else None
    try:
        masses = resolve_masses(rec, m_s=args.m_s, m_B=args.m_b, device=device)
    except ValueError:
        if need_masses:
            raise
        masses = None
    require_physical(rec, m_s=masses and masses.m_s, m_B=masses and masses.m_B, b_range=b_range_for(rec, device),
                     skip=tuple(args.skip_check), where=args.record)
    return rec, device, masses


def cmd_inspect(args) -> int:
    import math

    from .records import write_record
    from .records.checks import drive_frequency, fundamental

    rec, device, masses = _load_record(args, need_masses=False)
    print(f"{args.record}: valid record")
    print(f"  samples {len(rec.time)}, duration {rec.duration:g} s, rate {rec.fs:g} Hz")
    for name, x, unit in (("force", rec.force, "N"), ("accel", rec.accel, "m/s^2"), ("disp", rec.disp, "m")):
        if x is not None:
            print(f"  {name:6s} min {x.min():.6g} {unit}, max {x.max():.6g} {unit}, rms {x.std():.6g} {unit}")
    freq = drive_frequency(rec)
    z = fundamental(rec.time, rec.force, freq) / fundamental(rec.time, rec.accel, freq)
    source = "metadata" if rec.drive_frequency is not None else "from the spectrum"
    # F/a = M + iD at the drive: M the inertial mass; F/v = i omega F/a, whose real part
    # -omega D is the resistance (friction and damping, positive for a dissipating device)
    print(f"  drive {freq:.4g} Hz ({source}); at it, inertial mass Re(F/a) {z.real:.5g} kg, "
          f"resistance Re(F/v) {-z.imag * 2 * math.pi * freq:.5g} N s/m")
    print("  physical-sense checks: passed" + (f" (skipped: {', '.join(args.skip_check)})" if args.skip_check else ""))
    print(f"  masses: {masses.describe()}" if masses else
          "  masses: m_s unknown (give --m-s, a --device file, or m_s or setting in the metadata when fitting)")
    if device is not None and device.theoretical_inertance is not None:
        print(f"  theoretical inertance (device file): {device.theoretical_inertance:.6g} kg")
    shown = {k: v for k, v in rec.metadata.items() if k not in ("true_parameters", "generator")}
    for key, value in shown.items():
        text = json.dumps(value) if isinstance(value, (dict, list)) else str(value)
        print(f"  {key}: {text}")
    if not rec.metadata:
        print("  no metadata (give m_s or the setting when fitting)")
    if args.normalise:
        path, side = write_record(args.normalise, rec)
        print(f"wrote {path} and {side} (SI units, the project's columns)")
    if args.plot:
        import matplotlib.pyplot as plt

        from .plots import plot_record

        fig = plot_record(rec)
        try:
            Path(args.plot).parent.mkdir(parents=True, exist_ok=True)
            fig.savefig(args.plot, dpi=120)
        finally:
            plt.close(fig)  # main() may run again in the same process
        print(f"wrote {args.plot}")
    return EXIT_OK


def _percent_interval(lo: float, hi: float) -> str:
    """'lo % to hi %' with the fewest decimals (2 to 8) that tell the two apart."""
    for d in range(2, 9):
        a, b = f"{lo * 100:.{d}f}", f"{hi * 100:.{d}f}"
        if a != b:
            break
    return f"{a} % to {b} %"


def cmd_fit(args) -> int:
    import os

    from .cli_progress import StepProgress
    from .inference import fit_record
    from .inference.coordinates import EDGE_WARNING, MAX_SENSITIVITY_CHANGE
    from .inference.model import LikelihoodSettings
    from .inference.sampler import Adaptation

    # refused here, before the output folder is touched
    rec, device, masses = _load_record(args, need_masses=True)
    print(f"masses: {masses.describe()}", flush=True)
    bar = StepProgress("sampling", total=args.steps, check_interrupt=_check_interrupt)
    processes = args.processes or min(2, os.cpu_count() or 1)
    try:
        result = fit_record(
            rec, args.out, model=args.model, m_s=args.m_s, m_B=args.m_b, device=device, walkers=args.walkers,
            steps=args.steps, seed=args.seed, fresh=args.fresh, processes=processes,
            likelihood=LikelihoodSettings(residual=args.residual, upsample=args.upsample), progress=bar.step,
            report=bar.status, coordinates=args.coordinates, adaptation=None if args.no_adaptation else Adaptation(),
            checkpoint_seconds=args.checkpoint_seconds, plots=not args.no_plots,
        )
    finally:
        bar.close()
    if result.recovered:
        print(f"note: checkpoint damaged, recovered: {result.recovered}")
    b = result.row("b")
    print(f"b = {b['mean']:.6g} kg (94 % HDI {b['hdi_3%']:.6g} to {b['hdi_97%']:.6g}), "
          f"{result.iterations} steps")
    if result.b_theory is not None:
        print(f"theory (device file geometry): b = {result.b_theory:.6g} kg "
              f"({(b['mean'] - result.b_theory) / result.b_theory:+.1%} identified against it)")
    phi = result.row("phi")
    print(f"phi = {phi['mean']:.2%} (94 % HDI {_percent_interval(phi['hdi_3%'], phi['hdi_97%'])})")
    for w in result.warnings:
        print(f"warning: {w.message}")
    edge = json.loads((Path(args.out) / "fit.json").read_text()).get("coordinates_domain_edge")
    if edge is not None and edge > EDGE_WARNING:
        print(f"warning: the posterior reaches |dZ/dZ_theta - 1| = {edge:.2f}, near the edge of the impedance "
              f"coordinates' domain ({MAX_SENSITIVITY_CHANGE:g}), which may cut it; compare with "
              "--coordinates unconstrained")
    if result.converged:
        print("converged")
    else:
        print(f"warning: {result.reason}; do not trust these intervals yet "
              "(run again with more --steps, or without --steps)")
    figures = "" if args.no_plots else "corner.png, bands.png, trace.png, phi.png, "
    print(f"wrote {args.out}/summary.csv, posterior.nc, loo.json, chain.h5 (and its twin), {figures}fit.json")
    return EXIT_OK


def cmd_study(args) -> int:
    import os
    from dataclasses import replace

    from tqdm import tqdm

    from .cli_progress import StepProgress
    from .study import full_plan, quick_plan, run_study

    plan = quick_plan() if args.quick else full_plan()
    changes = {}
    if args.steps is not None:
        changes["steps"] = args.steps
    if args.seed is not None:
        changes["seed"] = args.seed
    if args.joint_steps is not None:
        changes["joint_steps"] = args.joint_steps
    if args.no_joint:
        changes["joint"] = False
    if args.sensor_uncertainty is not None:
        from .records.sensitivity import SensorCalibration

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
    plan = replace(plan, **changes)
    out = Path(args.out or Path("runs") / plan.name)
    processes = args.processes or min(2, os.cpu_count() or 1)
    tty = sys.stderr.isatty()
    bar = tqdm(desc=f"study {plan.name}", unit="fit", file=sys.stderr, disable=not tty)
    done_fits = []

    def on_jobs(n):
        bar.total = n
        bar.refresh()
        if not tty:
            print(f"study {plan.name}: {n} fits into {out}", file=sys.stderr, flush=True)

    def on_done(outcome):
        _check_interrupt()
        bar.update(1)
        done_fits.append(outcome)
        if outcome["status"] == "failed":
            bar.write(f"failed: {outcome['key']}: {outcome.get('error', '')}", file=sys.stderr)
        elif not tty:
            state = "reused" if outcome["status"] == "skipped" else (
                "converged" if outcome.get("converged") else "not converged")
            print(f"study {plan.name}: fit {len(done_fits)} of {bar.total} done: {outcome['key']} ({state})",
                  file=sys.stderr, flush=True)

    joint_bar = []

    def on_joint_step(iteration, target):
        if not joint_bar:
            bar.close()
            joint_bar.append(StepProgress("joint model", total=target, check_interrupt=_check_interrupt))
        joint_bar[0].step(iteration, target)

    try:
        result = run_study(plan, out, processes=processes, scheduler=args.scheduler, on_done=on_done,
                           on_jobs=on_jobs, on_joint_step=on_joint_step)
    finally:
        bar.close()
        for jb in joint_bar:
            jb.close()
    for row in result.tables["inertance"]:
        print(f"{row['setting']}: b = {row['b_median']:.6g} kg (94 % {row['b_hdi_3%']:.6g} to "
              f"{row['b_hdi_97%']:.6g}); theory {row['b_theory']:.6g}, paper {row['b_paper']:.6g}")
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


def cmd_report(args) -> int:
    from .study.redraw import redraw_fits

    done = redraw_fits(args.folder, on_fit=lambda folder, status: print(f"{folder}: {status}", flush=True))
    drawn = sum(status == "drawn" for _, status in done)
    print(f"drew the figures of {drawn} of {len(done)} fits")
    return EXIT_OK if drawn == len(done) else EXIT_FAIL


def cmd_demo(args) -> int:
    from .demo import run_demo

    for path in run_demo(Path(args.out), setting=args.setting, freq=args.freq, seed=args.seed):
        print(f"wrote {path}")
    return EXIT_OK


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="bayes-inerter",
        description="Bayesian uncertainty quantification of a ball-screw inerter.",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    p = sub.add_parser("demo", help="simulate a generated paper record with the paper's networks and plot it")
    p.add_argument("--setting", default="A1", help="flywheel setting (%(default)s)")
    p.add_argument("--freq", type=_positive_float, default=1.0, help="drive frequency, Hz (%(default)s)")
    p.add_argument("--seed", type=int, default=0, help="noise seed (%(default)s)")
    p.add_argument("--out", default="runs/demo", help="output folder (%(default)s)")
    p.set_defaults(func=cmd_demo)

    p = sub.add_parser("generate", help="generate records of the paper's protocol")
    p.add_argument("--setting", help="flywheel setting A0..A6, B1, B2")
    p.add_argument("--freq", type=_positive_float, help="drive frequency, Hz")
    p.add_argument("--paper-grid", action="store_true", help="all 27 records of the paper into --out (a folder)")
    p.add_argument("--out", required=True, help="record file (.csv), or folder with --paper-grid")
    _add_generator_options(p)
    p.set_defaults(func=cmd_generate)

    p = sub.add_parser("fit", help="sample the posterior of one record with emcee")
    p.add_argument("record", help="record CSV file")
    p.add_argument("--out", required=True, help="output folder (a checkpoint there is continued)")
    _add_record_options(p)
    p.add_argument("--model", choices=("two-port", "rigid", "linear"), default="two-port", help="model (%(default)s)")
    p.add_argument("--walkers", type=_positive_int, help="walkers (default 2 x parameters + 2)")
    p.add_argument("--steps", type=_positive_int, help="total steps (default: until converged)")
    p.add_argument("--seed", type=int, default=0, help="seed (%(default)s)")
    p.add_argument("--residual", choices=("ar1", "iid"), default="ar1", help="residual model (%(default)s)")
    p.add_argument("--upsample", type=_positive_int, default=1,
                   help="force reconstruction rate / record rate before simulating (%(default)s: linear interpolation)")
    p.add_argument("--processes", type=_positive_int, help="worker processes (default: up to 2)")
    p.add_argument("--fresh", action="store_true", help="start over instead of continuing the checkpoint")
    p.add_argument("--coordinates", choices=FIT_COORDINATES, default="impedance",
                   help="where the walkers move (%(default)s; the outputs are the same parameters either way)")
    p.add_argument("--no-adaptation", action="store_true",
                   help="emcee's ensemble moves alone, without the independence move fitted to the chain")
    p.add_argument("--no-plots", action="store_true", help="write no figures (they take several seconds)")
    p.add_argument("--checkpoint-seconds", type=_non_negative_float, default=CHECKPOINT_SECONDS,
                   help="write the chain's steps at most this many seconds apart (%(default)s; 0: every step): "
                        "a kill loses at most that much sampling")
    p.set_defaults(func=cmd_fit)

    p = sub.add_parser("study", help="posteriors of many records, theory against identification, a report")
    p.add_argument("--quick", action="store_true",
                   help="the quick study: 3 settings at 1 Hz, short chains (minutes, not converged)")
    p.add_argument("--out", help="output folder (default runs/quick or runs/full); finished fits there are reused")
    p.add_argument("--skip-check", action="append", default=[], choices=RECORD_CHECKS, metavar="CHECK",
                   help="with --records: skip a physical-sense check of your records")
    p.add_argument("--figures", action="store_true",
                   help="each fit draws its figures as it ends (default: later, by bayes-inerter report DIR)")
    p.add_argument("--records", help="a folder of your CSV records to fit instead of generated ones")
    p.add_argument("--steps", type=_positive_int, help="steps per chain (default: the plan's; full: until converged)")
    p.add_argument("--seed", type=int, help="seed of the generated records' noise and of the chains (0)")
    p.add_argument("--joint-steps", type=_positive_int,
                   help="steps of the joint model's chain (full study; default: until converged)")
    p.add_argument("--no-joint", action="store_true", help="skip the joint model of all records")
    p.add_argument("--sensor-uncertainty", type=_non_negative_float, nargs=2, metavar=("FORCE_%", "ACCEL_%"),
                   help="relative standard uncertainty of the load cell's and accelerometer's sensitivities, "
                        "percent, added to b in the b_cal columns (default 0.25 0.5; 0 0: exact sensors)")
    p.add_argument("--processes", type=_positive_int, help="local worker processes, one fit each (default: up to 2)")
    p.add_argument("--scheduler", help="run the fits on this Dask scheduler (tcp://host:port) instead")
    p.set_defaults(func=cmd_study)

    p = sub.add_parser("report", help="draw a study's per-fit figures again from the fits' checkpoints")
    p.add_argument("folder", help="a study's folder (or one fit's folder in it)")
    p.set_defaults(func=cmd_report)

    p = sub.add_parser("inspect", help="validate a record, check its physical sense and print its summary")
    p.add_argument("record", help="record CSV file")
    _add_record_options(p)
    p.add_argument("--normalise", metavar="OUT.csv",
                   help="write the record in the project's format (SI units, its columns) to OUT.csv")
    p.add_argument("--plot", help="also plot the record into this PNG file")
    p.set_defaults(func=cmd_inspect)
    return parser


def main(argv=None) -> int:
    import signal
    import threading

    global _INTERRUPTED
    parser = build_parser()
    args = parser.parse_args(argv)
    _INTERRUPTED = False
    # Ctrl-C's own handler, where Python's default one is in place (not where SIGINT is
    # ignored, as in a background job, nor off the main thread); restored on the way out
    previous = signal.getsignal(signal.SIGINT)
    ours = previous is signal.default_int_handler and threading.current_thread() is threading.main_thread()
    if ours:
        signal.signal(signal.SIGINT, _on_sigint)
    import warnings

    import numpy as np

    # library warnings that mean nothing to a user (arviz's FutureWarning on import,
    # numpy's on an overflow the code handles); the commands say what matters in words
    try:
        import logging

        logging.getLogger("arviz").setLevel(logging.ERROR)  # shape warnings of short chains, said in words
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.filterwarnings("ignore", category=FutureWarning)
            warnings.filterwarnings("ignore", category=RuntimeWarning)
            code = args.func(args)
        if _INTERRUPTED:  # came where it could only be dropped, and nothing asked again
            raise KeyboardInterrupt
        return code
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:  # the reader went away (| head): nothing more to say, to anyone
        import os

        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_PIPE
    except (CliError, ValueError, OSError, RuntimeError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_FAIL
    finally:
        if ours:
            signal.signal(signal.SIGINT, previous)


if __name__ == "__main__":
    sys.exit(main())
