"""Every repository path the user guide, the method docs and the results folders' READMEs
cite exists, and every results folder has a README that names a live command: a reader
who follows a citation finds what it names."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", ROOT / "CHANGELOG.md", *sorted((ROOT / "docs").glob("*.md"))]

# a path from one of the repository's top folders; a glob's * is kept
_PATH = re.compile(r"(?<![\w/.-])((?:results|studies|benchmarks|bayes_inerter|docs|tests|scripts)/[\w./*-]*[\w*])")


def cited_paths(text: str) -> list[str]:
    """The repository paths ``text`` cites, templates (``results/coverage-<family>``,
    ``{name}``) and a command's output folders (after ``--out`` or ``--work``, which a
    run makes) left out."""
    found = []
    for m in _PATH.finditer(text):
        after = text[m.end():m.end() + 2]
        if after.startswith(("<", "{")) or after in ("-<", "-{"):
            continue
        if re.search(r"--(out|work)[ =]$", text[max(0, m.start() - 7):m.start()]):
            continue
        found.append(m.group(1))
    return found


def test_cited_paths_are_found_and_templates_and_outputs_skipped():
    text = ("see results/quick/README.md, `studies/prior_tails.py`; results/coverage-<family>/ and docs/*.md; "
            "run it with --out results/new-folder or --work=runs/x.")
    assert cited_paths(text) == ["results/quick/README.md", "studies/prior_tails.py", "docs/*.md"]


def exists(path: str) -> bool:
    """Whether ``path`` (a glob where it holds ``*``) names something in the repository."""
    if "*" not in path:
        return (ROOT / path).exists()
    try:
        return any(ROOT.glob(path))
    except ValueError:  # "a**b", which pathlib refuses: read as "a*b"
        return any(ROOT.glob(re.sub(r"\*+", "*", path)))


@pytest.mark.parametrize("doc", DOCS, ids=lambda p: p.name)
def test_every_path_a_doc_cites_exists(doc):
    paths = cited_paths(doc.read_text())
    missing = [p for p in paths if not exists(p)]
    assert not missing, f"{doc.name} cites paths that are not in the repository: {sorted(set(missing))}"


def test_the_docs_cite_paths_at_all():
    # guards the test above against passing on nothing (a pattern that matches no path)
    assert sum(len(cited_paths(d.read_text())) for d in DOCS) > 100


RESULTS = sorted(d for d in (ROOT / "results").iterdir() if d.is_dir())
# a command that makes a results folder: a script of the repository, or the command line
_COMMAND = re.compile(r"(?:studies|benchmarks)/\w+\.py|run\.sh|bayes-inerter ")


def test_every_results_folder_has_a_readme():
    assert RESULTS
    assert [d.name for d in RESULTS if not (d / "README.md").exists()] == []


@pytest.mark.parametrize("folder", [d for d in RESULTS if (d / "README.md").exists()], ids=lambda d: d.name)
def test_every_results_readme_names_a_live_command_and_existing_paths(folder):
    text = (folder / "README.md").read_text()
    missing = [p for p in cited_paths(text) if not exists(p)]
    assert not missing, f"results/{folder.name}/README.md cites paths that are not in the repository: {missing}"
    scripts = [m.group(0) for m in _COMMAND.finditer(text)]
    assert scripts, f"results/{folder.name}/README.md names no command that makes it"
    dead = [s for s in scripts if s.endswith(".py") and not (ROOT / s).exists()]
    assert not dead, f"results/{folder.name}/README.md names scripts that are not there: {dead}"
