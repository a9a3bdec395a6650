"""A small study end to end: files, resume, a user's folder, failures, Dask."""

import json
import os
import shutil
import signal
from pathlib import Path

import numpy as np
import pytest

from bayes_inerter.cli import main
from bayes_inerter.device import setting as get_setting
from bayes_inerter.inference.sampling import optimize
from bayes_inerter.records import GeneratorSettings
from bayes_inerter.study import FitJob, quick_plan, run_jobs, run_study
from bayes_inerter.study import least_squares as least_squares_module
from bayes_inerter.study import runner as runner_module

#: One worker runs this module (``test.sh``'s ``--dist loadgroup``): the study fixture is
#: the quick subset's longest set-up, and each worker that ran a test of it would run it.
pytestmark = pytest.mark.xdist_group("study_run")

#: 5.5 s at 1 Hz: three steady drive periods after the first, what the study's likelihood
#: (the default, motion in, force out) needs.
TINY = GeneratorSettings(duration=5.5, ramp=0.6)


def tiny_plan(**changes):
    settings = dict(settings=("A0", "A2"), frequencies=(1.0,), steps=8, generator=TINY, comparison=(("A2",), (1.0,)),
                    joint=True, joint_steps=6)
    return quick_plan(**{**settings, **changes})


def _quick_identify(record, out, starts=4, seed=0):
    """study.least_squares.identify_one's output without its fit (seconds a record; its
    own test fits for real)."""
    from pathlib import Path

    info = {"record": Path(record).name, "starts": starts, "seed": seed, "b": 1000.0, "b_interval": [900.0, 1100.0],
            "phi": 0.9}
    Path(out).write_text(json.dumps(info))
    return info


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    out = tmp_path_factory.mktemp("study")
    # one worker process (forked from here, so it sees the patches): two compiled every kernel twice
    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(least_squares_module, "identify_one", _quick_identify)
        # a still lighter start search than conftest's: these tests read the study's files,
        # not its numbers (43 s against 36 s warm, with 8 steps a fit)
        mp.setattr(optimize, "DE_MAXITER", 6)
        mp.setattr(optimize, "NM_MAXITER", 60)
        return run_study(tiny_plan(identify=True), out, processes=1)


def report_head(out):
    """REPORT.md up to its limitations: the answer's screen."""
    return (out / "REPORT.md").read_text().split("## Limitations")[0]


def test_study_writes_tables_figures_and_report(study):
    out = study.out
    for name in ("inertance.csv", "inertance_records.csv", "flywheels.csv", "phi.csv", "model_comparison.csv",
                 "contraction.csv", "theory_vs_identified.png", "phi_map.png", "model_comparison.png", "REPORT.md",
                 "study.json"):
        assert (out / name).is_file(), name
    header = (out / "inertance.csv").read_text().splitlines()[0]
    assert header.startswith("setting,b_theory,b_paper,b_median,b_hdi_3%,b_hdi_97%")
    # the default likelihood samples the sensors' gain: its calibration is not added a second time
    assert "b_cal_hdi_3%" not in header and "b_honest_3%" in header
    # the honest interval per setting, from the fits' own (fit.json), in the report's first table
    assert "b_honest_3%" in header and "honest_records" in header
    assert "honest 94 % interval (kg)" in report_head(out) and "records the model reproduces" in report_head(out)
    assert [o["status"] for o in study.outcomes] == ["done"] * 4  # A0 two-port; A2 two-port, rigid, linear
    report = (out / "REPORT.md").read_text()
    assert "not converged" in report  # 8 steps: the report must say so
    assert "bayes_inerter" in report and "Plan:" in report
    assert {r["model"] for r in study.tables["models"]} == {"linear", "rigid", "two-port"}
    info = json.loads((out / "study.json").read_text())
    assert info["plan"]["steps"] == 8 and info["versions"]["emcee"]
    assert info["plan"]["calibration"] == {"force": 0.0025, "accel": 0.005}
    assert "sensitivities as exact" in report and "--sensor-uncertainty" in report
    # per record, the inertance seen through the nut (what the records fix) beside b, with its coverage
    assert "b_app_hdi_3%" in (out / "inertance_records.csv").read_text().splitlines()[0]
    assert "hold the generating b_app = b (1 + b k_n / c_n^2)" in report and "ambiguity.csv" in report
    # the joint model of both records: one b per setting beside the single-record ones
    assert (out / "joint" / "summary.csv").is_file() and (out / "flywheels_product.csv").is_file()
    assert [r["setting"] for r in study.tables["joint"]] == ["A0", "A2"]
    # inertance.csv's b is the joint model's, the records' product beside it
    assert "b_product_median" in header and [r["estimate"] for r in study.tables["inertance"]] == ["joint"] * 2
    draws = np.load(out / "joint" / "b_draws.npz")
    assert sorted(draws.files) == ["b_A0", "b_A2"]
    a0 = study.tables["inertance"][0]
    assert a0["b_median"] == pytest.approx(np.median(draws["b_A0"]))
    assert "Identified: the joint model of all records" in report
    assert "Joint model" in report and json.loads((out / "joint" / "fit.json").read_text())["iterations"] == 6
    # the paper's least squares of each record, beside its posterior and Table 2
    ls = study.tables["least_squares"]
    assert [r["record"] for r in ls] == ["A0_1Hz", "A2_1Hz"] and all(r["b_ls"] == 1000.0 for r in ls)
    assert all(r["b_paper"] == r["b_truth"] for r in ls)  # generated at the paper's b
    assert (out / "least_squares.csv").is_file() and (out / "least_squares.png").is_file()
    assert sorted(p.name for p in (out / "least_squares").iterdir()) == ["A0_1Hz.json", "A2_1Hz.json"]
    assert "### The paper's least squares beside the posterior" in report and info["seconds"]["least_squares"] > 0


def test_the_study_closes_its_figures_once_saved(study, tmp_path):
    import matplotlib.pyplot as plt

    from bayes_inerter.study.run import _write_figures

    before = set(plt.get_fignums())
    _write_figures(tmp_path, study.tables)
    assert sorted(p.name for p in tmp_path.glob("*.png")) == ["least_squares.png", "model_comparison.png",
                                                              "phi_map.png", "theory_vs_identified.png"]
    assert set(plt.get_fignums()) == before  # a study's figures do not pile up in memory


def test_the_two_port_fits_come_first_with_each_records_seed(tmp_path):
    records = {name: (tmp_path / f"{name}.csv", name[:2], 1.0) for name in ("A0_1Hz", "A2_1Hz", "B2_1Hz")}
    plan = tiny_plan(settings=("A0", "A2", "B2"), comparison=(("A0", "A2"), (1.0,)))
    jobs = plan.jobs(records, tmp_path)
    assert [(j.key, j.seed) for j in jobs] == [
        ("A0_1Hz/two-port", 0), ("A2_1Hz/two-port", 1), ("B2_1Hz/two-port", 2),
        ("A0_1Hz/rigid", 0), ("A0_1Hz/linear", 0), ("A2_1Hz/rigid", 1), ("A2_1Hz/linear", 1)]


def test_the_plans_tempering_reaches_every_single_record_job(tmp_path):
    records = {name: (tmp_path / f"{name}.csv", name[:2], 1.0) for name in ("A0_1Hz", "A2_1Hz")}
    assert {j.tempering for j in tiny_plan(comparison=(("A0",), (1.0,))).jobs(records, tmp_path)} == {None}
    jobs = tiny_plan(comparison=(("A0",), (1.0,)), tempering=3).jobs(records, tmp_path)
    assert len(jobs) == 4 and {j.tempering for j in jobs} == {3}
    with pytest.raises(ValueError, match="at least 2 temperatures"):
        tiny_plan(tempering=1)


def test_a_job_recorded_before_tempering_was_an_option_is_the_untempered_job(tmp_path):
    from dataclasses import asdict

    from bayes_inerter.study.runner import _same_job

    job = FitJob(str(tmp_path / "A0_1Hz.csv"), str(tmp_path / "fit"), steps=4)
    old = {k: v for k, v in asdict(job).items() if k != "tempering"}
    assert _same_job(old, job)
    assert not _same_job(old, FitJob(job.record, job.out, steps=4, tempering=4))
    assert _same_job(asdict(FitJob(job.record, job.out, steps=4, tempering=4)),
                     FitJob(job.record, job.out, steps=4, tempering=4))


def _fit_options(monkeypatch, jobs) -> list[dict]:
    """The options ``run_job`` hands ``fit_record`` for each of ``jobs``, no fit run (the
    plumbing is tested, not a fit)."""
    import bayes_inerter.inference as inference

    seen = []

    def fake_fit(rec, out, **options):
        seen.append(options)
        raise ValueError("stand-in fit")

    monkeypatch.setattr(inference, "fit_record", fake_fit)
    monkeypatch.setattr("bayes_inerter.records.read_record", lambda path: None)
    for job in jobs:
        with pytest.raises(ValueError, match="stand-in fit"):
            runner_module.run_job(job, plots=False)
    return seen


def test_a_jobs_tempering_reaches_its_fit(tmp_path, monkeypatch):
    from bayes_inerter.inference.sampling.tempering import Tempering

    seen = _fit_options(monkeypatch, [FitJob("r.csv", str(tmp_path / "f"), steps=4, tempering=temps)
                                      for temps in (None, 3)])
    assert [options["tempering"] for options in seen] == [None, Tempering(3)]


def test_a_jobs_cap_reaches_its_fit_and_a_job_recorded_without_one_had_fits_cap(tmp_path, monkeypatch):
    from dataclasses import asdict

    from bayes_inerter.inference.sampling.convergence import Convergence
    from bayes_inerter.inference.sampling.tempering import MAX_STEPS
    from bayes_inerter.study.runner import _same_job

    seen = [options["convergence"] for options in _fit_options(
        monkeypatch, [FitJob("r.csv", str(tmp_path / "f"), tempering=temps, max_steps=cap)
                      for cap, temps in ((None, None), (80000, None), (30000, 3))])]
    assert seen[0] is None  # fit's own rule
    assert seen[1] == Convergence(max_steps=80000) and Convergence().max_steps != 80000
    assert seen[2].max_steps == 30000 and MAX_STEPS != 30000
    job = FitJob(str(tmp_path / "A0_1Hz.csv"), str(tmp_path / "fit"))
    old = {k: v for k, v in asdict(job).items() if k != "max_steps"}
    assert _same_job(old, job)
    assert not _same_job(old, FitJob(job.record, job.out, max_steps=80000))


def _copy_of(study, tmp_path):
    """A copy of the module's study folder, for a test that runs into it again (the
    shared folder's REPORT.md and study.json must stay the first run's, whatever order
    the tests run in)."""
    import shutil

    return Path(shutil.copytree(study.out, tmp_path / study.out.name))


def test_running_again_reuses_finished_fits(study, tmp_path):
    out = _copy_of(study, tmp_path)
    first = json.loads((out / "study.json").read_text())
    again = run_study(tiny_plan(), out, processes=1)
    assert [o["status"] for o in again.outcomes] == ["skipped"] * 4
    assert again.tables["inertance"] == study.tables["inertance"]
    # the sampling run's time is kept beside the reuse's
    runs = json.loads((out / "study.json").read_text())["runs"]
    assert runs[:-1] == first["runs"]
    assert runs[-1]["reused"] == 4 and runs[-1]["sampled"] == 0
    assert first["runs"][-1]["sampled"] == 4 and first["runs"][-1]["seconds"] == first["seconds"]
    from bayes_inerter.study.manifest import source_commit

    assert runs[-1]["commit"] == source_commit()  # which source made the numbers


def test_a_study_given_by_another_path_to_its_folder_reuses_its_fits(study, tmp_path, monkeypatch):
    # studies/study.py gives the folder's absolute path; the command line, often a relative one
    out = _copy_of(study, tmp_path)
    monkeypatch.chdir(out.parent)
    again = run_study(tiny_plan(), out.name, processes=1)
    assert [o["status"] for o in again.outcomes] == ["skipped"] * 4


def test_earlier_runs_of_a_study_json_without_them(tmp_path):
    from bayes_inerter.study.run import _earlier_runs

    path = tmp_path / "study.json"
    assert _earlier_runs(path) == []
    path.write_text("{not json")
    assert _earlier_runs(path) == []
    path.write_text(json.dumps({"seconds": {"total": 3.0}, "processes": 2,
                                "outcomes": [{"status": "done"}, {"status": "skipped"}]}))
    assert _earlier_runs(path) == [{"finished": None, "seconds": {"total": 3.0}, "processes": 2,
                                    "sampled": 1, "reused": 1}]


@pytest.mark.slow
def test_a_fresh_clone_of_committed_results_reuses_their_fits(tmp_path, monkeypatch):
    """A fresh clone has done.json, the tables' files and loo.json but not posterior.nc
    or the checkpoints (not committed): the study reuses the fits, model comparison
    included. Without loo.json too, the records of the model comparison are fitted again
    (their LOO cannot be rebuilt) and the others are still reused. Committed studies name
    their folders relative to the clone, as here."""
    (tmp_path / "origin").mkdir()
    monkeypatch.chdir(tmp_path / "origin")
    first = run_study(tiny_plan(), "results/tiny", processes=2)
    assert [o["status"] for o in first.outcomes] == ["done"] * 4

    def clone(name, *dropped):
        shutil.copytree(tmp_path / "origin", tmp_path / name, ignore=shutil.ignore_patterns(*dropped))
        monkeypatch.chdir(tmp_path / name)
        return run_study(tiny_plan(), "results/tiny", processes=2)

    again = clone("clone", "posterior.nc", "chain*.h5", "*.png")
    assert [o["status"] for o in again.outcomes] == ["skipped"] * 4
    assert again.tables["models"] == first.tables["models"]
    assert again.tables["inertance"] == first.tables["inertance"]
    # the joint model's outputs are reused too, without its checkpoint
    # (its summary read back from summary.csv, written with 10 significant digits)
    for a, b in zip(again.tables["joint"], first.tables["joint"], strict=True):
        assert a.keys() == b.keys()
        for key in a:
            if isinstance(b[key], float):
                assert a[key] == pytest.approx(b[key], rel=1e-9, nan_ok=True), key
            else:
                assert a[key] == b[key], key
    assert not (tmp_path / "clone" / "results" / "tiny" / "joint" / "chain.h5").exists()
    # A2 is in the model comparison: its three fits run again; A0's two-port fit alone
    # needs no LOO and is reused
    older = clone("older", "posterior.nc", "chain*.h5", "loo.json")
    status = {o["key"]: o["status"] for o in older.outcomes}
    assert status == {"A0_1Hz/two-port": "skipped", "A2_1Hz/two-port": "done", "A2_1Hz/rigid": "done",
                      "A2_1Hz/linear": "done"}


def test_a_users_folder_of_records(study, tmp_path):
    folder = tmp_path / "mine"
    folder.mkdir()
    for name in ("A2_1Hz.csv", "A2_1Hz.json"):
        shutil.copy(study.out / "records" / name, folder / name)
    res = run_study(tiny_plan(records_dir=str(folder), comparison=((), ())), tmp_path / "out", processes=1)
    assert [r["setting"] for r in res.tables["inertance"]] == ["A2"]
    text = res.report.read_text()
    assert "the records in" in text
    # generated records carry the b they were made with: the report checks against it
    assert "carry the parameters they were generated with" in text
    assert "covers_truth_honest" in res.tables["inertance"][0]
    # a measured record carries none: no truth, the user's wording
    meta = json.loads((folder / "A2_1Hz.json").read_text())
    meta.pop("true_parameters")
    (folder / "A2_1Hz.json").write_text(json.dumps(meta))
    # (the same folder: the fit is reused, only the tables and report are made again)
    res = run_study(tiny_plan(records_dir=str(folder), comparison=((), ())), tmp_path / "out", processes=1)
    assert [o["status"] for o in res.outcomes] == ["skipped"]
    assert "no true inertance is known" in res.report.read_text()
    assert "covers_truth_honest" not in res.tables["inertance"][0]


@pytest.mark.slow
def test_the_joint_model_takes_only_records_that_name_their_setting(study, tmp_path):
    """A record known only by its screw mass has no setting to share a b with: the joint
    model leaves it out (here that leaves one record, so no joint model), and the study
    still finishes."""
    folder = tmp_path / "mixed"
    folder.mkdir()
    for name in ("A2_1Hz.csv", "A2_1Hz.json", "A0_1Hz.csv"):
        shutil.copy(study.out / "records" / name, folder / name)
    meta = json.loads((study.out / "records" / "A0_1Hz.json").read_text())
    meta["m_s"] = get_setting(meta.pop("setting")).m_s
    (folder / "A0_1Hz.json").write_text(json.dumps(meta))
    res = run_study(tiny_plan(records_dir=str(folder), comparison=((), ())), tmp_path / "out", processes=1)
    assert [o["status"] for o in res.outcomes] == ["done", "done"]
    assert "joint" not in res.tables and not (tmp_path / "out" / "joint").exists()


def test_failed_and_dying_jobs_are_reported_and_the_others_finish(study, tmp_path, monkeypatch):
    good = FitJob(str(study.out / "records" / "A0_1Hz.csv"), str(tmp_path / "good"), steps=4)
    missing = FitJob(str(tmp_path / "nope.csv"), str(tmp_path / "missing"), steps=4)
    dying = FitJob(str(study.out / "records" / "A2_1Hz.csv"), str(tmp_path / "dying"), steps=4)
    real = runner_module.run_job

    def run_or_die(job, *args, **kwargs):  # the forked worker of `dying` is killed outright
        if job.out.endswith("dying"):
            os.kill(os.getpid(), signal.SIGKILL)
        return real(job, *args, **kwargs)

    monkeypatch.setattr(runner_module, "run_job", run_or_die)
    by_out = {o["job"]["out"]: o for o in run_jobs([good, missing, dying], processes=2)}
    assert by_out[good.out]["status"] == "done"
    assert by_out[missing.out]["status"] == "failed" and "nope.csv" in by_out[missing.out]["error"]
    assert by_out[dying.out]["status"] == "failed" and "died" in by_out[dying.out]["error"]


@pytest.mark.slow
def test_study_on_a_local_dask_cluster(study, tmp_path):
    distributed = pytest.importorskip("distributed")
    folder = tmp_path / "recs"
    folder.mkdir()
    for name in ("A0_1Hz.csv", "A0_1Hz.json"):
        shutil.copy(study.out / "records" / name, folder / name)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        res = run_study(tiny_plan(records_dir=str(folder), comparison=((), ())), tmp_path / "dask",
                        scheduler=cluster.scheduler_address)
    assert [o["status"] for o in res.outcomes] == ["done"]
    assert (tmp_path / "dask" / "fits" / "two-port" / "A0_1Hz" / "done.json").is_file()


def test_cli_study_refuses_a_sensor_uncertainty_that_is_not_a_small_percentage(tmp_path, capsys):
    code = main(["study", "--quick", "--sensor-uncertainty", "60", "0.5", "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 1 and err.startswith("error: --sensor-uncertainty") and "percentages" in err and "60" in err
    assert "Traceback" not in err and not (tmp_path / "o").exists()


def test_cli_study_takes_the_sensor_uncertainty_in_percent(tmp_path, monkeypatch):
    import bayes_inerter.study as study_pkg

    seen = []

    def fake_run_study(plan, out, **kwargs):
        seen.append(plan)
        raise KeyboardInterrupt  # stop here: only the plan matters

    monkeypatch.setattr(study_pkg, "run_study", fake_run_study)
    assert main(["study", "--quick", "--sensor-uncertainty", "0.25", "1", "--out", str(tmp_path / "o")]) == 130
    assert seen[0].calibration.force == pytest.approx(0.0025) and seen[0].calibration.accel == pytest.approx(0.01)
    assert not seen[0].identify  # the quick study leaves the least squares out unless asked
    assert main(["study", "--quick", "--identify", "--out", str(tmp_path / "o")]) == 130
    assert main(["study", "--no-identify", "--out", str(tmp_path / "o")]) == 130
    assert seen[1].identify and not seen[2].identify
    assert seen[0].tempering is None  # the study's fits: the ensemble alone unless asked
    assert main(["study", "--quick", "--tempering", "3", "--out", str(tmp_path / "o")]) == 130
    assert seen[3].tempering == 3


def test_cli_study_refuses_a_missing_records_folder(tmp_path, capsys):
    code = main(["study", "--records", str(tmp_path / "none"), "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 1 and err.startswith("error:") and "not a folder" in err and "Traceback" not in err
    assert not (tmp_path / "o").exists()


def test_cli_study_says_which_fits_it_reused(tmp_path, monkeypatch, capsys):
    import types

    import bayes_inerter.study as study_pkg

    outcomes = [{"key": "A0_1Hz/two-port", "status": "skipped", "converged": True},
                {"key": "A3_1Hz/two-port", "status": "done", "converged": True}]
    result = types.SimpleNamespace(tables={"inertance": []}, outcomes=outcomes, report=tmp_path / "o" / "REPORT.md",
                                   seconds={"total": 1.0})
    monkeypatch.setattr(study_pkg, "run_study", lambda plan, out, **kwargs: result)
    assert main(["study", "--quick", "--out", str(tmp_path / "o")]) == 0
    text = capsys.readouterr().out
    assert f"reused 1 of 2 fits finished earlier in {tmp_path / 'o'}" in text and "another --out" in text
    outcomes[0]["status"] = "done"  # nothing reused: nothing said about it
    assert main(["study", "--quick", "--out", str(tmp_path / "o")]) == 0
    assert "reused" not in capsys.readouterr().out


def test_report_answers_first_and_flags_its_limits(study):
    report = (study.out / "REPORT.md").read_text()
    heads = [line for line in report.splitlines() if line.startswith("## ")]
    assert heads[:3] == ["## Inertance per flywheel setting", "## Limitations", "## Details"]
    first = report.split("## Limitations")[0]
    assert "| setting | theory (kg) | paper (kg) | identified (kg) | 94 % interval (kg) |" in first
    assert "theory_vs_identified.png" in first and "Identified: the joint model" in first
    limits = report.split("## Limitations")[1].split("## Details")[0]
    assert "generated by this package from the model it fits" in limits
    assert "did not meet the convergence criteria" in limits  # 8 steps
    assert report.count("samples the sensors' relative gain") == 1
    assert "These intervals take the sensors' sensitivities as exact" not in report


@pytest.mark.slow  # 7 s: per-fit figures drawn again; test_fit_writes_every_output draws them in the quick subset
def test_report_command_draws_the_figures_again(study, capsys):
    fit = study.out / "fits" / "two-port" / "A0_1Hz"
    for png in fit.glob("*.png"):
        png.unlink()
    assert main(["report", str(fit)]) == 0
    assert "drew the figures of 1 of 1 fits" in capsys.readouterr().out
    assert {p.name for p in fit.glob("*.png")} == {"corner.png", "bands.png", "trace.png", "phi.png", "loops.png"}
    (fit / "chain.h5").rename(fit / "kept.h5")
    try:
        assert main(["report", str(fit)]) == 1
        assert "no checkpoint here" in capsys.readouterr().out
    finally:
        (fit / "kept.h5").rename(fit / "chain.h5")


def test_a_joint_fit_of_another_likelihood_is_not_reused(tmp_path):
    """finished_joint matches an earlier joint fit by its records, seed and likelihood
    settings: one sampled under another likelihood (the AR(1) residual before the
    motion-in default, say) is sampled again, not read back."""
    import dataclasses

    from bayes_inerter.inference.fit import DRAWS_FILE, joint_records
    from bayes_inerter.inference.posterior.joint import JointModel
    from bayes_inerter.records.generator import paper_record
    from bayes_inerter.study.run import finished_joint

    recs = [paper_record(s, 1.0, seed=1) for s in ("A0", "A2")]
    jm = JointModel(tuple(recs))
    plan = tiny_plan()
    info = {"records": joint_records(jm), "seed": plan.seed, "converged": True, "iterations": plan.joint_steps,
            "likelihood": dataclasses.asdict(jm.likelihood)}
    (tmp_path / "summary.csv").write_text("name,kind,median\nb_A0,physical,700.0\n")
    np.savez(tmp_path / DRAWS_FILE, b_A0=np.ones(4))
    (tmp_path / "fit.json").write_text(json.dumps(info))
    assert finished_joint(tmp_path, recs, plan) is not None
    (tmp_path / "fit.json").write_text(json.dumps({**info, "likelihood": {"residual": "ar1"}}))
    assert finished_joint(tmp_path, recs, plan) is None
    # a fit written before the reversals' switch existed kept their deviations: reused
    older = {k: v for k, v in info["likelihood"].items() if k != "reversals"}
    (tmp_path / "fit.json").write_text(json.dumps({**info, "likelihood": older}))
    assert finished_joint(tmp_path, recs, plan) is not None


def test_cli_study_caps_chains_run_until_converged(tmp_path, monkeypatch, capsys):
    import bayes_inerter.study as study_pkg

    seen = []

    def fake_run_study(plan, out, **kwargs):
        seen.append(plan)
        raise KeyboardInterrupt  # stop here: only the plan matters

    monkeypatch.setattr(study_pkg, "run_study", fake_run_study)
    assert main(["study", "--max-steps", "80000", "--out", str(tmp_path / "o")]) == 130
    assert main(["study", "--quick", "--max-steps", "900", "--out", str(tmp_path / "o")]) == 130
    assert (seen[0].steps, seen[0].max_steps) == (None, 80000)
    assert (seen[1].steps, seen[1].max_steps) == (None, 900)  # the quick study's fixed steps give way
    capsys.readouterr()
    code = main(["study", "--steps", "50", "--max-steps", "900", "--out", str(tmp_path / "p")])
    err = capsys.readouterr().err
    assert code == 1 and err.startswith("error: --steps") and "give one of them" in err
    assert "Traceback" not in err and not (tmp_path / "p").exists() and len(seen) == 2


def test_a_plan_takes_fixed_steps_or_a_cap_not_both():
    with pytest.raises(ValueError, match="give one of them"):
        tiny_plan(max_steps=900)  # tiny_plan fixes the steps
    with pytest.raises(ValueError, match="max_steps must be a positive whole number"):
        tiny_plan(steps=None, max_steps=0)
    assert tiny_plan(steps=None, max_steps=900).max_steps == 900
