import os
import signal
import subprocess
import sys
import time

import h5py
import numpy as np
import pytest

from bayes_inerter import paper_parameters
from bayes_inerter.cli import main
from bayes_inerter.inference import fit_record
from bayes_inerter.records import GeneratorSettings, generate_record, write_record

SHORT = GeneratorSettings(duration=2.5, ramp=0.8)


@pytest.fixture(scope="module")
def record_file(tmp_path_factory):
    d = tmp_path_factory.mktemp("rec")
    rec = generate_record(paper_parameters("A4"), 1.5, settings=SHORT, rng=11, setting_name="A4")
    path, _ = write_record(d / "a4.csv", rec)
    return path


def _chain(path):
    with h5py.File(path, "r") as f:
        g = f["mcmc"]
        return g["chain"][: g.attrs["iteration"]].copy()


def test_fit_writes_every_output(tmp_path, record_file, capsys):
    out = tmp_path / "fit"
    code = main(["fit", str(record_file), "--out", str(out), "--steps", "30", "--walkers", "24", "--processes", "1"])
    assert code == 0
    text = capsys.readouterr().out
    assert "b = " in text and "warning: not converged" in text
    for name in ("summary.csv", "posterior.nc", "chain.h5", "corner.png", "bands.png", "trace.png", "phi.png", "fit.json"):
        assert (out / name).exists(), name
    header = (out / "summary.csv").read_text().splitlines()[0]
    assert header == "name,mean,sd,hdi_3%,hdi_97%,r_hat,ess_bulk,ess_tail"
    import arviz as az

    idata = az.from_netcdf(str(out / "posterior.nc"))
    for group in ("posterior", "log_likelihood", "posterior_predictive", "observed_data", "sample_stats"):
        assert group in idata.groups()
    assert "phi" in idata.posterior


def test_same_seed_same_summary(tmp_path, record_file):
    from bayes_inerter.records import read_record

    rec = read_record(record_file)
    a = fit_record(rec, tmp_path / "a", steps=20, walkers=24, seed=5, plots=False)
    fit_record(rec, tmp_path / "b", steps=20, walkers=24, seed=5, plots=False)
    assert (tmp_path / "a" / "summary.csv").read_bytes() == (tmp_path / "b" / "summary.csv").read_bytes()
    c = fit_record(rec, tmp_path / "c", steps=20, walkers=24, seed=6, plots=False)
    assert c.summary[0]["mean"] != a.summary[0]["mean"]


def _run_until_killed(cmd, chain_file, at_least: int) -> None:
    """Start ``cmd`` and SIGKILL it once its checkpoint holds ``at_least`` steps."""
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.time() + 300
    while time.time() < deadline and proc.poll() is None:
        time.sleep(0.05)
        try:
            with h5py.File(chain_file, "r", locking=False) as f:
                seen = int(f["mcmc"].attrs["iteration"])
        except (OSError, KeyError):
            continue
        if seen >= at_least:
            break
    assert proc.poll() is None, "the run ended before it could be killed"
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()


def _finish_and_compare(cmd, chain_file, before, tmp_path, record_file) -> None:
    """Run ``cmd`` to the end: exactly 40 steps, the killed runs' steps kept, and the same
    chain as a run never interrupted."""
    assert subprocess.run(cmd, capture_output=True).returncode == 0
    after = _chain(chain_file)
    assert len(after) == 40
    np.testing.assert_array_equal(after[: len(before)], before)
    ref = tmp_path / "uninterrupted"
    assert main(["fit", str(record_file), "--out", str(ref), "--steps", "40", "--walkers", "24",
                 "--processes", "1", "--seed", "3"]) == 0
    np.testing.assert_array_equal(_chain(ref / "chain.h5"), after)


def test_resume_after_sigkill(tmp_path, record_file):
    """Killed part-way and run again: exactly the requested steps, earlier steps kept, and
    the same chain as a run that was never interrupted."""
    out = tmp_path / "killed"
    cmd = [sys.executable, "-m", "bayes_inerter.cli", "fit", str(record_file), "--out", str(out),
           "--steps", "40", "--walkers", "24", "--processes", "1", "--seed", "3"]
    _run_until_killed(cmd, out / "chain.h5", 8)
    before = _chain(out / "chain.h5")
    assert 8 <= len(before) < 40
    _finish_and_compare(cmd, out / "chain.h5", before, tmp_path, record_file)


@pytest.mark.slow
@pytest.mark.xfail(strict=False, reason=(
    "known fault: a SIGKILL in the middle of an HDF5 write can leave the checkpoint unreadable "
    "(seen in a CI run: 'addr overflow'); the next run then refuses it with a one-line error "
    "instead of continuing. Needs a crash-safe checkpoint (e.g. two alternating files)."))
def test_resume_after_sigkill_several_times(tmp_path, record_file):
    """Killed three times in a row at random steps and run again: exactly the requested
    steps, every earlier step kept, and the same chain as a run never interrupted."""
    out = tmp_path / "killed"
    cmd = [sys.executable, "-m", "bayes_inerter.cli", "fit", str(record_file), "--out", str(out),
           "--steps", "40", "--walkers", "24", "--processes", "1", "--seed", "3"]
    chain_file = out / "chain.h5"
    before = None
    for at in sorted(np.random.default_rng(2).integers(4, 34, size=3)):
        _run_until_killed(cmd, chain_file, int(at))
        now = _chain(chain_file)
        assert at <= len(now) < 40
        if before is not None:  # nothing written before this kill was lost or changed
            np.testing.assert_array_equal(now[: len(before)], before)
        before = now
    _finish_and_compare(cmd, chain_file, before, tmp_path, record_file)


def test_bad_record_refused_before_sampling(tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    bad.write_text("time_s,force_N,accel_m_s2\n0,1,x\n")
    out = tmp_path / "never"
    assert main(["fit", str(bad), "--out", str(out)]) == 1
    assert "is not a number" in capsys.readouterr().err
    assert not out.exists()


def test_bad_options_refused_before_sampling(tmp_path, record_file, capsys):
    out = tmp_path / "never"
    assert main(["fit", str(record_file), "--out", str(out), "--walkers", "5"]) == 1
    assert "walkers must be even" in capsys.readouterr().err
    assert not out.exists()


def test_checkpoint_mismatch_and_corruption(tmp_path, record_file, capsys):
    out = tmp_path / "fit"
    assert main(["fit", str(record_file), "--out", str(out), "--steps", "5", "--walkers", "24", "--processes", "1"]) == 0
    capsys.readouterr()
    assert main(["fit", str(record_file), "--out", str(out), "--steps", "10", "--walkers", "26", "--processes", "1"]) == 1
    assert "use the same --walkers, or --fresh" in capsys.readouterr().err
    ck = out / "chain.h5"
    data = ck.read_bytes()
    ck.write_bytes(data[: len(data) // 3])  # truncated on disk
    assert main(["fit", str(record_file), "--out", str(out), "--steps", "10", "--walkers", "24", "--processes", "1"]) == 1
    err = capsys.readouterr().err
    assert "unreadable or truncated" in err and err.count("\n") == 1
    assert ck.read_bytes() == data[: len(data) // 3]  # not overwritten
    # damaged inside the stored steps (a valid HDF5 file whose numbers changed): refused too
    ck.write_bytes(data)
    with h5py.File(ck, "r") as f:
        offset = f["mcmc/chain"].id.get_chunk_info(0).byte_offset
    damaged = bytearray(data)
    damaged[offset + 8 : offset + 16] = b"\x7f" * 8
    ck.write_bytes(bytes(damaged))
    assert main(["fit", str(record_file), "--out", str(out), "--steps", "10", "--walkers", "24", "--processes", "1"]) == 1
    err = capsys.readouterr().err
    assert "do not match their checksum" in err and err.count("\n") == 1
    assert ck.read_bytes() == bytes(damaged)
    ck.write_bytes(data)  # the intact checkpoint continues
    assert main(["fit", str(record_file), "--out", str(out), "--steps", "10", "--walkers", "24", "--processes", "1"]) == 0


def test_unwritable_output_refused(tmp_path, record_file, capsys):
    if os.geteuid() == 0:
        target = tmp_path / "file-not-folder"
        target.write_text("x")
        assert main(["fit", str(record_file), "--out", str(target)]) == 1
        assert "not a folder" in capsys.readouterr().err
    else:  # pragma: no cover - depends on who runs the tests
        locked = tmp_path / "locked"
        locked.mkdir(mode=0o500)
        assert main(["fit", str(record_file), "--out", str(locked / "x")]) == 1
        assert "cannot write there" in capsys.readouterr().err


def test_reading_the_checkpoint_does_not_stop_a_run(tmp_path, record_file):
    """A reader holding chain.h5 open (with HDF5's default lock) must not make the
    sampler's next write fail."""
    out = tmp_path / "busy"
    args = ["fit", str(record_file), "--out", str(out), "--steps", "6", "--walkers", "24", "--processes", "1"]
    assert main(args) == 0
    # another process holds the file open, locked the usual way, while the run goes on
    reader = subprocess.Popen([sys.executable, "-c",
                               f"import h5py, time; f = h5py.File({str(out / 'chain.h5')!r}, 'r'); time.sleep(120)"])
    try:
        time.sleep(2.0)
        assert main(args[:5] + ["12"] + args[6:]) == 0
    finally:
        reader.kill()
        reader.wait()
    assert len(_chain(out / "chain.h5")) == 12
