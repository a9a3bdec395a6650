"""The full study's library form (``study.full``): its configuration, the paper-like
records it fits, the chains' sentence, and the report made again from committed results."""

import json
import shutil
import subprocess
from pathlib import Path

import pytest

from bayes_inerter.cli import main
from bayes_inerter.executor import Serial
from bayes_inerter.study.full import MORE, Config, chains_sentence, paper_like_records, run

RESULTS = Path(__file__).resolve().parents[1] / "results"


def test_the_configuration_refuses_too_few_steps():
    with pytest.raises(ValueError, match="at least 20"):
        Config(paper_like_steps=5)
    with pytest.raises(ValueError, match="whole number of temperatures"):
        Config(tempering=0)
    with pytest.raises(ValueError, match="max_steps must be a whole number of at least 100"):
        Config(max_steps=50)


def _plans_run(monkeypatch) -> list:
    """The plans ``run`` hands its studies, in order, none of them run (the plumbing is
    tested, not a study)."""
    import types

    from bayes_inerter.study import full

    plans = []

    def fake_run_study(plan, folder, **_):
        plans.append(plan)
        return types.SimpleNamespace(outcomes=[], seconds={"total": 0.0})

    monkeypatch.setattr(full, "run_study", fake_run_study)
    monkeypatch.setattr(full, "paper_like_records", lambda folder, seed: folder)
    monkeypatch.setattr(full, "_report", lambda out, seed: out / "REPORT.md")
    return plans


def test_the_cap_reaches_every_single_record_chain_of_both_studies(tmp_path, monkeypatch):
    plans = _plans_run(monkeypatch)
    run(Config(max_steps=80000), tmp_path, Serial())
    assert [p.max_steps for p in plans] == [80000, 80000]
    assert all(job.max_steps == 80000 for job in plans[0].jobs({"A0_1Hz": ("A0_1Hz.csv", "A0", 1.0)}, tmp_path))
    run(Config(max_steps=80000, paper_like_steps=300), tmp_path, Serial())
    assert (plans[2].steps, plans[2].max_steps) == (300, None)  # fixed steps: no cap to read
    assert (plans[3].steps, plans[3].max_steps) == (None, 80000)


def test_tempering_reaches_every_single_record_fit_of_both_studies(tmp_path, monkeypatch):
    plans = _plans_run(monkeypatch)
    run(Config(tempering=4), tmp_path, Serial())
    headline, control = plans  # the headline first
    assert headline.records_dir is not None and control.records_dir is None
    assert control.tempering == headline.tempering == 4
    assert control.joint and not headline.joint  # the joint model itself is not tempered
    run(Config(tempering=1), tmp_path, Serial())
    assert plans[2].tempering is None  # one temperature: the ensemble alone
    assert Config().tempering is None  # as fit: the ensemble alone


def test_the_paper_like_records_are_those_generate_writes(tmp_path):
    mine = paper_like_records(tmp_path / "mine", seed=3)
    assert main(["generate", "--paper-grid", "--truth", "paper-like", "--seed", "3", "--out",
                 str(tmp_path / "cli")]) == 0
    names = sorted(p.name for p in mine.glob("*.csv"))
    assert len(names) == 27 and names == sorted(p.name for p in (tmp_path / "cli").glob("*.csv"))
    for name in names:
        assert (mine / name).read_bytes() == (tmp_path / "cli" / name).read_bytes()
    stamp = (mine / names[0]).stat().st_mtime_ns
    assert paper_like_records(mine, seed=4) == mine and (mine / names[0]).stat().st_mtime_ns == stamp  # kept


def test_chains_sentence_counts_the_converged_two_port_chains(tmp_path):
    for k, (converged, steps) in enumerate([(True, 4000), (False, 20000)]):
        folder = tmp_path / "fits" / "two-port" / f"r{k}"
        folder.mkdir(parents=True)
        (folder / "fit.json").write_text(json.dumps({"converged": converged, "iterations": steps,
                                                     "timings_s": {"total": 30.0 + 60 * k}}))
    text = chains_sentence(tmp_path)
    assert text.startswith("1 of the 2 two-port chains met") and "4,000 to 20,000 steps" in text
    assert "a median 60 s and at most 90 s" in text and "(2 minutes in all" in text
    assert "indicative" in text and chains_sentence(tmp_path / "none") == ""


def test_report_only_remakes_the_committed_report(tmp_path):
    if subprocess.run(["git", "-C", str(RESULTS), "status", "--porcelain", "full"], capture_output=True,
                      text=True).stdout.strip():
        pytest.skip("results/full has changes not committed")
    for name in ("full", *MORE):  # the study's folder and those whose sections its report takes in
        if (RESULTS / name).is_dir():
            shutil.copytree(RESULTS / name, tmp_path / "results" / name,
                            ignore=shutil.ignore_patterns("*.h5", "*.nc", "records", "*.png"))
    got = run(Config(report_only=True), tmp_path / "results" / "full", Serial())
    (report,) = got.written
    assert report.read_text() == (RESULTS / "full" / "REPORT.md").read_text()


def test_report_only_without_a_study_says_what_to_do(tmp_path):
    with pytest.raises(ValueError, match="run the study without report_only first"):
        run(Config(report_only=True), tmp_path / "full", Serial())
