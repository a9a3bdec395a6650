"""The command line with a user's own files: column maps, units, checks, masses, device
files, normalising, one run per folder, and progress in a log file."""

import io
import json
import math

import numpy as np
import pytest

from bayes_inerter.cli_progress import StepProgress
from bayes_inerter.cli import main
from bayes_inerter.cli.fit import _percent_interval
from bayes_inerter.inference.sampling.sampler import SamplerStatus
from bayes_inerter.lock import folder_lock
from bayes_inerter.records import read_record


def _daq(tmp_path, force_scale=1e-3, name="daq.csv", metadata=True, seconds=3.0):
    """A DAQ export of a rigid 3,100 kg device at 1 Hz, ``seconds`` long: time in ms, force
    in kN (or ``force_scale`` of N), acceleration in g, semicolons, an extra channel; with
    the drive frequency and m_s in its header, or (``metadata`` False) nothing but the table."""
    t = np.arange(int(round(seconds * 1000)) + 1) / 1000.0
    w = 2 * math.pi
    x = 0.01 * np.sin(w * t)
    a = -w * w * x
    f = 3100.0 * a + 300.0 * np.tanh(0.01 * w * np.cos(w * t) / 1e-3)
    rows = [f"{ti * 1000:.3f};{fi * force_scale:.9g};{ai / 9.80665:.9g};{xi * 1000:.9g};21.5"
            for ti, fi, ai, xi in zip(t, f, a, x)]
    p = tmp_path / name
    head = "# drive_frequency_hz: 1\n# m_s: 21.7\n" if metadata else ""
    p.write_text(head + "Zeit;Kraft;Beschl;Weg;Temp\n" + "\n".join(rows) + "\n")
    return p


MAP = ["--columns", "time=Zeit,force=Kraft,accel=Beschl,disp=Weg", "--units", "time=ms,force=kN,accel=g,disp=mm"]

#: Long enough for the default likelihood (motion in, force out), which needs three whole
#: steady drive periods after the first (3 s hold two).
PERIODIC_SECONDS = 5.0


def test_inspect_reads_a_daq_export_and_normalises_it(tmp_path, capsys):
    p = _daq(tmp_path)
    out = tmp_path / "si.csv"
    assert main(["inspect", str(p), *MAP, "--normalise", str(out)]) == 0
    text = capsys.readouterr().out
    assert "valid record" in text and "physical-sense checks: passed" in text
    assert "m_B = 57.2 kg (the paper's Table I" in text
    rec = read_record(out)
    assert rec.fs == pytest.approx(1000.0) and np.max(np.abs(rec.disp)) == pytest.approx(0.01, rel=1e-6)


@pytest.mark.parametrize("units, cause", [
    ("time=ms,force=N,accel=g,disp=mm", "force in kN"),
    ("time=ms,force=kN,accel=m/s^2,disp=mm", "acceleration in g"),
    ("time=ms,force=kN,accel=g,disp=m", "displacement in mm"),
])
def test_a_wrong_unit_is_refused_in_one_line_naming_it(tmp_path, capsys, units, cause):
    p = _daq(tmp_path)
    argv = ["inspect", str(p), "--columns", "time=Zeit,force=Kraft,accel=Beschl,disp=Weg", "--units", units]
    assert main(argv) == 1
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and "\n" not in err and cause in err and "--skip-check" in err


def test_fit_refuses_before_touching_the_folder_and_the_override_is_named(tmp_path, capsys):
    p = _daq(tmp_path)
    out = tmp_path / "fit"
    argv = ["fit", str(p), "--columns", "time=Zeit,force=Kraft,accel=Beschl", "--units", "time=ms,accel=g",
            "--out", str(out), "--steps", "5"]
    assert main(argv) == 1
    err = capsys.readouterr().err
    assert "force in kN" in err and "--skip-check apparent-mass" in err
    assert not out.exists()


def test_a_second_fit_into_a_held_folder_is_refused_at_once(tmp_path, capsys):
    p = _daq(tmp_path, seconds=PERIODIC_SECONDS)
    out = tmp_path / "fit"
    with folder_lock(out):
        assert main(["fit", str(p), *MAP, "--out", str(out), "--steps", "5"]) == 1
    err = capsys.readouterr().err
    assert "is in use by another run (process" in err
    assert not (out / "chain.h5").exists()


def test_fit_prints_the_masses_and_their_sources_and_device_theory(tmp_path, capsys):
    p = _daq(tmp_path, seconds=PERIODIC_SECONDS)
    dev = tmp_path / "dev.toml"
    dev.write_text("m_B = 50.0\n[geometry]\nlead = 0.02\nJ_screw = 0.03\n")
    out = tmp_path / "fit"
    code = main(["fit", str(p), *MAP, "--device", str(dev), "--out", str(out), "--steps", "4", "--processes", "1",
                 "--walkers", "24", "--no-plots"])
    assert code == 0
    text = capsys.readouterr().out
    assert "m_s = 21.7 kg (record metadata m_s), m_B = 50 kg (device file" in text
    theory = (2 * math.pi / 0.02) ** 2 * 0.03  # (2 pi / lead)^2 J_screw
    assert f"theory (device file geometry): b = {theory:.6g} kg" in text
    # four steps cannot converge, nor tell how b mixes: the warning says so, and what to do
    assert "the chain is too short to judge how b mixes: trust no interval yet" in text
    assert "run again without --steps" in text
    info = json.loads((out / "fit.json").read_text())
    # fit.json and summary.csv say what the console said
    printed = [line[len("warning: "):] for line in text.splitlines() if line.startswith("warning: ")]
    assert printed and [w["message"] for w in info["warnings"]] == printed
    import csv

    rows = {r["name"]: r for r in csv.DictReader(open(out / "summary.csv"))}
    for w in info["warnings"]:
        for name in (w["name"], *w["also"]):
            assert w["flag"] in rows[name]["flag"], (name, w["flag"])
    assert "not converged" in rows["b"]["flag"]
    # the priors listed are those sampled; the raw frictions are derived from sums and shares
    assert "c_f1" not in info["priors"] and "c_f" in info["priors"] and "c_f1" in info["derived"]
    assert rows["c_f1"]["kind"] == "derived" and rows["b"]["kind"] == "sampled"
    assert info["masses"]["m_B"] == {"kg": 50.0, "source": f"device file {dev}"}
    m_s = info["masses"]["m_s"]  # the masses printed before the fit are the ones it used
    assert (f"masses: m_s = {m_s['kg']:g} kg ({m_s['source']}), m_B = 50 kg (device file {dev})"
            in text.splitlines())
    assert info["b_theory_device_file"] == pytest.approx((2 * math.pi / 0.02) ** 2 * 0.03)


def test_percent_interval_has_digits_enough_to_differ():
    assert _percent_interval(0.99141, 0.99143) == "99.141 % to 99.143 %"
    assert _percent_interval(0.5, 0.75) == "50.00 % to 75.00 %"


class _Clock:
    def __init__(self):
        self.t = 0.0


def test_progress_in_a_log_file_prints_lines_at_most_every_interval(monkeypatch):
    clock = _Clock()
    monkeypatch.setattr("bayes_inerter.cli_progress.time.monotonic", lambda: clock.t)
    log = io.StringIO()  # not a terminal
    bar = StepProgress("sampling", stream=log, interval=30.0)
    bar.status(SamplerStatus(250, 250, None))
    for step in range(251, 400):
        clock.t += 1.0  # a step a second
        bar.step(step, None)
        if step == 300:
            bar.status(SamplerStatus(300, 250, None, tau_max=42.0, acceptance=0.31, steps_needed=3000))
    bar.close()
    lines = log.getvalue().splitlines()
    assert lines[0] == "sampling: the checkpoint holds 250 steps; continuing until converged"
    steps = [ln for ln in lines[1:] if ln.startswith("sampling: step")]
    assert len(steps) == 1 + 149 // 30 + 1  # the first step, one every 30 s, the end
    assert "tau 42 steps, acceptance 0.31, about 3000 more steps needed" in lines[-1]
    assert lines[-1].endswith("(done)")


def test_study_checks_the_users_records_before_any_fit(tmp_path, capsys):
    folder = tmp_path / "records"
    folder.mkdir()
    p = _daq(folder, force_scale=1.0, name="good.csv")
    text = p.read_text().replace("Zeit;Kraft;Beschl;Weg;Temp", "time_s;force_N;accel_m_s2;disp_m;temp")
    # a file in the project's columns but with the force in kN and no map: refused
    rows = text.splitlines()
    header_at = next(i for i, r in enumerate(rows) if r.startswith("time_s"))
    body = [";".join([f"{float(a) / 1000:.6f}", f"{float(b) / 1000:.9g}", f"{float(c) * 9.80665:.9g}",
                      f"{float(d) / 1000:.9g}"]) for a, b, c, d, _ in (r.split(";") for r in rows[header_at + 1:])]
    (folder / "good.csv").unlink()
    (folder / "kN.csv").write_text("\n".join(rows[:header_at] + ["time_s;force_N;accel_m_s2;disp_m"] + body) + "\n")
    out = tmp_path / "study"
    assert main(["study", "--quick", "--records", str(folder), "--out", str(out), "--no-joint"]) == 1
    err = capsys.readouterr().err
    assert "kN.csv" in err and "force in kN" in err and "--skip-check apparent-mass" in err
    assert not (out / "fits").exists()


def test_swapped_columns_named_through_their_declared_units(tmp_path, capsys):
    # the file's force column holds the acceleration (in g) and its acceleration column
    # the force (in kN), and the user declared the units as the columns' names promised
    p = _daq(tmp_path)
    lines = p.read_text().splitlines()
    head = [ln for ln in lines if ln.startswith("#")]
    rows = [ln.split(";") for ln in lines[len(head) + 1:]]
    swapped = [";".join([r[0], r[2], r[1], r[3], r[4]]) for r in rows]
    p.write_text("\n".join(head + ["Zeit;Kraft;Beschl;Weg;Temp"] + swapped) + "\n")
    assert main(["inspect", str(p), *MAP]) == 1
    err = capsys.readouterr().err
    assert "likely force and acceleration columns swapped" in err
    assert "force in kN" not in err  # declared already: no advice to declare it


def test_a_closed_pipe_ends_quietly(tmp_path):
    """With stdout buffered, as a pipe's is unless PYTHONUNBUFFERED is set (it was in the
    shell this was first tested in, and the test passed there while a shell without it
    got exit status 120 from the flush at exit)."""
    import os
    import subprocess
    import sys

    p = _daq(tmp_path)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONUNBUFFERED"}
    proc = subprocess.Popen([sys.executable, "-m", "bayes_inerter.cli", "inspect", str(p), *MAP],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)
    proc.stdout.close()  # as `| head -0` does
    err = proc.stderr.read().decode()
    assert proc.wait() in (0, 141) and "Broken pipe" not in err and "Traceback" not in err


def test_a_daq_file_without_metadata_fits_as_the_readme_says_and_goes_on(tmp_path, capsys):
    """The README's own example on a file with no metadata: the drive frequency is
    estimated before sampling and printed with its source; the interval at the end needs
    nothing more. Given in the metadata afterwards, or fitted through the Python API, the
    same chain goes on: 1 Hz and the estimate differ by far less than the record's
    resolution."""
    from bayes_inerter.inference import fit_record
    from bayes_inerter.inference.posterior.likelihood import LikelihoodSettings
    from bayes_inerter.records import read_record as read

    p = _daq(tmp_path, metadata=False)
    out = tmp_path / "fits" / "run1"
    # the time-domain likelihood, whose interval is the honest one (and which the 3 s
    # record holds enough of: the default's harmonic likelihood needs three periods)
    common = [*MAP, "--out", str(out), "--processes", "1", "--walkers", "24", "--no-plots", "--residual", "ar1"]
    assert main(["fit", str(p), *common, "--m-s", "21.7", "--steps", "4"]) == 0
    text = capsys.readouterr().out
    line = next(x for x in text.splitlines() if x.startswith("drive frequency: "))
    estimated = float(line.split()[2])
    assert "(estimated from the record's spectrum)" in line and estimated == pytest.approx(1.0, rel=1e-4)
    info = json.loads((out / "fit.json").read_text())
    assert info["drive_frequency"]["hz"] == pytest.approx(estimated, rel=1e-6)
    assert "estimated" in info["drive_frequency"]["source"]
    assert info["b_interval"]["method"] == "honest"
    # the same frequency, now in the metadata: the checkpoint is continued, not refused
    p.with_suffix(".json").write_text(json.dumps({"drive_frequency_hz": 1.0, "m_s": 21.7}))
    assert main(["fit", str(p), *common, "--steps", "6"]) == 0
    captured = capsys.readouterr()
    assert "drive frequency: 1 Hz (record metadata drive_frequency_hz)" in captured.out
    assert json.loads((out / "fit.json").read_text())["iterations"] == 6
    # and through the API, on the record without metadata
    p.with_suffix(".json").unlink()
    rec = read(p, columns="time=Zeit,force=Kraft,accel=Beschl,disp=Weg", units="time=ms,force=kN,accel=g,disp=mm")
    assert rec.drive_frequency is None
    got = fit_record(rec, out, m_s=21.7, steps=8, walkers=24, plots=False,
                     likelihood=LikelihoodSettings(residual="ar1"))
    assert got.iterations == 8 and got.drive.hz == pytest.approx(1.0, rel=1e-4) and got.b_interval is not None


def test_freq_overrides_the_estimate(tmp_path, capsys):
    p = _daq(tmp_path, metadata=False)
    assert main(["inspect", str(p), *MAP, "--freq", "1.0"]) == 0
    assert "drive 1 Hz (option --freq)" in capsys.readouterr().out
    assert main(["inspect", str(p), *MAP]) == 0
    text = capsys.readouterr().out
    assert "Hz (estimated from the record's spectrum)" in text


def test_a_drive_that_cannot_be_settled_fails_before_the_folder_is_touched(tmp_path):
    from bayes_inerter.inference import fit_record
    from bayes_inerter.records import read_record as read

    rec = read(_daq(tmp_path, metadata=False), columns="time=Zeit,force=Kraft,accel=Beschl,disp=Weg",
               units="time=ms,force=kN,accel=g,disp=mm")
    out = tmp_path / "fit"
    with pytest.raises(ValueError, match="positive number of Hz"):
        fit_record(rec, out, m_s=21.7, steps=4, freq=-1.0)
    assert not out.exists()


@pytest.mark.parametrize("done, target, cap, said", [
    (1000, None, 20000, "the checkpoint holds 1000 steps; continuing until converged (at most 20000 steps)"),
    (20000, None, 20000, "the checkpoint holds 20000 steps, the cap of 20000: nothing more to sample "
                         "(a higher --max-steps continues it)"),
    (15491, 1, 20000, "the checkpoint holds 15491 steps, as many as --steps 1 asks or more: nothing more to sample"),
    (300, 600, 20000, "the checkpoint holds 300 steps; continuing to step 600"),
])
def test_resume_lines_read_naturally(done, target, cap, said):
    log = io.StringIO()
    bar = StepProgress("sampling", total=target, stream=log, cap=cap)
    bar.status(SamplerStatus(done, done, target))
    assert log.getvalue().splitlines() == [f"sampling: {said}"]


def test_progress_never_promises_steps_past_the_cap():
    log = io.StringIO()
    bar = StepProgress("sampling", stream=log, interval=0.0, cap=20000)
    bar.status(SamplerStatus(15000, 0, None, tau_max=300.0, acceptance=0.3, steps_needed=23360))
    bar.step(15000, None)
    assert "more steps needed than the cap of 20000 leaves" in log.getvalue()
    assert "23360" not in log.getvalue()


def test_progress_of_a_stopped_run_does_not_say_done():
    log = io.StringIO()
    bar = StepProgress("sampling", total=40, stream=log, interval=0.0)
    bar.step(3, 40)
    bar.close(done=False)
    assert log.getvalue().splitlines()[-1] == "sampling: step 3 of 40 (stopped)"


@pytest.mark.slow  # a fit with its start search (9 s); the sampler's tempering is tested quickly on its own
def test_a_tempered_fit_prints_its_ladder_and_swap_rates(tmp_path, capsys):
    p = _daq(tmp_path, seconds=PERIODIC_SECONDS)
    out = tmp_path / "fit"
    assert main(["fit", str(p), *MAP, "--out", str(out), "--steps", "4", "--processes", "1", "--walkers", "24",
                 "--no-plots", "--tempering", "3", "--hottest-beta", "0.25"]) == 0
    text = capsys.readouterr().out
    info = json.loads((out / "fit.json").read_text())["tempering"]
    assert info["betas"] == pytest.approx([1.0, 0.5, 0.25])
    largest = max(info["replica_tau"].values())  # the rule read the replicas (the default)
    assert f"tau read on the replicas too: largest {largest:.0f} steps" in text.splitlines()
    assert len(info["swap_rates"]) == 2 and all(0.0 <= r <= 1.0 for r in info["swap_rates"])
    rates = ", ".join(f"{r:.0%}" for r in info["swap_rates"])
    assert f"{info['ladder']}; swaps accepted between neighbours: {rates}" in text.splitlines()


@pytest.mark.parametrize("ladder", [["--tempering", "3"], ["--hottest-beta", "0.2"]])
def test_no_tempering_with_a_ladder_is_refused_before_the_folder_is_touched(tmp_path, capsys, ladder):
    p = _daq(tmp_path, seconds=PERIODIC_SECONDS)
    out = tmp_path / "fit"
    assert main(["fit", str(p), *MAP, "--out", str(out), "--steps", "4", "--no-tempering", *ladder]) != 0
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and "\n" not in err and "give one or the other" in err
    assert not out.exists()


def test_fit_is_tempered_only_when_asked(monkeypatch, tmp_path):
    """The command line's sampler: none by default, the ladder asked, and each one's
    cap."""
    from bayes_inerter.inference.sampling.tempering import Tempering

    seen, caps = [], []

    def fake_fit(rec, out, **options):  # the plumbing is tested, not a fit
        seen.append(options["tempering"])
        caps.append(options["convergence"].max_steps)
        raise ValueError("stand-in fit")

    monkeypatch.setattr("bayes_inerter.inference.fit_record", fake_fit)
    p = _daq(tmp_path, seconds=PERIODIC_SECONDS)
    for extra in ([], ["--tempering", "3"], ["--hottest-beta", "0.2"], ["--no-tempering"]):
        assert main(["fit", str(p), *MAP, "--out", str(tmp_path / "fit"), "--steps", "4", "--no-plots", *extra]) == 1
    assert seen == [None, Tempering(3), Tempering(4, 0.2), None]
    assert caps == [20_000, 10_000, 10_000, 20_000]  # each sampler's own cap unless --max-steps
    assert main(["fit", str(p), *MAP, "--out", str(tmp_path / "fit"), "--max-steps", "500", "--no-plots"]) == 1
    assert caps[-1] == 500


def test_fit_passes_the_form_sd_on_and_refuses_one_out_of_range(monkeypatch, tmp_path, capsys):
    """``fit --form-sd`` and ``--form-friction``: the likelihood's model-form errors of b
    (0 by default); a form sd outside [0, 0.2) is refused in one line before the folder
    is touched."""
    seen = []

    def fake_fit(rec, out, **options):  # the plumbing is tested, not a fit
        seen.append((options["likelihood"].form_sd, options["likelihood"].form_friction))
        raise ValueError("stand-in fit")

    monkeypatch.setattr("bayes_inerter.inference.fit_record", fake_fit)
    p = _daq(tmp_path, seconds=PERIODIC_SECONDS)
    out = tmp_path / "fit"
    for extra in ([], ["--form-sd", "0.005"], ["--form-friction", "0.01"]):
        assert main(["fit", str(p), *MAP, "--out", str(out), "--steps", "4", "--no-plots", *extra]) == 1
    assert seen == [(0.0, 0.0), (0.005, 0.0), (0.0, 0.01)]
    capsys.readouterr()
    assert main(["fit", str(p), *MAP, "--out", str(out), "--steps", "4", "--form-sd", "0.3"]) != 0
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and "\n" not in err and "form_sd" in err
    assert not out.exists()
