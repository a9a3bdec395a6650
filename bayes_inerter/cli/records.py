"""The commands about records: ``generate``, ``inspect`` and ``demo``."""

from __future__ import annotations

import json
import sys
from pathlib import Path

__all__ = ["cmd_generate", "cmd_inspect", "cmd_demo", "load_record"]


def _settings_from(args):
    from ..records.generator import GeneratorSettings

    return GeneratorSettings(
        amplitude=args.amplitude, fs=args.fs, duration=args.duration, ramp=args.ramp,
        force_noise=args.force_noise, accel_noise=args.accel_noise, noise_corner=args.noise_corner,
        force_gain=args.force_gain, accel_gain=args.accel_gain,
        antialias=args.antialias, network=args.truth_network, friction=args.truth_friction, backlash=args.backlash,
    )


def _paper_like(settings):
    """The paper-like device, with the record's length and rate from ``settings``."""
    import dataclasses

    from ..records.generator import GeneratorSettings
    from ..records.paper_like import PaperLike

    base = dataclasses.replace(GeneratorSettings(), amplitude=settings.amplitude, fs=settings.fs,
                               duration=settings.duration, ramp=settings.ramp)
    return PaperLike(base=base)


def _progress(iterable, total, desc):
    from tqdm import tqdm

    return tqdm(iterable, total=total, desc=desc, unit="record", file=sys.stderr, disable=None)


def cmd_generate(args) -> int:
    from ..device import FREQUENCIES_HZ, SETTINGS, paper_parameters
    from ..records import generate_record, paper_grid, write_record
    from ..records.paper_like import paper_like_grid, paper_like_record
    from .status import EXIT_OK, CliError

    settings = _settings_from(args)
    device = _paper_like(settings) if args.truth == "paper-like" else None
    out = Path(args.out)
    if args.paper_grid:
        if out.suffix.lower() == ".csv":
            raise CliError(f"--paper-grid writes a folder of records; {out} looks like a file name")
        total = len(SETTINGS) * len(FREQUENCIES_HZ)
        grid = (paper_grid(settings=settings, seed=args.seed) if device is None else
                paper_like_grid(seed=args.seed, device=device))
        for name, freq, rec in _progress(grid, total, "generating"):
            path, _ = write_record(out / f"{name}_{freq:g}Hz.csv", rec)
            print(f"wrote {path}")
        return EXIT_OK
    if args.setting is None or args.freq is None:
        raise CliError("give --setting and --freq for one record, or --paper-grid for all 27")
    if out.suffix.lower() != ".csv":
        raise CliError(f"--out must name a .csv file for one record, got {out}")
    if device is not None:
        try:
            rec = paper_like_record(args.setting.upper(), args.freq, seed=args.seed, device=device)
        except ValueError as exc:
            raise CliError(f"{exc}: a paper-like record is one of the paper's settings at 0.5, 1 or 1.5 Hz") from None
    else:
        rec = generate_record(paper_parameters(args.setting), args.freq, settings=settings, rng=args.seed,
                              setting_name=args.setting.upper())
    path, side = write_record(out, rec)
    print(f"wrote {path} ({len(rec.time)} samples, {rec.duration:g} s at {rec.fs:g} Hz) and {side}")
    return EXIT_OK


def load_record(args, *, need_masses: bool):
    """The record of ``args`` (read with --columns and --units), its device file, its
    masses (None when m_s is unknown and not ``need_masses``) and its drive frequency
    (``records.drive.DriveFrequency``: --freq, else the metadata's, else estimated; the
    record returned holds it in its metadata), checked for physical sense
    (--skip-check). What ``inspect``, ``identify`` and ``fit`` start from."""
    from ..device_file import read_device
    from ..masses import resolve_masses
    from ..records import read_record
    from ..records.checks import b_range_for, require_physical
    from ..records.drive import resolve_drive, with_drive

    rec = read_record(args.record, columns=args.columns, units=args.units)
    if args.freq is not None:  # the checks look at the drive the user names
        rec = with_drive(rec, resolve_drive(rec, args.freq))
    device = read_device(args.device) if args.device else None
    try:
        masses = resolve_masses(rec, m_s=args.m_s, m_B=args.m_b, device=device)
    except ValueError:
        if need_masses:
            raise
        masses = None
    require_physical(rec, m_s=masses and masses.m_s, m_B=masses and masses.m_B, b_range=b_range_for(rec, device),
                     skip=tuple(args.skip_check), where=args.record)
    try:
        drive = resolve_drive(rec)
    except ValueError as exc:
        from .status import CliError

        raise CliError(str(exc)) from None
    return with_drive(rec, drive), device, masses, drive


def cmd_inspect(args) -> int:
    import math

    from ..records import write_record
    from ..records.checks import fundamental
    from ..records.drive import SOURCE_KEY
    from .status import EXIT_OK

    rec, device, masses, drive = load_record(args, need_masses=False)
    print(f"{args.record}: valid record")
    print(f"  samples {len(rec.time)}, duration {rec.duration:g} s, rate {rec.fs:g} Hz")
    for name, x, unit in (("force", rec.force, "N"), ("accel", rec.accel, "m/s^2"), ("disp", rec.disp, "m")):
        if x is not None:
            print(f"  {name:6s} min {x.min():.6g} {unit}, max {x.max():.6g} {unit}, rms {x.std():.6g} {unit}")
    freq = drive.hz
    z = fundamental(rec.time, rec.force, freq) / fundamental(rec.time, rec.accel, freq)
    # F/a = M + iD at the drive: M the inertial mass; F/v = i omega F/a, whose real part
    # -omega D is the resistance (friction and damping, positive for a dissipating device)
    print(f"  drive {drive.describe()}; at it, inertial mass Re(F/a) {z.real:.5g} kg, "
          f"resistance Re(F/v) {-z.imag * 2 * math.pi * freq:.5g} N s/m")
    print("  physical-sense checks: passed" + (f" (skipped: {', '.join(args.skip_check)})" if args.skip_check else ""))
    print(f"  masses: {masses.describe()}" if masses else
          "  masses: m_s unknown (give --m-s, a --device file, or m_s or setting in the metadata when fitting)")
    if device is not None and device.theoretical_inertance is not None:
        print(f"  theoretical inertance (device file): {device.theoretical_inertance:.6g} kg")
    # the file's own metadata: not the drive frequency this command settled (printed above)
    hidden = {"true_parameters", "generator", SOURCE_KEY}
    if not drive.source.startswith("record metadata"):
        hidden.add("drive_frequency_hz")
    shown = {k: v for k, v in rec.metadata.items() if k not in hidden}
    for key, value in shown.items():
        text = json.dumps(value) if isinstance(value, (dict, list)) else str(value)
        print(f"  {key}: {text}")
    if not shown:
        print("  no metadata (give m_s or the setting when fitting)")
    if args.normalise:
        path, side = write_record(args.normalise, rec)
        print(f"wrote {path} and {side} (SI units, the project's columns)")
    if args.plot:
        _plot_record(rec, Path(args.plot))
        print(f"wrote {args.plot}")
    return EXIT_OK


def _plot_record(rec, path: Path) -> None:
    """The record's figure into the PNG file ``path``; the figure closed (``main`` may
    run again in the same process)."""
    from ..plots import plot_record  # first: it sets the Agg backend

    import matplotlib.pyplot as plt

    fig = plot_record(rec)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fig.savefig(path, dpi=120)
    finally:
        plt.close(fig)


def cmd_demo(args) -> int:
    from ..demo import run_demo
    from .status import EXIT_OK

    for path in run_demo(Path(args.out), setting=args.setting, freq=args.freq, seed=args.seed):
        print(f"wrote {path}")
    return EXIT_OK
