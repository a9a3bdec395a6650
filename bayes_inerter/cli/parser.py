"""The command line's parser: every command's options, their types and help.

It imports no numerical package (numpy's world, emcee, arviz) before a command runs:
the lists of choices that live in the library are written out here, each kept equal
to the library's by a test.
"""

from __future__ import annotations

import argparse

__all__ = ["build_parser", "CHECKPOINT_SECONDS", "FIT_COORDINATES", "FIT_RESIDUALS", "RECORD_CHECKS",
           "BLOCK_PARTNERS", "DEFAULT_BLOCK_PARTNERS"]


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
_non_negative_int = _number_type(int, lambda v: v >= 0, "0 or more", "whole number")
_at_least_two = _number_type(int, lambda v: v >= 2, "at least 2", "whole number")
_open_unit = _number_type(float, lambda v: 0 < v < 1, "between 0 and 1 (both left out)")
#: ``inference.sampling.checkpoint.WRITE_SECONDS``, written out for the same reason as the
#: coordinates below; a test keeps the two equal.
CHECKPOINT_SECONDS = 2.0
#: ``inference.sampling.coordinates.COORDINATES``, written out so that the parser does not import
#: the inference package (emcee, arviz) before it is needed; a test keeps the two equal.
FIT_COORDINATES = ("impedance", "unconstrained", "physical", "series", "compliance")
#: ``inference.posterior.likelihood.RESIDUALS`` and its default, written out likewise.
FIT_RESIDUALS = ("ar1", "iid", "harmonic", "motion")
DEFAULT_RESIDUAL = "motion"
#: ``inference.sampling.moves.block.PARTNERS`` and ``Adaptation``'s default, written out likewise.
BLOCK_PARTNERS = ("random", "correlated")
DEFAULT_BLOCK_PARTNERS = "random"


def _add_generator_options(p: argparse.ArgumentParser) -> None:
    from ..records.generator import GeneratorSettings

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


#: ``inference.posterior.model.MODELS``, written out so that the parser does not import numpy's
#: world before it is needed; a test keeps the two equal.
FIT_MODELS = ("two-port", "rigid", "linear", "two-port-stribeck", "two-port-backlash", "two-port-rich")

#: ``inference.summaries.interval.INTERVALS``, written out likewise; a test keeps the two equal.
FIT_INTERVALS = ("honest", "posterior")

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
    g.add_argument("--freq", type=_positive_float,
                   help="drive frequency, Hz (else the metadata's drive_frequency_hz, else estimated from the record)")
    g.add_argument("--skip-check", action="append", default=[], choices=RECORD_CHECKS, metavar="CHECK",
                   help=f"skip a physical-sense check you know to be wrong for your record ({', '.join(RECORD_CHECKS)})")


def _add_demo(sub) -> argparse.ArgumentParser:
    p = sub.add_parser("demo", help="simulate a generated paper record with the paper's networks and plot it")
    p.add_argument("--setting", default="A1", help="flywheel setting (%(default)s)")
    p.add_argument("--freq", type=_positive_float, default=1.0, help="drive frequency, Hz (%(default)s)")
    p.add_argument("--seed", type=int, default=0, help="noise seed (%(default)s)")
    p.add_argument("--out", default="runs/demo", help="output folder (%(default)s)")
    return p


def _add_generate(sub) -> argparse.ArgumentParser:
    p = sub.add_parser("generate", help="generate records of the paper's protocol")
    p.add_argument("--setting", help="flywheel setting A0..A6, B1, B2")
    p.add_argument("--freq", type=_positive_float, help="drive frequency, Hz")
    p.add_argument("--paper-grid", action="store_true", help="all 27 records of the paper into --out (a folder)")
    p.add_argument("--out", required=True, help="record file (.csv), or folder with --paper-grid")
    p.add_argument("--truth", choices=("model", "paper-like"), default="model",
                   help="model: the device as the generator settings below say (default); paper-like: a richer "
                        "device drawn per record (records.paper_like: full network, Stribeck, backlash, "
                        "calibration errors, coloured noise; --amplitude, --fs, --duration, --ramp still apply)")
    _add_generator_options(p)
    return p


def _add_fit(sub) -> argparse.ArgumentParser:
    p = sub.add_parser("fit", help="sample the posterior of one record with emcee")
    p.add_argument("record", help="record CSV file")
    p.add_argument("--out", required=True, help="output folder (a checkpoint there is continued)")
    _add_record_options(p)
    p.add_argument("--model", choices=FIT_MODELS + ("compare",), default="two-port",
                   help="model (%(default)s); two-port-stribeck, -backlash and -rich add Stribeck friction, nut "
                        "backlash or both; compare fits every model the likelihood knows, each into --out/<model>, "
                        "and compares them by LOO with b stacked over them (docs/inference.md)")
    p.add_argument("--interval", choices=FIT_INTERVALS, default=None,
                   help="b's reported interval: honest widens the posterior's by the sensors' calibration and the "
                        "model discrepancy the record shows; posterior is the posterior's alone (default: posterior "
                        "for the harmonic and motion likelihoods, whose posterior holds both, honest for ar1 and "
                        "iid; docs/inference.md)")
    p.add_argument("--walkers", type=_positive_int, help="walkers (default 2 x parameters + 2)")
    p.add_argument("--steps", type=_positive_int, help="total steps (default: until converged)")
    p.add_argument("--max-steps", type=_positive_int,
                   help="until converged, but at most this many steps in all (default 20000, 10000 tempered; "
                        "a checkpoint is continued)")
    p.add_argument("--seed", type=int, default=0, help="seed (%(default)s)")
    p.add_argument("--residual", choices=FIT_RESIDUALS, default=DEFAULT_RESIDUAL,
                   help="likelihood (%(default)s): ar1 or iid, the low-passed acceleration sample by sample; "
                        "harmonic, the acceleration at the drive's harmonics; motion, the force at the drive's "
                        "harmonics given the measured motion (docs/inference.md)")
    p.add_argument("--upsample", type=_positive_int, default=1,
                   help="force reconstruction rate / record rate before simulating (%(default)s: linear interpolation)")
    p.add_argument("--delay-sd", type=float, default=None, metavar="SECONDS",
                   help="motion likelihood: the prior sd of the force channel's delay behind the accelerometer's, "
                        "s (default 0.0005; 0: the channels taken as simultaneous)")
    p.add_argument("--form-sd", type=_non_negative_float, default=0.0, metavar="FRACTION",
                   help="motion likelihood: b's model-form uncertainty, a relative sd marginalised inside the "
                        "likelihood (default 0: none; 0.005 for 0.5 %%, docs/inference.md)")
    p.add_argument("--form-friction", type=_non_negative_float, default=0.0, metavar="SHARE",
                   help="motion likelihood: a model-form error of the inertial force at the fundamental, this "
                        "share of the Coulomb force (default 0: none; docs/inference.md)")
    p.add_argument("--processes", type=_positive_int, help="worker processes (default: up to 2)")
    p.add_argument("--fresh", action="store_true", help="start over instead of continuing the checkpoint")
    p.add_argument("--coordinates", choices=FIT_COORDINATES, default="impedance",
                   help="where the walkers move (%(default)s; the outputs are the same parameters either way)")
    p.add_argument("--no-adaptation", action="store_true",
                   help="emcee's ensemble moves alone, without the independence move fitted to the chain")
    p.add_argument("--block-partners", choices=BLOCK_PARTNERS, default=DEFAULT_BLOCK_PARTNERS,
                   help="how the fitted block moves pick their coordinates (%(default)s; correlated: a coordinate "
                        "and its most correlated partners)")
    p.add_argument("--tempering", type=_at_least_two, metavar="TEMPS",
                   help="parallel tempering with this many temperatures (default: none; 4 is the ladder "
                        "measured); each step costs TEMPS times the evaluations, hot copies of the posterior carry "
                        "the walkers between its humps, and the chain converges only once its replicas have mixed "
                        "(docs/inference.md)")
    p.add_argument("--hottest-beta", type=_open_unit, metavar="BETA",
                   help="the tempering ladder's hottest copy's power of the likelihood, in (0, 1) (default 0.1; "
                        "alone, it asks for 4 temperatures)")
    p.add_argument("--no-tempering", action="store_true",
                   help="the posterior's ensemble alone, without tempering (the default; kept for scripts "
                        "that ask for it)")
    p.add_argument("--no-plots", action="store_true", help="write no figures (they take several seconds)")
    p.add_argument("--checkpoint-seconds", type=_non_negative_float, default=CHECKPOINT_SECONDS,
                   help="write the chain's steps at most this many seconds apart (%(default)s; 0: every step): "
                        "a kill loses at most that much sampling")
    return p


def _add_identify(sub) -> argparse.ArgumentParser:
    p = sub.add_parser("identify", help="the paper's least-squares fit of one record (eq. 4) with phi and b's interval")
    p.add_argument("record", help="record CSV file")
    _add_record_options(p)
    p.add_argument("--model", choices=FIT_MODELS, default="two-port", help="model (%(default)s)")
    p.add_argument("--starts", type=_positive_int, default=4,
                   help="least-squares starts: the quick optimum's and Sobol points in the priors' box (%(default)s)")
    p.add_argument("--bootstrap", type=_non_negative_int, default=0, metavar="N",
                   help="b's interval from N refits on the record's residual cycles drawn again (seconds each; "
                        "50 or more) instead of the cycle-clustered Hessian (default)")
    p.add_argument("--seed", type=int, default=0, help="seed of the starts and the bootstrap (%(default)s)")
    p.add_argument("--out", metavar="FILE.json", help="also write the fit to this JSON file")
    return p


def _add_study(sub) -> argparse.ArgumentParser:
    p = sub.add_parser("study", help="posteriors of many records, theory against identification, a report")
    p.add_argument("--quick", action="store_true",
                   help="the quick study: 3 settings at 1 Hz, short chains (about a minute, not converged)")
    p.add_argument("--out", help="output folder (default runs/quick or runs/full); finished fits there are reused")
    p.add_argument("--skip-check", action="append", default=[], choices=RECORD_CHECKS, metavar="CHECK",
                   help="with --records: skip a physical-sense check of your records")
    p.add_argument("--figures", action="store_true",
                   help="each fit draws its figures as it ends (default: later, by bayes-inerter report DIR)")
    p.add_argument("--records", help="a folder of your CSV records to fit instead of generated ones")
    p.add_argument("--steps", type=_positive_int, help="steps per chain (default: the plan's; full: until converged)")
    p.add_argument("--max-steps", type=_positive_int,
                   help="each record's chain until converged, but at most this many steps (default: fit's, 20000, "
                        "10000 tempered)")
    p.add_argument("--seed", type=int, help="seed of the generated records' noise and of the chains (0)")
    p.add_argument("--joint-steps", type=_positive_int,
                   help="steps of the joint model's chain (full study; default: until converged)")
    p.add_argument("--no-joint", action="store_true", help="skip the joint model of all records")
    p.add_argument("--tempering", type=_at_least_two, metavar="TEMPS",
                   help="fit each record with parallel tempering of this many temperatures (default: none, as "
                        "fit, and results/full; the joint model is not tempered)")
    p.add_argument("--identify", action=argparse.BooleanOptionalAction, default=None,
                   help="also fit every record by the paper's least squares (eq. 4; about 20 s a 10 s record on one core) and set it "
                        "beside the posterior in least_squares.csv (default: full study yes, quick no)")
    p.add_argument("--sensor-uncertainty", type=_non_negative_float, nargs=2, metavar=("FORCE_%", "ACCEL_%"),
                   help="relative standard uncertainty of the load cell's and accelerometer's sensitivities, "
                        "percent, added to b in the b_cal columns (default 0.25 0.5; 0 0: exact sensors)")
    p.add_argument("--processes", type=_positive_int, help="local worker processes, one fit each (default: up to 2)")
    p.add_argument("--scheduler", help="run the fits on this Dask scheduler (tcp://host:port) instead")
    return p


def _add_report(sub) -> argparse.ArgumentParser:
    p = sub.add_parser("report", help="draw a study's per-fit figures again from the fits' checkpoints")
    p.add_argument("folder", help="a study's folder (or one fit's folder in it)")
    return p


def _add_inspect(sub) -> argparse.ArgumentParser:
    p = sub.add_parser("inspect", help="validate a record, check its physical sense and print its summary")
    p.add_argument("record", help="record CSV file")
    _add_record_options(p)
    p.add_argument("--normalise", metavar="OUT.csv",
                   help="write the record in the project's format (SI units, its columns) to OUT.csv")
    p.add_argument("--plot", help="also plot the record into this PNG file")
    return p


#: The commands in the order ``--help`` lists them, each with what adds its options.
_COMMANDS = (("demo", _add_demo), ("generate", _add_generate), ("fit", _add_fit), ("identify", _add_identify),
             ("study", _add_study),
             ("report", _add_report), ("inspect", _add_inspect))


def build_parser(commands: dict) -> argparse.ArgumentParser:
    """The parser of every command; ``commands`` maps each command's name to the
    function that runs it (``args.func``)."""
    parser = argparse.ArgumentParser(
        prog="bayes-inerter",
        description="Bayesian uncertainty quantification of a ball-screw inerter.",
    )
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name, add in _COMMANDS:
        add(sub).set_defaults(func=commands[name])
    return parser
