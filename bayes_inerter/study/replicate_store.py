"""Where a study keeps its finished replicates.

While a run goes on, each replicate it finishes is one JSON file in
``<out>/replicates/<k>.json`` (written whole, so an interruption loses at most the
replicates in progress). A run that is done can be packed into one file,
``<out>/replicates.jsonl``, one replicate per line in the order of their number: the
same content in one file instead of hundreds of small ones (on a 4 kB-block file system
150 replicates of 1.5 kB each take 600 kB loose and 230 kB packed). Every reader takes
both; a run continued into a packed folder writes its new replicates loose beside it.
"""

from __future__ import annotations

import json
from pathlib import Path

from .output import write_json

__all__ = ["LOOSE", "PACKED", "replicate_path", "write_replicate", "load_replicates", "finished", "pack", "unpack"]

#: The folder of one JSON per replicate, under a study's output folder.
LOOSE = "replicates"
#: The packed file, one JSON line per replicate, under a study's output folder.
PACKED = "replicates.jsonl"


def replicate_path(out, k: int) -> Path:
    """Where a run writes replicate ``k`` of ``out`` when it finishes."""
    return Path(out) / LOOSE / f"{int(k):04d}.json"


def write_replicate(out, k: int, value: dict, *, indent: int | None = None) -> Path:
    """Write finished replicate ``k`` of ``out`` to its own file (its folder made where
    needed), whole or not at all; returns the path."""
    path = replicate_path(out, k)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_json(path, value, indent=indent)
    return path


def _loose_files(out: Path) -> list[Path]:
    folder = out / LOOSE
    return sorted(folder.glob("[0-9]*.json")) if folder.is_dir() else []


def load_replicates(out) -> dict[int, dict]:
    """Every finished replicate of ``out``, packed and loose, by number. ValueError where
    one number is both packed and loose (two runs' results for one replicate)."""
    out = Path(out)
    found: dict[int, dict] = {}
    packed = out / PACKED
    if packed.is_file():
        for line in packed.read_text().splitlines():
            if line.strip():
                r = json.loads(line)
                found[int(r["replicate"])] = r
    for f in _loose_files(out):
        r = json.loads(f.read_text())
        k = int(r["replicate"])
        if k in found:
            raise ValueError(f"replicate {k} of {out} is both in {PACKED} and in {f.relative_to(out)}; "
                             "remove the one that should not count")
        found[k] = r
    return found


def finished(out) -> list[dict]:
    """The finished replicates of ``out`` in the order of their number."""
    found = load_replicates(out)
    return [found[k] for k in sorted(found)]


def pack(out) -> int:
    """Pack every finished replicate of ``out`` into :data:`PACKED` and remove the loose
    files (and their folder, if left empty). The packed file is written whole before any
    loose file goes. Returns how many replicates the packed file holds."""
    out = Path(out)
    reps = finished(out)
    if not reps:
        raise ValueError(f"{out} holds no finished replicate ({LOOSE}/ or {PACKED}); nothing to pack")
    text = "".join(json.dumps(r) + "\n" for r in reps)
    tmp = out / f".{PACKED}.tmp"
    tmp.write_text(text)
    tmp.replace(out / PACKED)
    for f in _loose_files(out):
        f.unlink()
    folder = out / LOOSE
    if folder.is_dir() and not any(folder.iterdir()):
        folder.rmdir()
    return len(reps)


def unpack(out) -> int:
    """Write every packed replicate of ``out`` back to its own file and remove
    :data:`PACKED` (for example before :func:`study_calibration.raise_cap`, which moves
    files). Returns how many replicates were unpacked."""
    out = Path(out)
    reps = finished(out)
    for r in reps:
        if not replicate_path(out, r["replicate"]).exists():
            write_replicate(out, r["replicate"], r)
    (out / PACKED).unlink(missing_ok=True)
    return len(reps)
