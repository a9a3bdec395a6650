"""Committed text names no folder of the machine that wrote it, and the numbers the
docs quote from a committed result are that result's.

The files are git's (``git ls-files``), so a run left untracked in the tree is not
checked; each checker is also tried on a planted example, so a check that cannot fail
is caught."""

import csv
import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
#: What is checked: text files under these (paths relative to the repository).
CHECKED = ("results", "docs", "README.md", "CHANGELOG.md")
SUFFIXES = (".md", ".csv", ".json", ".txt")
#: An absolute path of a machine: a Unix home, scratch or work folder, a macOS home, a
#: Windows drive. Not inside a relative path (``runs/tmp/`` is fine) nor a URL's path.
MACHINE_PATH = re.compile(r"(?<![\w.~-])/(?:work|tmp|home|root|Users)/|(?<![\w/])[A-Za-z]:\\")
#: docs/reproducibility.md's sentence quoting results/quick's b's.
QUOTED = re.compile(r"`results/quick/inertance\.csv` now holds ([^;]+);")


def machine_paths(text: str) -> list[tuple[int, str]]:
    """(line number, line) of each line of ``text`` that holds an absolute path of a machine."""
    return [(i, line.strip()) for i, line in enumerate(text.splitlines(), 1) if MACHINE_PATH.search(line)]


def committed_names(root: Path, *under: str) -> list[str]:
    """The committed (tracked) files of ``root`` (relative, posix), those ``under`` the
    given paths if any; the test is skipped outside a git checkout."""
    try:
        out = subprocess.run(["git", "ls-files", "-z", "--", *under], cwd=root, capture_output=True, text=True,
                             check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("not a git checkout: no list of committed files")
    return [name for name in out.split("\0") if name]


def committed_text_files(root: Path = ROOT) -> list[Path]:
    """The committed (tracked) text files of :data:`CHECKED` under ``root``."""
    return [root / name for name in committed_names(root, *CHECKED) if name.endswith(SUFFIXES)]


def quoted_b_mismatches(doc: str, rows: list[dict]) -> list[str]:
    """Each b ``doc`` quotes as results/quick's (``A0 752.422``) that is not the row's
    ``b_median`` to the digits quoted; an error if ``doc`` quotes none."""
    found = QUOTED.search(doc)
    if not found:
        return ["no sentence quoting `results/quick/inertance.csv`'s b's"]
    quoted = re.findall(r"\b([AB]\d) (\d+(?:\.\d+)?)\b", found.group(1))
    if not quoted:
        return [f"no b's in {found.group(0)!r}"]
    by_setting = {r["setting"]: float(r["b_median"]) for r in rows}
    bad = []
    for setting, text in quoted:
        decimals = len(text.partition(".")[2])
        if setting not in by_setting:
            bad.append(f"{setting}: not in results/quick/inertance.csv")
        elif f"{by_setting[setting]:.{decimals}f}" != text:
            bad.append(f"{setting}: the doc says {text}, results/quick/inertance.csv holds {by_setting[setting]}")
    return bad


@pytest.mark.parametrize("text", [
    "Fitted: the records in `/work/main/results/full/paper-like/records`.",
    "--out /tmp/rich/rec.csv",
    '"records_dir": "/home/someone/records"',
    "cd /root/project",
    "see /Users/name/Desktop/run1.csv",
    r"C:\Users\name\run1.csv",
    r'"path": "D:\\data\\run1.csv"',
    "file:///tmp/x.html",
])
def test_a_machine_path_is_found(text):
    assert machine_paths("first line\n" + text) == [(2, text.strip())]


@pytest.mark.parametrize("text", [
    "Fitted: the records in [`records`](records).",
    "runs/tmp/quick and results/work/x are relative",
    "https://github.com/home/project and a ratio 1:3",
    "time=Zeit,force=Kraft",
])
def test_relative_paths_and_urls_are_not(text):
    assert machine_paths(text) == []


def test_a_planted_file_is_caught(tmp_path):
    """The listing and the check together: a committed file with an absolute path is
    named, an untracked one is not."""
    def git(*args):
        subprocess.run(["git", *args], cwd=tmp_path, check=True, capture_output=True)

    try:
        git("init", "-q")
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("no git")
    (tmp_path / "results" / "study").mkdir(parents=True)
    (tmp_path / "results" / "study" / "REPORT.md").write_text("the records in `/work/main/records`\n")
    (tmp_path / "results" / "study" / "fig.png").write_bytes(b"/tmp/ in a binary file")
    (tmp_path / "README.md").write_text("relative only\n")
    git("add", "results", "README.md")
    (tmp_path / "results" / "untracked.md").write_text("/tmp/x\n")
    files = committed_text_files(tmp_path)
    assert sorted(p.relative_to(tmp_path).as_posix() for p in files) == ["README.md", "results/study/REPORT.md"]
    assert [p.name for p in files if machine_paths(p.read_text())] == ["REPORT.md"]


def test_committed_text_names_no_machine_path():
    files = committed_text_files()
    assert any(p.name == "REPORT.md" for p in files)  # the listing found the results
    found = {p.relative_to(ROOT).as_posix(): hits for p in files
             if (hits := machine_paths(p.read_text(encoding="utf-8", errors="replace")))}
    assert not found, "absolute paths of a machine in committed text (write them relative):\n" + "\n".join(
        f"{name}:{i}: {line[:160]}" for name, hits in found.items() for i, line in hits)


def _quick_rows() -> list[dict]:
    with open(ROOT / "results" / "quick" / "inertance.csv", newline="") as f:
        return list(csv.DictReader(f))


def test_the_docs_quote_results_quick_as_committed():
    doc = (ROOT / "docs" / "reproducibility.md").read_text()
    assert quoted_b_mismatches(doc, _quick_rows()) == []


def test_a_stale_quote_is_caught():
    rows = [{"setting": "A0", "b_median": "752.422"}, {"setting": "B2", "b_median": "20258.8"}]
    ok = "and `results/quick/inertance.csv` now holds A0 752.422 and B2 20259, its `b_median`;"
    assert quoted_b_mismatches(ok, rows) == []
    stale = "and `results/quick/inertance.csv` now holds A0 752.577 and B2 20258.9, its `b_median`;"
    assert quoted_b_mismatches(stale, rows) == [
        "A0: the doc says 752.577, results/quick/inertance.csv holds 752.422",
        "B2: the doc says 20258.9, results/quick/inertance.csv holds 20258.8"]
    assert quoted_b_mismatches("no numbers quoted", rows) != []
    assert quoted_b_mismatches("`results/quick/inertance.csv` now holds A7 1.0;", rows) == [
        "A7: not in results/quick/inertance.csv"]


#: A path the user guide or docs/ cite, under one of the repository's own folders.
CITED = re.compile(r"(?<![\w/.-])((?:results|studies|benchmarks|docs|bayes_inerter|tests|scripts)/[\w./-]*[\w/])")
#: What follows the stem of a path with a placeholder.
PLACEHOLDER = re.compile(r"[\w./-]*[<{*]")
#: A script or command a results folder's README can name as what made it.
MAKER = re.compile(r"\b((?:studies|benchmarks|scripts)/[\w-]+\.py)\b|\bbayes-inerter \w+|\brun\.sh\b")


def tracked_paths(root: Path = ROOT) -> set[str]:
    """Every committed file of ``root`` and every folder that holds one (relative, posix)."""
    paths = set()
    for name in committed_names(root):
        parts = name.split("/")
        paths.update("/".join(parts[:i]) for i in range(1, len(parts) + 1))
    return paths


def missing_citations(text: str, paths: set[str]) -> list[str]:
    """The paths ``text`` cites that are not among ``paths`` (a placeholder's stem, as in
    ``results/coverage-<family>/``, is not a citation)."""
    missing = []
    for m in CITED.finditer(text):
        if PLACEHOLDER.match(text, m.end()):
            continue
        path = m.group(1).rstrip("/.")
        if path not in paths:
            missing.append(path)
    return sorted(set(missing))


def test_a_missing_citation_is_caught():
    paths = {"docs", "docs/studies.md", "results", "results/quick", "results/quick/inertance.csv"}
    text = ("see docs/studies.md and `results/quick/inertance.csv`, `results/coverage-<family>/`; "
            "python studies/long_chain.py writes results/long-chain/.")
    assert missing_citations(text, paths) == ["results/long-chain", "studies/long_chain.py"]


def test_every_path_the_guide_and_docs_cite_is_committed():
    """A renamed module, a removed study or a deleted results folder leaves no citation
    behind in README.md or docs/ (CHANGELOG.md is history and may name what is gone)."""
    paths = tracked_paths()
    assert "results/quick/inertance.csv" in paths  # the listing found the results
    found = {}
    for doc in [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]:
        if missing := missing_citations(doc.read_text(encoding="utf-8"), paths):
            found[doc.relative_to(ROOT).as_posix()] = missing
    assert not found, f"cited but not in the repository: {found}"


def unmade_results(root: Path, paths: set[str]) -> list[str]:
    """The folders directly under ``root``/results without a committed README, or whose
    README names no script that is committed (nor the command line, nor run.sh)."""
    bad = []
    for folder in sorted(p for p in paths if p.count("/") == 1 and p.startswith("results/")):
        if folder + "/README.md" not in paths:
            if any(p.startswith(folder + "/") for p in paths):  # a folder, not a file
                bad.append(f"{folder}: no README.md")
            continue
        makers = MAKER.findall((root / folder / "README.md").read_text(encoding="utf-8"))
        scripts = [m for m in makers if m]  # "" where the command line or run.sh made it
        if not makers or (scripts and not any(s in paths for s in scripts)):
            bad.append(f"{folder}: its README names no committed script ({', '.join(scripts) or 'none'})")
    return bad


def test_a_results_folder_without_its_maker_is_caught(tmp_path):
    paths = {"results", "results/a", "results/a/README.md", "results/b", "results/b/README.md", "results/c",
             "results/c/t.csv", "results/d", "results/d/README.md", "results/x.md", "studies", "studies/a.py"}
    (tmp_path / "results" / "a").mkdir(parents=True)
    (tmp_path / "results" / "a" / "README.md").write_text("python studies/a.py --out results/a\n")
    (tmp_path / "results" / "b").mkdir()
    (tmp_path / "results" / "b" / "README.md").write_text("python studies/gone.py\n")
    (tmp_path / "results" / "d").mkdir()
    (tmp_path / "results" / "d" / "README.md").write_text("made by `bayes-inerter study --out results/d`\n")
    assert unmade_results(tmp_path, paths) == ["results/b: its README names no committed script (studies/gone.py)",
                                               "results/c: no README.md"]


def test_every_results_folder_names_the_script_that_makes_it():
    paths = tracked_paths()
    assert "results/quick/README.md" in paths
    assert unmade_results(ROOT, paths) == []


# --- docs without history: no dated runs in the methods -----------------------------------

DATE = re.compile(r"\b20\d\d-[01]\d-[0-3]\d\b")
#: Docs whose dates are data: the performance tables, generated from the CSV rows that
#: carry each measurement's date (``benchmarks/performance_table.py``).
DATED_DATA = ("performance.md",)


def dated_lines(text: str) -> list[str]:
    """Lines of ``text`` that name a calendar date (a run's day belongs in CHANGELOG.md)."""
    return [line for line in text.splitlines() if DATE.search(line)]


def test_a_dated_line_is_caught():
    assert dated_lines("measured on 2026-11-25 (8 min)\nmeasured from rows\n") == ["measured on 2026-11-25 (8 min)"]
    assert dated_lines("a record of 2026 samples, seed 11-25") == []


def test_the_docs_and_the_guide_name_no_run_by_its_date():
    pages = [p for p in (ROOT / "docs").glob("*.md") if p.name not in DATED_DATA] + [ROOT / "README.md"]
    found = {p.name: dated_lines(p.read_text()) for p in pages}
    assert {k: v for k, v in found.items() if v} == {}
