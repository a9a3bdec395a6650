"""The composed report (study.headline): the headline study first, the folder's own
study kept as its control."""

import pytest

from bayes_inerter.study.headline import CONTROL_FILE, write_headline

HEADLINE = """# Study `full`: the inertance of each flywheel setting

Fitted: the records in `records`; 2 posteriors.

## Inertance per flywheel setting

| setting | honest 94 % interval (kg) |
| A3 | 3400 to 3600 |

![theory against identification](theory_vs_identified.png)

## Limitations

- The records carry the parameters they were generated with.

## Details

### Each record on its own

records table

### Fit accuracy phi (the paper's Table 2, with uncertainty)

| setting | phi_mean | phi_paper |

![phi heat map](phi_map.png)

### The paper's least squares beside the posterior

least squares table

![least squares beside the posterior](least_squares.png)

### Model comparison

loo table
"""

CONTROL = "# Study `full`: the inertance of each flywheel setting\n\nthe ideal device's answer\n"


@pytest.fixture
def folders(tmp_path):
    out = tmp_path / "full"
    (out / "paper-like").mkdir(parents=True)
    (out / "paper-like" / "REPORT.md").write_text(HEADLINE)
    (out / "REPORT.md").write_text(CONTROL)
    return out


def test_headline_leads_and_the_study_becomes_the_control(folders):
    path = write_headline(folders, folders / "paper-like", title="Paper-like", summary="Why these records.")
    text = path.read_text()
    assert (folders / CONTROL_FILE).read_text() == CONTROL
    order = [text.index(s) for s in ("# Paper-like", "Why these records.", "## Inertance per flywheel setting",
                                     "### Fit accuracy phi", "## Limitations", "## The ideal-device control")]
    assert order == sorted(order)
    # the figures are linked from the headline study's folder; its details stay there
    assert "](paper-like/theory_vs_identified.png)" in text and "](paper-like/phi_map.png)" in text
    assert "records table" not in text and "loo table" not in text
    assert f"]({CONTROL_FILE})" in text


def test_the_least_squares_and_other_studies_sections_are_taken_in(folders):
    structure = folders.parent / "structure"
    structure.mkdir()
    (structure / "SECTION.md").write_text("## Why b differs from theory\n\n![fit](structure.png)\n")
    text = write_headline(folders, folders / "paper-like", title="T", summary="S",
                          more=[structure / "SECTION.md", folders / "missing.md"]).read_text()
    order = [text.index(s) for s in ("least squares table", "## Limitations", "## Why b differs from theory",
                                     "## The ideal-device control")]
    assert order == sorted(order)
    assert "](paper-like/least_squares.png)" in text and "](../structure/structure.png)" in text


def test_composing_again_keeps_the_control(folders):
    first = write_headline(folders, folders / "paper-like", title="T", summary="S").read_text()
    second = write_headline(folders, folders / "paper-like", title="T", summary="S").read_text()
    assert first == second
    assert (folders / CONTROL_FILE).read_text() == CONTROL
    # a study run into the folder again writes its own report: that becomes the control
    (folders / "REPORT.md").write_text(CONTROL + "rerun\n")
    write_headline(folders, folders / "paper-like", title="T", summary="S")
    assert (folders / CONTROL_FILE).read_text().endswith("rerun\n")


def test_missing_studies_are_named(tmp_path):
    with pytest.raises(FileNotFoundError, match="run the headline study first"):
        write_headline(tmp_path, tmp_path / "nothing", title="T", summary="S")
    (tmp_path / "h").mkdir()
    (tmp_path / "h" / "REPORT.md").write_text(HEADLINE)
    with pytest.raises(FileNotFoundError, match="no control study"):
        write_headline(tmp_path, tmp_path / "h", title="T", summary="S")
