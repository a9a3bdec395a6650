"""A study's finished replicates (``study.replicate_store``): loose files and the packed
file read alike, packing keeps every replicate and removes the loose files, a replicate
in both is refused, and the studies read a packed folder as they read a loose one."""

import gzip
import json
import subprocess
import sys
from pathlib import Path

import pytest

from bayes_inerter.executor import Serial
from bayes_inerter.study.paper_like_coverage import Config, run
from bayes_inerter.study.replicate_store import (LOOSE, PACKED, PLAIN, finished, is_packed, load_replicates, pack,
                                                 replicate_path, unpack)

ROOT = Path(__file__).resolve().parents[1]


def _write(out, reps):
    (out / LOOSE).mkdir(parents=True, exist_ok=True)
    for r in reps:
        replicate_path(out, r["replicate"]).write_text(json.dumps(r))


def test_packing_keeps_every_replicate_in_order_and_removes_the_loose_files(tmp_path):
    reps = [{"replicate": k, "value": k * 1.5, "nested": {"z": k, "a": [k]}} for k in (3, 0, 12, 1)]
    _write(tmp_path, reps)
    before = finished(tmp_path)
    assert [r["replicate"] for r in before] == [0, 1, 3, 12]
    assert pack(tmp_path) == 4
    assert not (tmp_path / LOOSE).exists()
    assert len(gzip.decompress((tmp_path / PACKED).read_bytes()).decode().splitlines()) == 4
    after = finished(tmp_path)
    assert after == before
    assert [(list(r), list(r["nested"])) for r in after] == [(list(r), list(r["nested"])) for r in before]  # order too: tables follow it


def test_a_run_continued_into_a_packed_folder_reads_both(tmp_path):
    _write(tmp_path, [{"replicate": 0}, {"replicate": 1}])
    pack(tmp_path)
    _write(tmp_path, [{"replicate": 2}])
    assert sorted(load_replicates(tmp_path)) == [0, 1, 2]
    assert pack(tmp_path) == 3 and not (tmp_path / LOOSE).exists()


def test_packing_again_writes_the_same_bytes(tmp_path):
    _write(tmp_path, [{"replicate": k, "x": k / 3} for k in range(5)])
    pack(tmp_path)
    first = (tmp_path / PACKED).read_bytes()
    unpack(tmp_path)
    pack(tmp_path)
    assert (tmp_path / PACKED).read_bytes() == first  # no time in the gzip header: a repack changes nothing


def test_a_plain_packed_file_is_read_and_gzipped_by_packing(tmp_path):
    reps = [{"replicate": k, "x": [k]} for k in (2, 0)]
    (tmp_path / PLAIN).write_text("".join(json.dumps(r) + "\n" for r in reps) + "\n")
    assert is_packed(tmp_path) and finished(tmp_path) == sorted(reps, key=lambda r: r["replicate"])
    _write(tmp_path, [{"replicate": 5}])
    assert pack(tmp_path) == 3
    assert not (tmp_path / PLAIN).exists() and (tmp_path / PACKED).exists()
    assert [r["replicate"] for r in finished(tmp_path)] == [0, 2, 5]


def test_one_replicate_both_packed_and_loose_is_refused(tmp_path):
    _write(tmp_path, [{"replicate": 0, "run": "first"}])
    pack(tmp_path)
    _write(tmp_path, [{"replicate": 0, "run": "second"}])
    with pytest.raises(ValueError, match="replicate 0 .* both in replicates.jsonl.gz and in replicates/0000.json"):
        load_replicates(tmp_path)
    (tmp_path / PLAIN).write_text(json.dumps({"replicate": 0, "run": "third"}) + "\n")
    with pytest.raises(ValueError, match="replicate 0 .* both in replicates.jsonl.gz and in replicates.jsonl"):
        load_replicates(tmp_path)


def test_unpack_restores_the_loose_files(tmp_path):
    reps = [{"replicate": k, "x": [k, k + 1]} for k in range(3)]
    _write(tmp_path, reps)
    pack(tmp_path)
    assert unpack(tmp_path) == 3
    assert not is_packed(tmp_path)
    assert [json.loads(replicate_path(tmp_path, k).read_text()) for k in range(3)] == reps


def test_an_empty_folder_has_nothing_to_pack(tmp_path):
    with pytest.raises(ValueError, match="nothing to pack"):
        pack(tmp_path)


def test_a_packed_paper_like_folder_remakes_the_same_tables(tmp_path):
    reps = finished(ROOT / "results" / "coverage-paper-like-v5")
    loose, packed = tmp_path / "loose", tmp_path / "packed"
    for folder in (loose, packed):
        _write(folder, reps)
    pack(packed)
    for folder in (loose, packed):
        run(Config(summarise=True), folder, Serial())
    for name in ("replicates.csv", "coverage.csv"):
        assert (packed / name).read_bytes() == (loose / name).read_bytes()
    assert not (packed / LOOSE).exists()


def test_the_script_reports_a_missing_folder_in_one_line(tmp_path):
    got = subprocess.run([sys.executable, str(ROOT / "studies" / "pack_replicates.py"), str(tmp_path / "nope")],
                         capture_output=True, text=True)
    assert got.returncode == 2
    assert got.stderr.strip().count("\n") == 0 and "not a folder" in got.stderr
