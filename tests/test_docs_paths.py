"""Every repository path the user guide and the method docs cite exists, and every
results folder has a README: a reader who follows a citation finds what it names."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = [ROOT / "README.md", ROOT / "CHANGELOG.md", *sorted((ROOT / "docs").glob("*.md"))]

# a path from one of the repository's top folders; a glob's * is kept
_PATH = re.compile(r"(?<![\w/.-])((?:results|studies|benchmarks|bayes_inerter|docs|tests|scripts)/[\w./*-]*[\w*])")


def cited_paths(text: str) -> list[str]:
    """The repository paths ``text`` cites, templates (``results/coverage-<family>``,
    ``{name}``) left out."""
    found = []
    for m in _PATH.finditer(text):
        after = text[m.end():m.end() + 2]
        if after.startswith(("<", "{")) or after in ("-<", "-{"):
            continue
        found.append(m.group(1))
    return found


def test_cited_paths_are_found_and_templates_skipped():
    text = "see results/quick/README.md, `studies/prior_tails.py`; results/coverage-<family>/ and docs/*.md."
    assert cited_paths(text) == ["results/quick/README.md", "studies/prior_tails.py", "docs/*.md"]


@pytest.mark.parametrize("doc", DOCS, ids=lambda p: p.name)
def test_every_path_a_doc_cites_exists(doc):
    paths = cited_paths(doc.read_text())
    missing = [p for p in paths if not (any(ROOT.glob(p)) if "*" in p else (ROOT / p).exists())]
    assert not missing, f"{doc.name} cites paths that are not in the repository: {sorted(set(missing))}"


def test_the_docs_cite_paths_at_all():
    # guards the test above against passing on nothing (a pattern that matches no path)
    assert sum(len(cited_paths(d.read_text())) for d in DOCS) > 100


def test_every_results_folder_has_a_readme():
    folders = [d for d in (ROOT / "results").iterdir() if d.is_dir()]
    assert folders
    assert [d.name for d in folders if not (d / "README.md").exists()] == []
