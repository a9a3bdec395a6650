"""docs/performance.md from results/performance/*.csv: one table per benchmark file, each
row with its commit, machine and date, after the file's note (<name>.md beside it) where
there is one.

    python benchmarks/performance_table.py

Rows written by ``_timing.record_row`` carry their own commit, machine and date. Older
files have none: their rows get the commit that last changed the file and its date
(when they were committed, not necessarily measured), and "not recorded" for the
machine.
"""

import csv
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SOURCE = ROOT / "results" / "performance"
OUT = ROOT / "docs" / "performance.md"


def _committed(path: Path) -> tuple[str, str]:
    out = subprocess.run(["git", "log", "-1", "--format=%h %cs", "--", str(path)], cwd=ROOT, capture_output=True,
                         text=True).stdout.split()
    return (out[0], out[1]) if len(out) == 2 else ("not committed", "")


def table(path: Path) -> list[str]:
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    if not rows:
        return []
    cols = list(rows[0])
    if "commit" not in cols:
        commit, date = _committed(path)
        rows = [{"commit": f"{commit} (committed)", "machine": "not recorded", "date": date, **r} for r in rows]
        cols = ["commit", "machine", "date"] + cols
    lines = ["| " + " | ".join(cols) + " |", "|" + "---|" * len(cols)]
    lines += ["| " + " | ".join(r.get(c, "") for c in cols) + " |" for r in rows]
    return lines


def main():
    lines = ["# Performance", "",
             "Measured by the benchmarks in `benchmarks/` (each prints its ratios, measured side by side in one run, "
             "and writes its rows to `results/performance/`). Made by `python benchmarks/performance_table.py`; "
             "do not edit by hand. Every number holds for the machine and commit of its row only.", ""]
    for path in sorted(SOURCE.glob("*.csv")):
        note = path.with_suffix(".md")  # what the columns mean, where a benchmark keeps one
        lines += [f"## {path.stem}", "", f"`results/performance/{path.name}`", ""]
        lines += [note.read_text().strip(), ""] if note.is_file() else []
        lines += [*table(path), ""]
    OUT.write_text("\n".join(lines))
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
