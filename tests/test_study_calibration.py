"""Simulation-based calibration: the small version CI runs (the pipeline, not the verdict;
results/calibration holds the study's run)."""

import json
from dataclasses import dataclass
from typing import ClassVar

import pytest

from bayes_inerter.inference.posterior.likelihood import LikelihoodSettings
from bayes_inerter.records import GeneratorSettings
from bayes_inerter.study.calibration import (RUNNING, CalibrationSettings, compare_calibrations, coverage_table,
                                            replicate, run_calibration, run_replicates)

#: One worker runs this module (``test.sh``'s ``--dist loadgroup``): each worker that ran a
#: test of the calibration fixture would make it.
pytestmark = pytest.mark.xdist_group("study_calibration")

TINY = CalibrationSettings(steps=30, draws=9, generator=GeneratorSettings(duration=2.0, ramp=0.6))


@pytest.fixture(scope="module")
def calibration(tmp_path_factory):
    out = tmp_path_factory.mktemp("sbc")
    return out, run_calibration(TINY, out, 3, processes=1)  # one worker: two compile each kernel twice


def test_writes_ranks_coverage_and_report(calibration):
    """The pipeline, not the search: the test suite's short start search (conftest's
    TEST_SEARCH) may end at a point of zero density on a 2 s record, which way depending
    on the processor's arithmetic; such a replicate is named as failed and the others
    are kept."""
    out, res = calibration
    for name in ("ranks.csv", "coverage.csv", "ranks.png", "REPORT.md", "settings.json"):
        assert (out / name).is_file()
    assert res["replicates"] >= 1 and res["replicates"] + len(res["failed"]) == 3
    # the one failure the processor's arithmetic may bring; any other is a bug
    assert all("zero posterior density" in f["error"] for f in res["failed"]), res["failed"]
    names = [r["parameter"] for r in res["coverage"]]
    assert names == ["b", "f_0", "f_share", "c_f", "c_share", "c_n", "k_n", "c_B", "k_B", "sigma", "rho"]
    ran = [k for k in range(3) if k not in {f["replicate"] for f in res["failed"]}]
    for k in ran:
        rep = json.loads((out / "replicates" / f"{k:04d}.json").read_text())
        assert all(0 <= r <= TINY.draws for r in rep["ranks"].values())
        assert all(rep["in50"][n] <= rep["in90"][n] for n in rep["in50"])  # the 50 % interval lies inside the 90 %


@pytest.mark.slow
def test_same_seed_same_replicate_and_a_rerun_reuses_them(calibration):
    out, res = calibration
    stamp = {p.name: p.stat().st_mtime_ns for p in (out / "replicates").iterdir()}
    again = run_calibration(TINY, out, 3, processes=1)
    assert {p.name: p.stat().st_mtime_ns for p in (out / "replicates").iterdir()} == stamp
    assert again["coverage"] == res["coverage"]
    k = min(set(range(3)) - {f["replicate"] for f in res["failed"]})
    assert replicate(TINY, k) == json.loads((out / "replicates" / f"{k:04d}.json").read_text())


def test_other_settings_in_the_same_folder_are_refused(calibration):
    out, _ = calibration
    with pytest.raises(ValueError, match="other calibration settings"):
        run_calibration(CalibrationSettings(steps=31, draws=9), out, 1)


def test_settings_saved_before_a_new_option_existed_still_match(calibration):
    """A settings.json written before an option existed (here the generator's
    noise_corner) holds the option's default: the same settings, not other ones."""
    import json

    out, _ = calibration
    path = out / "settings.json"
    original = path.read_text()
    saved = json.loads(original)
    del saved["generator"]["noise_corner"]
    path.write_text(json.dumps(saved))
    assert run_calibration(TINY, out, 3, processes=1)["replicates"] == calibration[1]["replicates"]
    saved["generator"]["noise_corner"] = 20.0  # a real difference is still refused
    path.write_text(json.dumps(saved))
    with pytest.raises(ValueError, match="other calibration settings"):
        run_calibration(TINY, out, 3, processes=1)
    path.write_text(original)  # the module's other tests share this folder


def test_cases_compared_side_by_side(calibration):
    out, res = calibration
    report = compare_calibrations(out.parent)
    text = report.read_text()
    assert f"| {out.name} (n = {res['replicates']}," in text and "| b |" in text
    assert (out.parent / "coverage.png").is_file()


def test_coverage_counts():
    reps = [{"replicate": k, "L": 9, "ranks": {"b": k % 10}, "in50": {"b": k < 5}, "in90": {"b": k < 9}}
            for k in range(10)]
    (row,) = coverage_table(reps + [{"replicate": 10, "error": "boom"}])
    assert row["replicates"] == 10 and row["coverage_50"] == 0.5 and row["coverage_90"] == 0.9
    assert row["se_90"] == pytest.approx((0.9 * 0.1 / 10) ** 0.5)
    assert row["rank_chi2_p"] == pytest.approx(1.0)  # one draw in each of the 10 bins: perfectly uniform


@dataclass(frozen=True)
class _Resuming:
    """Settings whose replicates run in a work folder they are given (as
    ``StudyCalibration``'s do): the folder is where a stopped replicate's fit is kept."""

    resumes: ClassVar[bool] = True
    seed: int = 0

    def replicate(self, k, folder=None):
        return {"replicate": k, "folder": str(folder)}


@dataclass(frozen=True)
class _Plain:
    seed: int = 0

    def replicate(self, k):
        return {"replicate": k}


def test_a_resuming_replicate_is_given_a_work_folder_under_the_run(tmp_path):
    got = run_replicates(_Resuming(), tmp_path / "a", 2)
    assert [r["folder"] for r in got] == [str(tmp_path / "a" / RUNNING / f"{k:04d}") for k in range(2)]
    assert run_replicates(_Plain(), tmp_path / "b", 2) == [{"replicate": 0}, {"replicate": 1}]
    got = run_replicates(_Resuming(), tmp_path / "c", 1, work=tmp_path / "elsewhere")  # a checkpoint kept apart
    assert got[0]["folder"] == str(tmp_path / "elsewhere" / "0000")


@dataclass(frozen=True)
class _Checkpointing:
    """Settings whose replicate leaves a chain in its work folder, or fails after it."""

    resumes: ClassVar[bool] = True
    seed: int = 0
    fail: bool = False

    def replicate(self, k, folder=None):
        (folder / "fit").mkdir(parents=True)
        (folder / "fit" / "chain.h5").write_bytes(b"steps")
        if self.fail:
            raise RuntimeError("only 50 posterior draws kept")
        return {"replicate": k}


def test_a_work_folder_goes_once_its_result_is_written_and_stays_where_it_failed(tmp_path, monkeypatch):
    from bayes_inerter.study import calibration

    work = tmp_path / "work"
    run_replicates(_Checkpointing(), tmp_path / "a", 1, work=work)
    assert (tmp_path / "a" / "replicates" / "0000.json").is_file() and not (work / "0000").exists()
    run_replicates(_Checkpointing(fail=True), tmp_path / "b", 1, work=work)
    assert (work / "0000" / "fit" / "chain.h5").is_file()  # the failed replicate's chain, for a look

    def no_disk(out, k, result):
        raise OSError("No space left on device")

    monkeypatch.setattr(calibration, "write_replicate", no_disk)
    with pytest.raises(OSError):
        run_replicates(_Checkpointing(), tmp_path / "c", 1, work=tmp_path / "w2")
    assert (tmp_path / "w2" / "0000" / "fit" / "chain.h5").is_file()  # the chain kept for the next run


def test_a_work_folder_of_another_run_is_refused_before_any_fit_starts(tmp_path):
    from bayes_inerter.study.calibration import WORK_STAMP, stamped_folder, work_stamp

    work = tmp_path / "work"
    stamped_folder(work / "0001", work_stamp(_Checkpointing(), tmp_path / "a"))  # replicate 1's chain, run a's
    with pytest.raises(ValueError, match="another run .*out"):
        run_replicates(_Checkpointing(), tmp_path / "b", 2, work=work)
    assert not (tmp_path / "b" / "replicates" / "0000.json").exists()  # not even replicate 0 fitted
    assert not (work / "0000").exists()
    # the cap is no part of the stamp: a chain stopped under a cap goes on under a raised one,
    # also where an earlier version stamped it
    assert "max_steps" not in work_stamp(_Checkpointing(), tmp_path / "a")
    earlier = {**work_stamp(_Checkpointing(), tmp_path / "a"), "max_steps": 20000}
    (work / "0001" / WORK_STAMP).write_text(json.dumps(earlier))
    assert stamped_folder(work / "0001", work_stamp(_Checkpointing(), tmp_path / "a")) == work / "0001"
    (work / "0001" / WORK_STAMP).unlink()  # a chain left by code before the stamp is taken, and stamped
    assert stamped_folder(work / "0001", work_stamp(_Checkpointing(), tmp_path / "b")) == work / "0001"
    assert json.loads((work / "0001" / WORK_STAMP).read_text())["out"] == str((tmp_path / "b").resolve())


@dataclass(frozen=True)
class _Partnered:
    """Settings with a block-moves choice whose default changed after runs were saved."""

    seed: int = 0
    block_partners: str = "correlated"

    def replicate(self, k):
        return {"replicate": k}


def test_a_run_saved_before_the_block_moves_setting_goes_on_with_random_blocks(tmp_path):
    run_replicates(_Partnered(), tmp_path, 1)
    saved = json.loads((tmp_path / "settings.json").read_text())
    (tmp_path / "settings.json").write_text(json.dumps({k: v for k, v in saved.items() if k != "block_partners"}))
    with pytest.raises(ValueError, match="other calibration settings"):
        run_replicates(_Partnered(), tmp_path, 2)
    assert run_replicates(_Partnered(block_partners="random"), tmp_path, 2)[1] == {"replicate": 1}
    assert run_replicates(_Plain(), tmp_path / "plain", 1) == [{"replicate": 0}]  # settings without the field


def test_a_result_file_is_written_whole_and_leaves_nothing_beside_it(tmp_path):
    from bayes_inerter.study.output import write_json

    write_json(tmp_path / "0001.json", {"replicate": 1, "b": 3531.6}, indent=1)
    assert json.loads((tmp_path / "0001.json").read_text()) == {"replicate": 1, "b": 3531.6}
    assert (tmp_path / "0001.json").read_text().endswith("}\n")
    assert [p.name for p in tmp_path.iterdir()] == ["0001.json"]


@dataclass(frozen=True)
class _Likelihood:
    """A calibration whose fits take a likelihood (its replicates are stand-ins)."""

    likelihood: LikelihoodSettings = LikelihoodSettings()

    def replicate(self, k):
        return {"replicate": k}


def test_a_run_saved_before_the_model_form_terms_holds_them_at_0(tmp_path):
    """A settings.json saved before the likelihood's model-form terms existed was fitted
    without them: it holds them at 0 (``identity.LATER_LIKELIHOOD``), so it goes on
    under a likelihood without them and is refused by one that takes them."""
    run_replicates(_Likelihood(), tmp_path, 1)
    saved = json.loads((tmp_path / "settings.json").read_text())
    assert saved["likelihood"]["form_sd"] == 0 and saved["likelihood"]["form_friction"] == 0
    saved["likelihood"] = {k: v for k, v in saved["likelihood"].items() if k not in ("form_sd", "form_friction")}
    (tmp_path / "settings.json").write_text(json.dumps(saved))
    with pytest.raises(ValueError, match="other calibration settings"):
        run_replicates(_Likelihood(LikelihoodSettings(form_sd=0.005)), tmp_path, 2)
    assert run_replicates(_Likelihood(), tmp_path, 2)[1] == {"replicate": 1}
