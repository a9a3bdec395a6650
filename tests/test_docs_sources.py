"""Every measured number in docs/ names where it was measured (issue 41, item 4): a reader
who meets a number in the method docs can find the committed file, study or test it
comes from.

The rule, paragraph by paragraph (paragraphs are separated by blank lines; tables,
fenced code blocks and headings are left out of them, and tables are checked by rule 5):

1. **A measured number** is, in the paragraph's text with its line breaks made spaces,

   - a number followed by ``%``, ``x`` (``2.2x``), or the word ``ms``, ``s``, ``us``,
     ``µs``, ``times``, ``nat(s)``, ``steps``, ``min``, ``minutes``, ``h``, ``hour(s)``
     (``27 %``, ``0.64 ms``, ``1,103 s``, ``8.4 times``, ``10.8 nats``, ``9,500 steps``);
   - a number with a decimal point next to a physical unit: ``kg``, ``N``, ``N/m``,
     ``N s/m``, ``mm``, ``m``, ``g`` (``3,502.6 kg``, ``0.23 N``; ``57.2 kg``).

   That is ``MEASURED`` below. Hertz are left out (0.5, 1 and 1.5 Hz are the drive's
   settings, 1 kHz the sampling's), and so are four conventions that are never a
   measurement (``CONVENTION``): ``94 %``, the package's interval level (arviz's
   default) and the chi-square arithmetic made with it; ``3 % to 97 %`` (or ``and``),
   the quantiles that bound that interval; ``10 s record``, the records' length; and
   ``9.80665 m/s^2``, standard gravity (the definition by which a record in g is read).

2. **Its source** is named in the same paragraph (``SOURCE``): a ``results/...`` path, a
   ``*.csv`` file, or a ``benchmarks/``, ``studies/`` or ``tests/`` path (the command or
   test that measures it). In docs/performance.md a paragraph may instead rely on its
   ``## section``, whose first line names ``results/performance/<section>.csv`` (made
   by ``benchmarks/performance_table.py`` from those files; checked below).

3. **The narrow escape for numbers that are not measurements** (arithmetic, definitions,
   settings, defaults, the paper's Table I): a number is not counted where its clause
   (the text between ``.`` or ``;`` and the next, a sentence or a part of one) cites
   ``MODEL.md`` (``../shared/MODEL.md``, the model and Table I's values), or names in
   backticks a constant of the package whose value it is: an upper-case name
   (``motion.FUNDAMENTAL_MAX``, ``BACKLASH_RAMP``) assigned at the top level of a
   module of ``bayes_inerter`` (of the module named before the dot, where one is).
   Clause, not paragraph: a constant named beside a setting does not excuse the
   measurements in the paragraph's other sentences.

4. **No allow-list.** A paragraph with a measured number for which no committed source
   is found (a session's scratch measurement, printed and not kept) is measured again
   with its command committed, or moved verbatim to CHANGELOG.md ("History:
   measurements behind the method docs"), the docs keeping the decision it led to
   without it. The allow-list that once excused such paragraphs emptied as they moved,
   and went.

5. **Tables.** A table is a run of consecutive lines starting with ``|`` whose second
   line is the delimiter row (``| --- | --- |``), as markdown reads one; a line
   starting with ``|`` that begins no table (``|1 / z|, ...``) is paragraph text. Every
   row of a table but the header (which names the quantities: ``b 3-50-97 %``) and the
   delimiter is read cell by cell, each cell as a paragraph's text is (rules 1 and 3:
   its clauses, ``CONVENTION``, the escape for ``MODEL.md`` and the package's
   constants), and its measured numbers are

   - the ``MEASURED`` numbers, and
   - any other number with a decimal point (``-4.72``, ``0.94``, ``1.7e-10``): in a
     table the unit or the quantity is in the header or the caption, so a bare
     ``20.7`` in a row is as measured as ``20.7 nats`` in a sentence (hertz left out
     here too: ``A6 0.5 Hz`` names a record). Integers alone (``6 of 12``,
     ``292 (k_n)``) do not count: counts and step numbers stand beside decimals or
     units in every measured table in docs/.

   A table with a measured number has its source (``SOURCE``) in the table itself or in
   the paragraph immediately before it, its caption (only blank lines between; not
   across a heading or code); in docs/performance.md its ``## section`` may name it
   instead (rule 2). The paragraph after a table does not count: it is the next
   paragraph's text, whose source may be for another measurement. The check cannot
   tell whose numbers a caption's source is for; a caption that cites another
   measurement is read by hand (the first pass moved the five whose neighbour cited
   another measurement). The escape of rule 3 excuses a cell only where that
   cell cites the constant or MODEL.md, so a table of settings says what it is in its
   header instead (``SETTINGS_HEADER``): a header
   cell that is exactly ``default`` marks the table as stating defaults, not
   measurements (the assumptions tables of docs/assumptions.md, the checks'
   thresholds of docs/records.md), and it is not checked. A comparison of measured
   variants must therefore not head a column ``default`` alone: it names what it
   measured (``b's error, default``, ``both (default)``). As for paragraphs (rule 4), a
   table without a committed source is measured again or moved to CHANGELOG.md with
   its caption.

6. **A cited CSV exists.** Every ``*.csv`` a paragraph or table names is in the
   repository: a ``results/...`` path as written, a bare name (``geometry.csv``) as a
   file somewhere under results/. Left out: names in capitals (``RECORD.csv``, a
   placeholder for the user's file) and, in paragraphs, names in a clause (rule 3's)
   that states no measured number (a command's outputs described, which it may write
   under runs/). So a
   number cannot rest on a file that was never committed or has been removed, which
   rule 2 alone (a script's name is a source) would let pass.

7. **Counts are measured numbers** in paragraphs: ``N of M`` (``15 of 33``, ``9 of the
   27 records``) counts as rule 1's numbers do, so a sentence of counts needs its
   source as one of per cents does.
"""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = sorted((ROOT / "docs").glob("*.md"))

_NUM = r"(?<![\w.])\d[\d,]*(?:\.\d+)?"
MEASURED = re.compile(
    _NUM + r"(?:\s?%|x\b|\s?(?:ms|s|us|µs|times|nats?|steps|minutes|min|hours?|h)\b)"
    r"|(?<![\w.])\d[\d,]*\.\d+\s?(?:kg|N/m|N s/m|N|mm|m|g)\b")
# rule 7: a count, "15 of 33" or "9 of the 27"
COUNT = re.compile(r"(?<![\w.,])\d[\d,]* of (?:the )?\d[\d,]*\b")
CONVENTION = re.compile(r"\b94 %|\b3 % (?:to|and) 97 %|\b\d+ s records?\b|(?<![\w.])9\.80665 m/s\^2")
# in a table, any number with a decimal point (rule 5)
DECIMAL = re.compile(r"(?<![\w.])\d[\d,]*\.\d+(?![\d.]|\s?k?Hz\b)")
# a delimiter row, the second line of a markdown table
DELIMITER = re.compile(r"^\|?\s*:?-+:?\s*(?:\|\s*:?-+:?\s*)*\|?$")
# a header cell that marks a table of settings (rule 5)
SETTINGS_HEADER = "default"
SOURCE = re.compile(r"(?<![\w/.-])(?:results|benchmarks|studies|tests)/[\w./*-]*|[\w./-]+\.csv\b")
_MODEL = re.compile(r"\bMODEL\.md\b")
_CODE_CONSTANT = re.compile(r"`(?:[\w.]*?(\w+)\.)?([A-Z][A-Z0-9_]{2,})\b[^`]*`")

# (doc, the paragraph's first 40 characters, why it has no source)


def blocks(text: str) -> list[tuple[str, str, str]]:
    """``text``'s paragraphs and tables in order, as (kind, the ``## `` section they are
    in, the text): kind ``"paragraph"`` (blank-line separated), ``"table"`` (rule 5) or
    ``"break"`` (a heading or a fenced code block, which nothing reads across)."""
    out, cur, fence, section = [], [], False, ""
    lines = text.splitlines()

    def close():
        if cur:
            out.append(("paragraph", section, "\n".join(cur)))
            cur.clear()

    i = 0
    while i < len(lines):
        line = lines[i]
        stripped = line.strip()
        i += 1
        if stripped.startswith("```"):
            close()
            if not fence:
                out.append(("break", section, ""))
            fence = not fence
            continue
        if fence:
            continue
        if not stripped or stripped.startswith("#"):
            close()
            if stripped.startswith("#"):
                if stripped.startswith("## "):
                    section = stripped[3:].strip()
                out.append(("break", section, ""))
            continue
        if stripped.startswith("|") and i < len(lines) and DELIMITER.match(lines[i].strip()):
            close()
            rows = [stripped]
            while i < len(lines) and lines[i].strip().startswith("|"):
                rows.append(lines[i].strip())
                i += 1
            out.append(("table", section, "\n".join(rows)))
            continue
        cur.append(line)
    close()
    return out


def paragraphs(text: str) -> list[tuple[str, str]]:
    """``text``'s paragraphs as (the ``## `` section they are in, the paragraph), blank-line
    separated; tables, fenced code and headings left out."""
    return [(section, t) for kind, section, t in blocks(text) if kind == "paragraph"]


def tables(text: str) -> list[tuple[str, str, str, str]]:
    """``text``'s tables as (section, the paragraph immediately before, the table, the
    paragraph immediately after); a neighbour across a heading or code is ``""``."""
    found = blocks(text)
    out = []
    for n, (kind, section, t) in enumerate(found):
        if kind != "table":
            continue
        before = found[n - 1][2] if n > 0 and found[n - 1][0] == "paragraph" else ""
        after = found[n + 1][2] if n + 1 < len(found) and found[n + 1][0] == "paragraph" else ""
        out.append((section, before, t, after))
    return out


def _constants() -> dict[str, set[str]]:
    """Each upper-case name assigned at a module's top level in the package: the modules
    (file stems, a package's folder name for its ``__init__``) that assign it."""
    found: dict[str, set[str]] = {}
    for path in (ROOT / "bayes_inerter").rglob("*.py"):
        module = path.parent.name if path.stem == "__init__" else path.stem
        for name in re.findall(r"^([A-Z][A-Z0-9_]{2,})\s*(?::[^=\n]*)?=", path.read_text(), re.M):
            found.setdefault(name, set()).add(module)
    return found


CONSTANTS = _constants()


def _excused(clause: str) -> bool:
    """Whether ``clause`` cites MODEL.md or names a constant of the package in backticks."""
    if _MODEL.search(clause):
        return True
    for m in _CODE_CONSTANT.finditer(clause):
        module, name = m.group(1), m.group(2)
        if name in CONSTANTS and (module is None or module in CONSTANTS[name]):
            return True
    return False


def measured_numbers(paragraph: str, decimals: bool = False) -> list[str]:
    """The measured numbers ``paragraph`` states (rules 1, 3 and 7 of the module docstring);
    with ``decimals``, a table's cell (rule 5): also its other numbers with a decimal
    point, and not its counts."""
    flat = " ".join(paragraph.split())
    found = []
    for clause in clauses(flat):
        if not _excused(clause):
            text = CONVENTION.sub("", clause)
            found += MEASURED.findall(text) + ([] if decimals else COUNT.findall(text))
            if decimals:
                found += DECIMAL.findall(MEASURED.sub(" ", text))
    return found


def _cells(row: str) -> list[str]:
    return [c.strip() for c in row.strip().strip("|").split("|")]


def table_numbers(table: str) -> list[str]:
    """The measured numbers a table states (rule 5): none in a table of settings."""
    rows = [r for r in table.splitlines() if not DELIMITER.match(r.strip())]
    if any(c.lower() == SETTINGS_HEADER for c in _cells(rows[0])):
        return []
    return [n for row in rows[1:] for cell in _cells(row) for n in measured_numbers(cell, decimals=True)]


def names_source(paragraph: str) -> bool:
    return bool(SOURCE.search(paragraph))


def _section_csv(doc: Path, section: str) -> bool:
    return doc.name == "performance.md" and (ROOT / "results" / "performance" / f"{section}.csv").is_file()


def unsourced(doc: Path) -> list[str]:
    """The paragraphs of ``doc`` that state a measured number and name no source."""
    return [p for section, p in paragraphs(doc.read_text())
            if measured_numbers(p) and not names_source(p) and not _section_csv(doc, section)]


def sourced_table(caption: str, table: str) -> bool:
    """Whether a table or its caption (the paragraph just before it) names a source."""
    return names_source(caption) or names_source(table)


def unsourced_tables(doc: Path) -> list[str]:
    """The tables of ``doc`` that state a measured number and name no source in
    themselves or their caption (rule 5)."""
    return [t for section, before, t, _ in tables(doc.read_text())
            if table_numbers(t) and not sourced_table(before, t) and not _section_csv(doc, section)]


# rule 6: a CSV named, with its results/ path or bare
_CSV = re.compile(r"(?<![\w/.-])((?:results/[\w./-]+/)?([\w.-]+\.csv))\b")
_COMMITTED_CSV = {p.name for p in (ROOT / "results").rglob("*.csv")}


def missing_csvs(block: str, measured: bool) -> list[str]:
    """The CSVs ``block`` (a paragraph or a table) names that are not in the repository
    (rule 6); none where it states no ``measured`` number."""
    if not measured:
        return []
    out = []
    for path, name in _CSV.findall(block):
        if name[:-4].isupper():
            continue
        if not ((ROOT / path).is_file() if path.startswith("results/") else name in _COMMITTED_CSV):
            out.append(path)
    return out


def clauses(paragraph: str) -> list[str]:
    """``paragraph``'s clauses (rule 3: the text between ``.`` or ``;`` and the next)."""
    return re.split(r"(?<=[.;])\s+", " ".join(paragraph.split()))


def test_the_classifier_on_made_up_paragraphs():
    sourced = ("On the six design records the slowest tau fell from 416 to 67 steps "
               "(results/chain-geometry, `geometry.csv`).")
    bare = "On the six design records the slowest tau fell from 416 to 67 steps, b moved 0.1 %."
    assert measured_numbers(sourced) and names_source(sourced)
    assert measured_numbers(bare) == ["67 steps", "0.1 %"] and not names_source(bare)
    # conventions, settings and Table I's values are not measurements
    assert measured_numbers("b's 94 % interval (3 % to 97 %) on a 10 s record at 0.5 Hz") == []
    assert measured_numbers("With m_B = 57.2 kg (Table I, ../shared/MODEL.md) and p = 20 mm: a sum.") == []
    assert measured_numbers("at least 0.2 % of a period (`reversals.MIN_HALF_WIDTH`). It took 4 s.") == ["4 s"]
    # a constant counts only where the package defines it, in the module named
    assert measured_numbers("a ramp over 10 % of the gap (`NO_SUCH_CONSTANT`)") == ["10 %"]
    assert measured_numbers("a ramp over 10 % of the gap (`motion.BACKLASH_RAMP`)") == ["10 %"]
    assert measured_numbers("a ramp over 10 % of the gap (`BACKLASH_RAMP`)") == []


def test_paragraphs_leave_out_tables_code_and_headings():
    text = ("## one\n\nA 5 % text\nsecond line\n\n| a | b |\n| --- | --- |\n| 3 % | row |\n\n"
            "```\n7 %\n```\n\n## two\nlast 2 s\n|x| is 4 %\n")
    assert paragraphs(text) == [("one", "A 5 % text\nsecond line"), ("two", "last 2 s\n|x| is 4 %")]
    assert tables(text) == [("one", "A 5 % text\nsecond line", "| a | b |\n| --- | --- |\n| 3 % | row |", "")]


def test_the_classifier_on_made_up_tables():
    table = ("| record | largest tau | b's error (3 %, 50 %, 97 %) |\n| --- | --- | --- |\n"
             "| A6 0.5 Hz | 292 (k_n) | -4.72, -3.21, -1.12 % |\n| B1 0.5 Hz | 219 (k_n) | -0.75 |")
    sourced = ("Chains on paper-like design records (results/chain-geometry, `geometry.csv`):", table,
               "The text after it.")
    bare = ("Chains on paper-like design records (laboratory seed 11):", table, "The text after it.")
    assert table_numbers(table) == ["1.12 %", "4.72", "3.21", "0.75"]  # the header's labels are not read
    assert any(map(names_source, sourced)) and not any(map(names_source, bare))
    # a source in the caption counts; one in the paragraph after the table does not
    assert sourced_table(*sourced[:2]) and not sourced_table(*bare[:2])
    doc = "\n\n".join(bare[:2]) + "\n\n" + "Made by studies/chain_geometry.py."
    assert tables(doc)[0][3] == "Made by studies/chain_geometry.py." and not sourced_table(*tables(doc)[0][1:3])
    assert tables("## one\n\nstudies/x.py\n\n## two\n\n" + bare[1])[0][1] == ""  # nor one across a heading
    # integers alone, hertz and the conventions are not measured; a plain decimal is
    assert table_numbers("| replicate | steps |\n| --- | --- |\n| 1 (1 Hz) | 4,000 of 12 |") == []
    assert table_numbers("| | median |\n| --- | --- |\n| input_noise=0 | 20.7 |") == ["20.7"]
    assert table_numbers("| quantity | units |\n| --- | --- |\n| accel | m/s^2, g (9.80665 m/s^2) |") == []
    # a table of settings says so by a column headed `default`; a measured one may not hide
    settings = "| check | refuses | default |\n| --- | --- | --- |\n| clipped | a pile | 0.2 %, 4 |"
    measured = "| record | b's error, default |\n| --- | --- |\n| A3 0.5 Hz | -0.67 % |"
    assert table_numbers(settings) == [] and table_numbers(measured) == ["0.67 %"]


@pytest.mark.parametrize("doc", DOCS, ids=lambda p: p.name)
def test_every_measured_number_names_its_source(doc):
    flagged = unsourced(doc)
    assert not flagged, (
        f"{doc.name}: paragraphs that state a measured number and name no source "
        f"(results/..., a .csv, or the benchmarks/, studies/ or tests/ file that measures it):\n\n"
        + "\n\n".join(" ".join(p.split())[:300] for p in flagged))


def test_performance_sections_name_their_csv():
    doc = ROOT / "docs" / "performance.md"
    sections = {}
    for section, p in paragraphs(doc.read_text()):
        sections.setdefault(section, p)
    named = {s: first for s, first in sections.items() if s}
    assert len(named) >= 10
    for section, first in named.items():
        assert first.strip() == f"`results/performance/{section}.csv`", f"## {section} begins {first[:60]!r}"
        assert _section_csv(doc, section), f"## {section}: results/performance/{section}.csv is not there"


def test_the_check_inspects_many_paragraphs():
    # guards the tests above against passing on nothing (a pattern that matches nothing)
    all_paragraphs = [p for doc in DOCS for _, p in paragraphs(doc.read_text())]
    with_numbers = [p for p in all_paragraphs if measured_numbers(p)]
    sourced = [p for p in with_numbers if names_source(p)]
    assert len(all_paragraphs) > 150
    assert len(with_numbers) > 60  # 97 before the unsourced ones moved to CHANGELOG.md, 77 after
    assert len(sourced) > 50


@pytest.mark.parametrize("doc", DOCS, ids=lambda p: p.name)
def test_every_measured_table_names_its_source(doc):
    flagged = unsourced_tables(doc)
    assert not flagged, (
        f"{doc.name}: tables that state a measured number and name no source in "
        f"themselves or the paragraph just before them (their caption):\n\n"
        + "\n\n".join(t[:300] for t in flagged))


def test_the_check_inspects_many_tables():
    # guards the table check against passing on nothing (a table never found, no number read)
    found = [(doc, *t) for doc in DOCS for t in tables(doc.read_text())]
    measured = [t for _, _, _, t, _ in found if table_numbers(t)]
    outside_performance = [t for doc, _, _, t, _ in found if doc.name != "performance.md" and table_numbers(t)]
    settings = [t for _, _, _, t, _ in found if any(c.lower() == SETTINGS_HEADER for c in _cells(t.splitlines()[0]))]
    assert len(found) > 20  # 34 before the unsourced ones moved to CHANGELOG.md, 25 after
    assert len(measured) > 15  # 20: the 17 of docs/performance.md and 3 sourced ones of docs/inference.md
    assert len(outside_performance) >= 3
    assert 1 <= len(settings) <= 5  # the two of docs/assumptions.md and the checks' of docs/records.md


def test_a_cited_csv_is_there():
    assert missing_csvs("tau 207.5 steps (`walks.csv`, results/chain-geometry/geometry.csv)", True) == ["walks.csv"]
    assert missing_csvs("tau 207.5 steps (results/chain-geometry/walks.csv, `geometry.csv`)", True) == [
        "results/chain-geometry/walks.csv"]
    assert missing_csvs("writes `ridge.csv` under runs/", False) == []
    assert clauses("one 2 %\n more; two `ridge.csv`. Three") == ["one 2 % more;", "two `ridge.csv`.", "Three"]
    assert missing_csvs("`bayes-inerter fit RECORD.csv`: b 3.5 %", True) == []
    assert len(_COMMITTED_CSV) > 50  # the names are read from results/, not from nothing


@pytest.mark.parametrize("doc", DOCS, ids=lambda p: p.name)
def test_every_cited_csv_is_committed(doc):
    missing = []
    for kind, _, text in blocks(doc.read_text()):
        if kind == "paragraph":
            for clause in clauses(text):
                missing += missing_csvs(clause, bool(measured_numbers(clause)))
        elif kind == "table":
            missing += missing_csvs(text, bool(table_numbers(text)))
    assert not missing, f"{doc.name} rests measured numbers on CSVs that are not committed: {sorted(set(missing))}"


def test_counts_are_measured_numbers():
    assert measured_numbers("The 94 % interval held b on 93 of 100, and on 9 of the 33 at 0.5 Hz.") == [
        "93 of 100", "9 of the 33"]
