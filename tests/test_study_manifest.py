"""Tests of a results folder's manifest (bayes_inerter.study.manifest)."""

import json

import pytest

from bayes_inerter.study.manifest import MANIFEST, RUN, source_commit, write_manifest


def test_a_run_adds_one_entry_and_a_second_run_another(tmp_path):
    path = write_manifest(tmp_path, {"script": "x.py", "arguments": ["--seed", "1"]})
    write_manifest(tmp_path, {"script": "x.py", "arguments": ["--seed", "1"]})  # the same run writing again
    runs = json.loads(path.read_text())["runs"]
    assert path.name == MANIFEST and len(runs) == 1
    entry = runs[0]
    assert entry["configuration"] == {"script": "x.py", "arguments": ["--seed", "1"]}
    assert entry["run"] == RUN and entry["cores"] >= 1
    assert {"bayes_inerter", "numpy", "emcee", "cpu"} <= set(entry["versions"])
    assert entry["commit"] == source_commit()
    write_manifest(tmp_path, {"script": "x.py", "arguments": ["--seed", "2"]})  # another configuration
    write_manifest(tmp_path, {"script": "x.py", "arguments": ["--seed", "1"]})  # the first again: kept once
    assert len(json.loads(path.read_text())["runs"]) == 2


def test_the_commit_is_the_clones_or_none_outside_one(tmp_path):
    got = source_commit()
    assert got is None or (len(got.removesuffix("-dirty")) >= 7 and all(
        c in "0123456789abcdef" for c in got.removesuffix("-dirty")))
    assert source_commit(tmp_path) is None  # not a clone


def test_a_file_it_did_not_write_is_refused(tmp_path):
    (tmp_path / MANIFEST).write_text("[1, 2]")
    with pytest.raises(ValueError, match="move it aside"):
        write_manifest(tmp_path, {})


def test_what_json_cannot_hold_is_kept_by_its_repr(tmp_path):
    class Settings:
        def __repr__(self):
            return "Settings(seed=3)"

    path = write_manifest(tmp_path, {"settings": Settings(), "replicates": 4})
    write_manifest(tmp_path, {"settings": Settings(), "replicates": 4})  # the same run and configuration
    runs = json.loads(path.read_text())["runs"]
    assert [r["configuration"] for r in runs] == [{"settings": "Settings(seed=3)", "replicates": 4}]
