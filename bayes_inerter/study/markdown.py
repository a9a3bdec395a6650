"""Markdown for the studies' reports."""

from __future__ import annotations

__all__ = ["table"]


def table(rows: list[dict], columns: list[str], fmt: dict | None = None) -> str:
    """A Markdown table of ``rows`` (dicts) in ``columns``; a float formatted by ``fmt``'s
    format for its column (``{:.4g}`` if none), None as an empty cell."""
    fmt = fmt or {}
    lines = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    for r in rows:
        cells = []
        for c in columns:
            v = r.get(c)
            if isinstance(v, float):
                cells.append(fmt.get(c, "{:.4g}").format(v))
            else:
                cells.append("" if v is None else str(v))
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines)
