import subprocess
import sys

import pytest

from bayes_inerter.cli import main
from bayes_inerter.records import read_record

SHORT = ["--duration", "1.0", "--ramp", "0.3"]


def test_generate_one_record(tmp_path, capsys):
    out = tmp_path / "a1.csv"
    assert main(["generate", "--setting", "A1", "--freq", "1.0", "--out", str(out), *SHORT]) == 0
    assert f"wrote {out}" in capsys.readouterr().out
    rec = read_record(out)
    assert rec.metadata["setting"] == "A1" and rec.metadata["generator"]["duration"] == 1.0
    coloured = tmp_path / "a1c.csv"
    assert main(["generate", "--setting", "A1", "--freq", "1.0", "--out", str(coloured), *SHORT,
                 "--noise-corner", "20"]) == 0
    assert read_record(coloured).metadata["generator"]["noise_corner"] == 20.0


@pytest.mark.slow
def test_generate_a_paper_like_record(tmp_path, capsys):
    out = tmp_path / "a1.csv"
    assert main(["generate", "--truth", "paper-like", "--setting", "A1", "--freq", "1.5", "--out", str(out),
                 "--duration", "1.0", "--ramp", "0.3"]) == 0
    meta = read_record(out).metadata
    assert meta["truth"] == "paper-like" and meta["generator"]["duration"] == 1.0
    assert meta["generator"]["friction"] == "stribeck" and meta["generator"]["backlash"] > 0


def test_generate_paper_grid(tmp_path, capsys):
    out = tmp_path / "grid"
    assert main(["generate", "--paper-grid", "--out", str(out), "--duration", "0.3", "--ramp", "0.1"]) == 0
    files = sorted(p.name for p in out.glob("*.csv"))
    assert len(files) == 27 and "B2_1.5Hz.csv" in files and "A0_0.5Hz.csv" in files
    assert capsys.readouterr().out.count("wrote ") == 27


def test_inspect_valid(tmp_path, capsys):
    import matplotlib.pyplot as plt

    out = tmp_path / "b2.csv"
    main(["generate", "--setting", "B2", "--freq", "1.5", "--out", str(out), *SHORT])
    capsys.readouterr()
    png = tmp_path / "b2.png"
    before = set(plt.get_fignums())
    assert main(["inspect", str(out), "--plot", str(png)]) == 0
    text = capsys.readouterr().out
    assert "valid record" in text and "duration 1 s" in text and "rate 1000 Hz" in text
    assert "setting: B2" in text and png.exists()
    assert set(plt.get_fignums()) == before  # the figure closed: main() may run again in the process


def test_inspect_bad_record(tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    bad.write_text("time_s,force_N\n0,1\n")
    png = tmp_path / "bad.png"
    assert main(["inspect", str(bad), "--plot", str(png)]) == 1
    err = capsys.readouterr().err
    assert err.startswith("error: ") and "missing column 'accel_m_s2'" in err
    assert err.count("\n") == 1
    assert not png.exists()


@pytest.mark.parametrize(
    "argv, message",
    [
        (["generate", "--setting", "A9", "--freq", "1", "--out", "x.csv"], "unknown flywheel setting"),
        (["generate", "--setting", "A1", "--out", "x.csv"], "give --setting and --freq"),
        (["generate", "--setting", "A1", "--freq", "1", "--out", "x.txt"], "must name a .csv file"),
        (["generate", "--paper-grid", "--out", "x.csv"], "writes a folder"),
        (["generate", "--setting", "A1", "--freq", "1", "--out", "x.csv", "--noise-corner", "700"],
         "noise_corner must lie between"),
        (["generate", "--truth", "paper-like", "--setting", "A1", "--freq", "0.7", "--out", "x.csv"],
         "a paper-like record is one of the paper's settings at 0.5, 1 or 1.5 Hz"),
    ],
)
def test_generate_bad_input(tmp_path, monkeypatch, capsys, argv, message):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 1
    assert message in capsys.readouterr().err
    assert not any(tmp_path.iterdir())


def test_usage_errors_exit_2(capsys):
    with pytest.raises(SystemExit) as info:
        main(["generate", "--setting", "A1", "--freq", "-1", "--out", "x.csv"])
    assert info.value.code == 2
    assert "must be a positive number" in capsys.readouterr().err


def test_no_traceback_from_the_console_script(tmp_path):
    proc = subprocess.run(
        [sys.executable, "-m", "bayes_inerter.cli", "inspect", str(tmp_path / "nope.csv")],
        capture_output=True, text=True,
    )
    assert proc.returncode == 1
    assert "Traceback" not in proc.stderr
    assert proc.stderr.strip() == f"error: {tmp_path / 'nope.csv'}: no such file; check the path"


def test_demo(tmp_path, capsys):
    assert main(["demo", "--out", str(tmp_path)]) == 0
    for name in ("demo_fits.png", "demo_record.png", "demo_phi.csv", "A1_1Hz.csv"):
        assert (tmp_path / name).exists()
    rows = (tmp_path / "demo_phi.csv").read_text().splitlines()
    assert rows[0] == "network,phi" and len(rows) == 4


def _drop_a_ctrl_c(monkeypatch):
    """Ctrl-C's handler run where Python drops what it raises: in a weakref callback (a
    fit on two processes was once interrupted there and ran on to exit status 0)."""
    import gc
    import signal
    import weakref

    from bayes_inerter.cli import status

    class Thing:
        pass

    monkeypatch.setattr(sys, "unraisablehook", lambda unraisable: None)  # Python's report of the drop
    thing = Thing()
    weakref.finalize(thing, status.on_sigint, signal.SIGINT, None)
    del thing
    gc.collect()


def test_a_dropped_ctrl_c_is_raised_again_at_the_next_step(monkeypatch):
    from bayes_inerter.cli import status

    status.reset_interrupt()
    try:
        status.check_interrupt()  # nothing came: nothing raised
        _drop_a_ctrl_c(monkeypatch)  # no KeyboardInterrupt reaches here ...
        assert status.interrupted()
        with pytest.raises(KeyboardInterrupt):
            status.check_interrupt()  # ... but the next step's callback raises it
    finally:
        status.reset_interrupt()


def test_a_command_that_ends_after_a_dropped_ctrl_c_exits_130(monkeypatch, capsys):
    import signal

    from bayes_inerter import cli

    def command(args):
        _drop_a_ctrl_c(monkeypatch)
        return 0

    monkeypatch.setattr(cli, "cmd_inspect", command)
    before = signal.getsignal(signal.SIGINT)
    assert main(["inspect", "any.csv"]) == 130
    assert "interrupted" in capsys.readouterr().err
    assert signal.getsignal(signal.SIGINT) is before  # the handler is put back
    monkeypatch.setattr(cli, "cmd_inspect", lambda args: 0)
    assert main(["inspect", "any.csv"]) == 0  # the next command starts afresh


@pytest.mark.parametrize("fails", [False, True])
def test_output_into_a_closed_pipe_keeps_the_commands_own_status(tmp_path, fails):
    """With stdout buffered (no PYTHONUNBUFFERED) a closed pipe shows only at a flush;
    Python's own at exit would end the process with status 120, a failed command's too.
    The command here is a stand-in that prints, then fails or not."""
    import os

    script = ("import sys\n"
              "import bayes_inerter.cli as cli\n"
              "def command(args):\n"
              "    print('a line of output\\n' * 50)\n"
              f"    if {fails}:\n"
              "        raise cli.CliError('the stand-in failed')\n"
              "    return 0\n"
              "cli.cmd_inspect = command\n"
              f"sys.exit(cli.main(['inspect', {str(tmp_path / 'r.csv')!r}]))\n")
    env = {k: v for k, v in os.environ.items() if k != "PYTHONUNBUFFERED"}
    proc = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env)
    proc.stdout.close()  # as `| head -0` does
    err = proc.stderr.read().decode()
    status = proc.wait()
    assert "Traceback" not in err and "Broken pipe" not in err
    if fails:
        assert status == 1 and "error: the stand-in failed" in err
    else:
        assert status in (0, 141)
