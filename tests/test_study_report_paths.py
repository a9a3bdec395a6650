"""A study's report names its records' folder relative to itself, and a composed report
(study.headline) keeps that name pointing at the folder: committed reports name no
folder of the machine that made them."""

from bayes_inerter.study.headline import write_headline
from bayes_inerter.study.plan import StudyPlan
from bayes_inerter.study.report import shown_path, write_report


def test_shown_path_is_relative_to_the_report(tmp_path):
    assert shown_path(tmp_path / "study" / "records", tmp_path / "study") == "records"
    assert shown_path(tmp_path / "records", tmp_path / "full" / "study") == "../../records"


def test_report_and_headline_name_the_records_relative_to_themselves(tmp_path):
    full = tmp_path / "full"
    study = full / "paper-like"
    (study / "records").mkdir(parents=True)
    plan = StudyPlan(name="full", records_dir=str((study / "records").resolve()))
    text = write_report(study, plan, {}, [], {"bayes_inerter": "0"}, {"A3": 3531.6}).read_text()
    assert str(tmp_path) not in text
    assert "Fitted: the records in [`records`](records);" in text
    assert "The records ([`records`](records)) carry" in text
    assert "records_dir='records'" in text and "(`records_dir` relative to this folder)" in text
    (full / "REPORT.md").write_text("# the control study\n")
    composed = write_headline(full, study, title="Paper-like", summary="Why.").read_text()
    assert "The records ([`paper-like/records`](paper-like/records)) carry" in composed
    assert str(tmp_path) not in composed


def test_study_json_names_the_records_relative_to_the_working_folder(tmp_path, monkeypatch):
    from bayes_inerter.study.run import _portable

    (tmp_path / "mine" / "records").mkdir(parents=True)
    monkeypatch.chdir(tmp_path)
    assert _portable(str(tmp_path / "mine" / "records")) == "mine/records"
    assert _portable("mine/records") == "mine/records"
    outside = tmp_path.parent / "elsewhere"
    assert _portable(str(outside)) == str(outside)  # not inside: as given
