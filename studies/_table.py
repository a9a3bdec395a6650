"""What the studies' scripts share: write rows of results to a CSV file and print them."""

import csv
from pathlib import Path


def write_rows(path, rows: list[dict]) -> Path:
    """Write ``rows`` (dicts with the same keys) to the CSV file ``path`` (its folder made
    if needed), print each as ``key value, ...``, and return the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    for row in rows:
        print(", ".join(f"{k} {v}" for k, v in row.items()))
    return path
