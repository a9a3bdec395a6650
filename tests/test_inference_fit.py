import csv
import json
import os
import signal
import subprocess
import sys
import time
import warnings

import emcee
import h5py
import numpy as np
import pytest
from conftest import SEARCH_SOURCE

from bayes_inerter import paper_parameters
from bayes_inerter.cli import main
from bayes_inerter.inference import fit_record
from bayes_inerter.inference.sampling.checkpoint import read_chain, steps_written
from bayes_inerter.records import GeneratorSettings, generate_record, write_record

SHORT = GeneratorSettings(duration=2.5, ramp=0.8)
#: Long enough for the default likelihood (motion in, force out), which needs three whole
#: steady drive periods after the first: 2.5 s at 1.5 Hz hold one.
PERIODIC = GeneratorSettings(duration=4.0, ramp=0.8)

#: The time-domain likelihood, for the tests that check what it does (its honest interval)
#: or need its pace: it simulates the record at every evaluation, so a kill or a Ctrl-C
#: can come mid-chain (the default simulates only for the posterior's draws).
AR1 = ("--residual", "ar1")


@pytest.fixture(scope="module")
def record_file(tmp_path_factory):
    d = tmp_path_factory.mktemp("rec")
    rec = generate_record(paper_parameters("A4"), 1.5, settings=PERIODIC, rng=11, setting_name="A4")
    path, _ = write_record(d / "a4.csv", rec)
    return path


@pytest.fixture(scope="module")
def ar1_record_file(tmp_path_factory):
    """A shorter record, for the fits with the time-domain likelihood (:data:`AR1`)."""
    d = tmp_path_factory.mktemp("rec")
    rec = generate_record(paper_parameters("A4"), 1.5, settings=SHORT, rng=11, setting_name="A4")
    path, _ = write_record(d / "a4.csv", rec)
    return path


def _chain(path):
    with h5py.File(path, "r") as f:
        g = f["mcmc"]
        return g["chain"][: g.attrs["iteration"]].copy()


def test_fit_writes_every_output(tmp_path, ar1_record_file, capsys):
    out = tmp_path / "fit"
    code = main(["fit", str(ar1_record_file), "--out", str(out), "--steps", "30", "--walkers", "24", "--processes", "1",
                 *AR1])
    assert code == 0
    text = capsys.readouterr().out
    assert "b = " in text and "warning: not converged" in text
    for name in ("summary.csv", "posterior.nc", "loo.json", "chain.h5", "corner.png", "bands.png", "trace.png",
                 "phi.png", "fit.json"):
        assert (out / name).exists(), name
    assert not (out / "loops.png").exists()  # the time-domain likelihoods predict no force
    assert (f"wrote {out}/summary.csv, posterior.nc, loo.json, chain.h5 (and its twin), corner.png, bands.png, "
            "trace.png, phi.png, fit.json") in text.splitlines()
    header = (out / "summary.csv").read_text().splitlines()[0]
    assert header == "name,kind,mean,sd,hdi_3%,hdi_97%,r_hat,ess_bulk,ess_tail,flag"
    import arviz as az

    idata = az.from_netcdf(str(out / "posterior.nc"))
    for group in ("posterior", "log_likelihood", "posterior_predictive", "observed_data", "sample_stats"):
        assert group in idata.groups()
    assert "phi" in idata.posterior
    # loo.json holds what arviz computes from posterior.nc
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # 30 steps: large Pareto k, which loo.json keeps
        loo = az.loo(idata, pointwise=True)
    kept = json.loads((out / "loo.json").read_text())
    assert kept["elpd_loo"] == pytest.approx(float(loo.elpd_loo), rel=1e-12)
    assert kept["elpd_se"] == pytest.approx(float(loo.se), rel=1e-12)
    assert kept["pareto_k_max"] == pytest.approx(float(np.max(loo.pareto_k)), rel=1e-12)
    assert kept["n_points"] == idata.log_likelihood["accel"].shape[-1]
    info = json.loads((out / "fit.json").read_text())
    # walked in the impedance coordinates at the record's 1.5 Hz, where the nut's ridge is an axis
    assert info["coordinates"].startswith("impedance (M, C at 1.5 Hz"), info["coordinates"]
    assert not any(m.startswith("NutRidgeMove") for m in info["moves"]), info["moves"]
    # 30 steps are too few for the adaptation to fit a proposal (it refits every 250), so fit.json
    # names only the ensemble moves the chain used (the fitted case: tests/test_inference_sampler.py)
    assert info["moves"] and not any(m.startswith("IndependenceMove") for m in info["moves"]), info["moves"]
    assert 0.0 < info["coordinates_domain_edge"] < 0.5  # how near the domain's edge its draws came
    # the start's phases each on their own line of the timings (sampler.START_PHASES)
    assert {"start_search", "start_modes", "start_ensemble"} <= set(info["timings_s"])
    # the record's own force ratio at the drive, as records.reactance reads it
    from bayes_inerter.records import read_record
    from bayes_inerter.records.reactance import drive_impedance
    assert info["drive_impedance"]["ratio"] == pytest.approx(drive_impedance(read_record(ar1_record_file), 1.5).ratio,
                                                           rel=1e-9)
    # b's reported interval is the honest one, wider than the posterior's own, and printed
    iv = info["b_interval"]
    assert iv["method"] == "honest" and iv["sd_log_sensors"] > 0 and iv["sd_log_discrepancy"] >= 0
    b = next(r for r in csv.DictReader(open(out / "summary.csv")) if r["name"] == "b")
    assert iv["lo"] < float(b["hdi_3%"]) < float(b["hdi_97%"]) < iv["hi"]
    assert f"{iv['lo']:.6g} to {iv['hi']:.6g}" in text and "the posterior alone" in text




def test_fit_names_the_figures_it_drew_not_those_the_folder_holds(tmp_path, ar1_record_file, capsys):
    out = tmp_path / "fit"
    out.mkdir()
    (out / "corner.png").write_bytes(b"an earlier run's")
    assert main(["fit", str(ar1_record_file), "--out", str(out), "--steps", "4", "--walkers", "24",
                 "--processes", "1", "--no-plots", *AR1]) == 0
    wrote = [line for line in capsys.readouterr().out.splitlines() if line.startswith("wrote ")]
    assert wrote == [f"wrote {out}/summary.csv, posterior.nc, loo.json, chain.h5 (and its twin), fit.json"]

def test_the_default_likelihoods_fit_writes_every_output(tmp_path, record_file, capsys):
    """The default likelihood, motion in, force out: its own parameters and the bearing's
    damping ratio sampled, its pointwise terms the force's harmonics, and b's interval the
    posterior's own, which holds the discrepancy and the gain itself."""
    out = tmp_path / "fit"
    assert main(["fit", str(record_file), "--out", str(out), "--steps", "10", "--walkers", "26",
                 "--processes", "1"]) == 0
    text = capsys.readouterr().out
    for name in ("summary.csv", "posterior.nc", "loo.json", "chain.h5", "corner.png", "bands.png", "trace.png",
                 "phi.png", "loops.png", "fit.json"):
        assert (out / name).exists(), name
    assert "loops.png, fit.json" in text
    info = json.loads((out / "fit.json").read_text())
    assert info["likelihood"]["residual"] == "motion"
    assert info["tempering"] is None  # the posterior's ensemble alone by default
    assert "parallel tempering" not in text
    rows = {r["name"]: r for r in csv.DictReader(open(out / "summary.csv"))}
    assert all(rows[n]["kind"] == "sampled" for n in ("zeta_B", "tau", "gain"))
    assert "alpha" not in rows  # the motion-in discrepancy is white by default
    assert rows["c_B"]["kind"] == "derived" and "sigma" not in rows and "rho" not in rows
    assert set(info["priors"]) == {n for n, r in rows.items() if r["kind"] == "sampled"}
    iv = info["b_interval"]
    assert iv["method"] == "posterior" and iv["sd_log_sensors"] == iv["sd_log_discrepancy"] == 0.0
    assert f"{iv['lo']:.6g} to {iv['hi']:.6g}" in text
    import arviz as az

    idata = az.from_netcdf(str(out / "posterior.nc"))
    terms = idata.log_likelihood["force_harmonics"]
    assert terms.dims[-1] == "harmonic" and json.loads((out / "loo.json").read_text())["n_points"] == terms.shape[-1]

@pytest.mark.slow
def test_physical_coordinates_keep_the_ridge_move(tmp_path, record_file):
    from bayes_inerter.records import read_record

    res = fit_record(read_record(record_file), tmp_path / "fit", steps=4, walkers=24, coordinates="physical",
                     plots=False)
    info = json.loads((res.out / "fit.json").read_text())
    assert info["coordinates"] == "physical"
    assert any(m.startswith("NutRidgeMove") for m in info["moves"]), info["moves"]


def test_thinned_draws_keep_every_walker_and_space_the_draws_evenly():
    from bayes_inerter.inference.fit import thinned_draws

    values = np.arange(4 * 10 * 2, dtype=float).reshape(4, 10, 2)  # walkers, draws, parameters
    kept = thinned_draws(values, most=20)  # 5 a walker: every second draw
    assert kept.shape == (4, 5, 2) and np.array_equal(kept, values[:, ::2])
    assert np.array_equal(thinned_draws(values, most=1000), values)  # under the cap: all of them
    assert thinned_draws(values, most=1).shape == (4, 1, 2)  # never fewer than one a walker


def test_a_records_fit_can_keep_the_draws_its_summary_comes_from(tmp_path, record_file):
    """``all_draws``: the draws.npz of a single record holds the draws summary.csv's
    numbers are made from (a short chain: none thinned away), where posterior.nc holds
    only those that carry a simulation."""
    from bayes_inerter.inference.fit import ALL_DRAWS_FILE
    from bayes_inerter.records import read_record

    res = fit_record(read_record(record_file), tmp_path / "fit", steps=6, walkers=24, plots=False,
                     all_draws=True, tempering=None)
    rows = {r["name"]: r for r in res.summary}
    with np.load(tmp_path / "fit" / ALL_DRAWS_FILE) as every:
        assert set(every.files) == {n for n, r in rows.items() if r["kind"] == "sampled"}
        for name in every.files:
            assert every[name].shape[0] == 24
            assert float(np.mean(every[name])) == pytest.approx(rows[name]["mean"], rel=1e-12, abs=1e-300)


@pytest.mark.slow
def test_no_adaptation_leaves_the_ensemble_moves_alone(tmp_path, record_file):
    out = tmp_path / "fit"
    assert main(["fit", str(record_file), "--out", str(out), "--steps", "4", "--walkers", "24", "--processes", "1", "--no-plots",
                 "--no-adaptation"]) == 0
    moves = json.loads((out / "fit.json").read_text())["moves"]
    assert moves and not any(m.startswith("IndependenceMove") for m in moves), moves


@pytest.mark.slow  # 3 fits, about a minute; the resume tests check same-seed chains in CI
def test_same_seed_same_summary(tmp_path, record_file):
    from bayes_inerter.records import read_record

    rec = read_record(record_file)
    a = fit_record(rec, tmp_path / "a", steps=20, walkers=24, seed=5, plots=False)
    first = (tmp_path / "a" / "summary.csv").read_bytes()
    c = fit_record(rec, tmp_path / "c", steps=20, walkers=24, seed=6, plots=False)
    assert c.summary[0]["mean"] != a.summary[0]["mean"]
    # the checkpoint gone (a fresh clone keeps fit.json, not chain.h5): the chain starts
    # over from nothing, as a second fresh run with the same seed, and gives the same
    # summary byte for byte; its sampling time is this run's alone, not added to the
    # old fit.json's
    for name in ("chain.h5", "chain.twin.h5"):
        (tmp_path / "a" / name).unlink()
    again = fit_record(rec, tmp_path / "a", steps=20, walkers=24, seed=5, plots=False)
    assert again.timings["sampling_all_runs"] == again.timings["sampling"]
    assert again.timings["steps_timed"] == 20
    assert (tmp_path / "a" / "summary.csv").read_bytes() == first



#: The command line in a process of its own, as ``python -m bayes_inerter.cli`` runs it,
#: with the tests' start search (conftest's SEARCH_SOURCE: a fresh interpreter does not
#: read conftest), so a killed command's chain can be compared with one run here.
COMMAND = [sys.executable, "-c",
           "import sys; " + SEARCH_SOURCE + "from bayes_inerter.cli import main; sys.exit(main(sys.argv[1:]))"]

#: The kill tests stop runs at a step count they watch in chain.h5: they write every step.
EVERY_STEP = ("--checkpoint-seconds", "0")


#: Steps of the kill-and-resume fits: the kill comes at 8, so the finish has most of them to take.
RESUME_STEPS = 24


def _run_until_killed(cmd, chain_file, at_least: int) -> None:
    """Start ``cmd`` and SIGKILL it once its checkpoint holds ``at_least`` steps."""
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.time() + 300
    while time.time() < deadline and proc.poll() is None and steps_written(chain_file) < at_least:
        time.sleep(0.05)
    assert proc.poll() is None, "the run ended before it could be killed"
    os.kill(proc.pid, signal.SIGKILL)
    proc.wait()


def _finish_and_compare(cmd, chain_file, before, tmp_path, record_file) -> None:
    """Run ``cmd`` to the end: exactly its ``--steps``, the killed runs' steps kept, and the
    same chain as a run never interrupted (the killed runs' likelihood: :data:`AR1`)."""
    steps = int(cmd[cmd.index("--steps") + 1])
    assert subprocess.run(cmd, capture_output=True).returncode == 0
    after = _chain(chain_file)
    assert len(after) == steps
    np.testing.assert_array_equal(after[: len(before)], before)
    ref = tmp_path / "uninterrupted"
    assert main(["fit", str(record_file), "--out", str(ref), "--steps", str(steps), "--walkers", "24",
                 "--processes", "1", "--no-plots", "--seed", "3", *AR1]) == 0
    np.testing.assert_array_equal(_chain(ref / "chain.h5"), after)


def test_resume_after_sigkill(tmp_path, ar1_record_file):
    """Killed part-way and run again: exactly the requested steps, earlier steps kept, and
    the same chain as a run that was never interrupted."""
    out = tmp_path / "killed"
    cmd = [*COMMAND, "fit", str(ar1_record_file), "--out", str(out), *AR1, *EVERY_STEP,
           "--walkers", "24", "--processes", "1", "--no-plots", "--seed", "3"]
    # the killed run asks for far more steps than it gets, so that no processor is fast
    # enough to finish between two looks at its checkpoint; the continued run asks for
    # RESUME_STEPS - 8 more than the kill left (a checkpoint's identity leaves --steps out)
    _run_until_killed([*cmd, "--steps", "4000"], out / "chain.h5", 8)
    before = read_chain(out / "chain.h5")
    assert len(before) >= 7
    more = [*cmd, "--steps", str(len(before) + RESUME_STEPS - 8)]
    _finish_and_compare(more, out / "chain.h5", before, tmp_path, ar1_record_file)


@pytest.mark.slow
def test_resume_after_sigkill_with_steps_held_between_writes(tmp_path, ar1_record_file):
    """Written every 0.02 s rather than every step and killed: the steps held since the
    last write are lost and taken again, and the finished chain is the uninterrupted one
    (whose run writes at the default interval)."""
    out = tmp_path / "killed"
    cmd = [*COMMAND, "fit", str(ar1_record_file), "--out", str(out), *AR1,
           "--checkpoint-seconds", "0.02", "--steps", "40", "--walkers", "24", "--processes", "1", "--no-plots", "--seed", "3"]
    _run_until_killed(cmd, out / "chain.h5", 8)
    before = read_chain(out / "chain.h5")
    assert 1 <= len(before) < 40
    _finish_and_compare(cmd, out / "chain.h5", before, tmp_path, ar1_record_file)


@pytest.mark.slow
def test_ctrl_c_on_worker_processes_ends_the_run_with_130_and_keeps_its_steps(tmp_path, ar1_record_file):
    """Ctrl-C goes to the whole process group, the walkers' worker processes included: the
    run must stop (it used to wait for ever for a worker that died of it), say so with
    exit status 130, and leave a checkpoint that a second run continues."""
    out = tmp_path / "interrupted"
    cmd = [*COMMAND, "fit", str(ar1_record_file), "--out", str(out), *AR1, *EVERY_STEP,
           "--steps", "400", "--walkers", "24", "--processes", "2", "--seed", "3", "--no-plots"]
    # a test run in the background of a non-interactive shell (as CI may be) inherits
    # SIGINT ignored, and Python then never turns it into KeyboardInterrupt: give the
    # run a terminal's default, as a user pressing Ctrl-C has
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    deadline = time.time() + 300
    while time.time() < deadline and proc.poll() is None and steps_written(out / "chain.h5") < 5:
        time.sleep(0.05)
    assert proc.poll() is None, "the run ended before it could be interrupted"
    os.killpg(proc.pid, signal.SIGINT)
    try:
        _, err = proc.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.communicate()
        pytest.fail("the run did not stop within 60 s of Ctrl-C")
    assert proc.returncode == 130, err
    assert b"interrupted" in err
    kept = read_chain(out / "chain.h5")
    assert 5 <= len(kept) < 400
    more = [*cmd[:cmd.index("--steps") + 1], str(len(kept) + 3), *cmd[cmd.index("--steps") + 2:]]
    assert subprocess.run(more, capture_output=True).returncode == 0
    np.testing.assert_array_equal(_chain(out / "chain.h5")[: len(kept)], kept)


@pytest.mark.slow  # about 2 minutes; CI keeps the single kill and the write-interrupted cases below
def test_resume_after_sigkill_several_times(tmp_path, ar1_record_file):
    """Killed three times in a row at random steps and run again: exactly the requested
    steps, every earlier step kept, and the same chain as a run never interrupted."""
    out = tmp_path / "killed"
    cmd = [*COMMAND, "fit", str(ar1_record_file), "--out", str(out), *AR1, *EVERY_STEP,
           "--steps", "40", "--walkers", "24", "--processes", "1", "--no-plots", "--seed", "3"]
    chain_file = out / "chain.h5"
    before = None
    for at in sorted(np.random.default_rng(2).integers(4, 34, size=3)):
        _run_until_killed(cmd, chain_file, int(at))
        now = read_chain(chain_file)  # what a continued run keeps (a kill may damage one file)
        assert at - 1 <= len(now) < 40
        if before is not None:  # nothing written before this kill was lost or changed
            np.testing.assert_array_equal(now[: len(before)], before)
        before = now
    _finish_and_compare(cmd, chain_file, before, tmp_path, ar1_record_file)


@pytest.mark.slow
def test_resume_after_many_kills_at_random_moments(tmp_path, ar1_record_file):
    """Killed 12 times at random moments (not at step boundaries: at a seeded random delay
    after the run wrote a new step), run again each time: every intact step is kept and
    the finished chain is the uninterrupted one."""
    out = tmp_path / "killed"
    cmd = [*COMMAND, "fit", str(ar1_record_file), "--out", str(out), *AR1, *EVERY_STEP,
           "--steps", "40", "--walkers", "24", "--processes", "1", "--no-plots", "--seed", "3"]
    chain_file = out / "chain.h5"
    rng = np.random.default_rng(7)
    before = None
    for _ in range(12):
        start = 0 if before is None else len(before)
        proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        while proc.poll() is None and steps_written(chain_file) <= start:
            time.sleep(0.005)  # until the run writes a new step
        time.sleep(rng.uniform(0.0, 0.3))
        if proc.poll() is not None:
            break
        os.kill(proc.pid, signal.SIGKILL)
        proc.wait()
        now = read_chain(chain_file)
        if before is not None:
            assert len(now) >= len(before)
            np.testing.assert_array_equal(now[: len(before)], before)
        before = now
    _finish_and_compare(cmd, chain_file, before, tmp_path, ar1_record_file)


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



def test_masses_resolved_once_are_taken_and_not_given_twice(tmp_path, record_file):
    """The command line resolves the masses once and hands them over (``masses=``); the
    same masses given again as numbers is refused before the folder is touched."""
    from bayes_inerter.masses import resolve_masses
    from bayes_inerter.records import read_record

    rec = read_record(record_file)
    masses = resolve_masses(rec, m_B=60.0)
    out = tmp_path / "never"
    with pytest.raises(ValueError, match="not both"):
        fit_record(rec, out, masses=masses, m_s=masses.m_s, steps=2)
    assert not out.exists()

def _fit(record_file, out, steps, walkers=24):
    return main(["fit", str(record_file), "--out", str(out), "--steps", str(steps), "--walkers", str(walkers),
                 "--processes", "1", "--no-plots"])


@pytest.fixture(scope="module")
def ten_steps(record_file, tmp_path_factory):
    """The chain of an uninterrupted 10-step fit (seed 0, 24 walkers)."""
    out = tmp_path_factory.mktemp("ten") / "fit"
    assert _fit(record_file, out, 10) == 0
    return _chain(out / "chain.h5")


def _damage_numbers(path):
    """Change stored numbers of a valid HDF5 checkpoint (it stays readable)."""
    with h5py.File(path, "r") as f:
        offset = f["mcmc/chain"].id.get_chunk_info(0).byte_offset
    data = bytearray(path.read_bytes())
    data[offset + 8 : offset + 16] = b"\x7f" * 8
    path.write_bytes(bytes(data))
    return bytes(data)


def test_checkpoint_of_another_run_refused(tmp_path, record_file, capsys):
    out = tmp_path / "fit"
    assert _fit(record_file, out, 5) == 0
    capsys.readouterr()
    assert _fit(record_file, out, 10, walkers=26) == 1
    assert "use the same --walkers, or --fresh" in capsys.readouterr().err


@pytest.mark.slow
def test_damaged_checkpoint_with_no_intact_copy_refused(tmp_path, record_file, capsys):
    out = tmp_path / "fit"
    assert _fit(record_file, out, 5) == 0
    capsys.readouterr()
    ck, twin = out / "chain.h5", out / "chain.twin.h5"
    for p in (ck, twin):  # truncated on disk, both
        p.write_bytes(p.read_bytes()[: p.stat().st_size // 3])
    kept = ck.read_bytes(), twin.read_bytes()
    assert _fit(record_file, out, 10) == 1
    err = capsys.readouterr().err
    assert "unreadable or truncated" in err and "no intact copy" in err and err.count("\n") == 1
    assert (ck.read_bytes(), twin.read_bytes()) == kept  # not overwritten
    # both valid HDF5 files whose stored numbers changed: refused too, and left as they are
    out2 = tmp_path / "fit2"
    assert _fit(record_file, out2, 5) == 0
    capsys.readouterr()
    kept = [_damage_numbers(out2 / "chain.h5"), _damage_numbers(out2 / "chain.twin.h5")]
    assert _fit(record_file, out2, 10) == 1
    err = capsys.readouterr().err
    assert "do not match their checksum" in err and err.count("\n") == 1
    assert [(out2 / "chain.h5").read_bytes(), (out2 / "chain.twin.h5").read_bytes()] == kept


# the truncated main file in the quick subset; the twin's changed numbers (the same
# recovery from the other side, 6 s) with the slow tests
@pytest.mark.parametrize("damage", ["truncate chain.h5",
                                    pytest.param("change numbers in chain.twin.h5", marks=pytest.mark.slow)])
def test_damaged_file_moved_aside_and_run_continues_from_its_twin(tmp_path, record_file, capsys, ten_steps, damage):
    out = tmp_path / "fit"
    assert _fit(record_file, out, 5) == 0
    capsys.readouterr()
    name = damage.split()[-1]
    target = out / name
    if damage.startswith("truncate"):
        target.write_bytes(target.read_bytes()[: target.stat().st_size // 3])
        kept = target.read_bytes()
    else:
        kept = _damage_numbers(target)
    assert _fit(record_file, out, 10) == 0
    text = capsys.readouterr().out
    assert f"note: checkpoint damaged, recovered: {name}" in text and f"kept as {name}.damaged" in text
    assert (out / f"{name}.damaged").read_bytes() == kept  # the damaged file is kept, unchanged
    np.testing.assert_array_equal(_chain(out / "chain.h5"), ten_steps)
    np.testing.assert_array_equal(_chain(out / "chain.twin.h5"), ten_steps)
    assert "kept as" in json.loads((out / "fit.json").read_text())["checkpoint_recovered"]


@pytest.mark.slow
def test_kill_between_random_state_and_step_count(tmp_path, record_file, ten_steps):
    """emcee writes a step's random state before it counts the step: a kill in between
    leaves the random state of step k + 1 beside k steps. The run continues from the
    sealed random state and gives the uninterrupted chain."""
    out = tmp_path / "fit"
    assert _fit(record_file, out, 5) == 0
    for p in (out / "chain.h5", out / "chain.twin.h5"):
        with h5py.File(p, "a") as f:
            g = f["mcmc"]
            for i, v in enumerate(np.random.RandomState(99).get_state()):
                g.attrs[f"random_state_{i}"] = v
            g["accepted"][:] += 1
    assert _fit(record_file, out, 10) == 0
    np.testing.assert_array_equal(_chain(out / "chain.h5"), ten_steps)


@pytest.mark.slow
def test_intact_checkpoint_continues(tmp_path, record_file, ten_steps):
    out = tmp_path / "fit"
    assert _fit(record_file, out, 5) == 0
    (out / "chain.twin.h5").unlink()  # a lost twin: the run continues from chain.h5 and writes it again
    assert _fit(record_file, out, 10) == 0
    np.testing.assert_array_equal(_chain(out / "chain.h5"), ten_steps)
    np.testing.assert_array_equal(read_chain(out / "chain.h5"), ten_steps)


def test_steps_held_between_writes_are_counted_read_and_lost_only_to_a_kill(tmp_path):
    from bayes_inerter.inference.sampling.checkpoint import new_checkpoint, open_checkpoint
    from bayes_inerter.inference.sampling.identity import CHECKPOINT_FORMAT

    path = tmp_path / "chain.h5"
    identity = {"format": CHECKPOINT_FORMAT, "nwalkers": 4, "ndim": 2}
    backend = new_checkpoint(path, identity=identity, write_seconds=3600.0)
    rng = np.random.default_rng(0)
    states = [emcee.State(rng.normal(size=(4, 2)), log_prob=rng.normal(size=4), blobs=rng.normal(size=4),
                          random_state=np.random.RandomState(k).get_state()) for k in range(8)]
    backend.grow(8, states[0].blobs)
    for state in states[:5]:
        backend.save_step(state, np.ones(4, dtype=bool))
    assert backend.iteration == 5 and steps_written(path) == 0  # taken, held, not yet written
    np.testing.assert_array_equal(backend.get_chain(), [s.coords for s in states[:5]])  # a read writes them first
    assert steps_written(path) == 5
    assert backend.get_last_sample().random_state[1].tolist() == states[4].random_state[1].tolist()
    for state in states[5:]:
        backend.save_step(state, np.ones(4, dtype=bool))
    assert backend.iteration == 8 and steps_written(path) == 5
    del backend  # killed: the three steps held are lost, the five written are intact
    opened = open_checkpoint(path, identity=identity)
    assert opened.steps == 5 and not opened.recovered
    np.testing.assert_array_equal(read_chain(path), [s.coords for s in states[:5]])
    # written every step with 0 seconds, and the twin brought up to date by flush
    backend = new_checkpoint(tmp_path / "every.h5", identity=identity, write_seconds=0.0)
    backend.grow(3, states[0].blobs)
    for k, state in enumerate(states[:3]):
        backend.save_step(state, np.ones(4, dtype=bool))
        assert steps_written(tmp_path / "every.h5") == k + 1
    backend.flush()
    assert steps_written(tmp_path / "every.twin.h5") == 3
    with pytest.raises(ValueError, match="non-negative"):
        new_checkpoint(tmp_path / "bad.h5", identity=identity, write_seconds=-1.0)
    assert not (tmp_path / "bad.h5").exists()  # refused before any file is made


def test_checkpoint_interval_option(tmp_path, record_file, capsys):
    from bayes_inerter.cli import CHECKPOINT_SECONDS
    from bayes_inerter.inference.sampling.checkpoint import WRITE_SECONDS

    assert CHECKPOINT_SECONDS == WRITE_SECONDS  # written out in the CLI so that parsing imports no emcee
    with pytest.raises(SystemExit) as info:
        main(["fit", str(record_file), "--out", str(tmp_path / "x"), "--checkpoint-seconds", "-1"])
    assert info.value.code == 2 and "non-negative" in capsys.readouterr().err
    assert not (tmp_path / "x").exists()


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


@pytest.mark.slow
def test_reading_the_checkpoint_does_not_stop_a_run(tmp_path, record_file):
    """A reader holding chain.h5 open (with HDF5's default lock) must not make the
    sampler's next write fail."""
    out = tmp_path / "busy"
    args = ["fit", str(record_file), "--out", str(out), "--steps", "6", "--walkers", "24", "--processes", "1", "--no-plots"]
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
