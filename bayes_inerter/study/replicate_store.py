"""Where a study keeps its finished replicates.

While a run goes on, each replicate it finishes is one JSON file in
``<out>/replicates/<k>.json`` (written whole, so an interruption loses at most the
replicates in progress). A run that is done can be packed into one file,
``<out>/replicates.jsonl.gz``, one replicate per line in the order of their number,
gzipped: the same content in one file instead of hundreds of small ones (on a 4 kB-block
file system 150 replicates of 1.5 kB each take 600 kB loose, 250 kB as plain JSON lines
and about 50 kB gzipped). Every reader takes the loose files, the packed file and the
plain ``replicates.jsonl`` that packing wrote before it was gzipped; a run continued
into a packed folder writes its new replicates loose beside it.
"""

from __future__ import annotations

import gzip
import json
from pathlib import Path

from .output import write_json

__all__ = ["LOOSE", "PACKED", "PLAIN", "replicate_path", "write_replicate", "load_replicates", "finished",
           "is_packed", "pack", "unpack"]

#: The folder of one JSON per replicate, under a study's output folder.
LOOSE = "replicates"
#: The packed file, one JSON line per replicate, gzipped, under a study's output folder.
PACKED = "replicates.jsonl.gz"
#: The packed file as packing wrote it before it was gzipped (read, never written).
PLAIN = "replicates.jsonl"


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
    where: dict[int, str] = {}
    sources = [(name, line) for name in _packed_files(out) for line in _packed_lines(out / name)]
    sources += [(str(f.relative_to(out)), f.read_text()) for f in _loose_files(out)]
    for name, text in sources:
        if not text.strip():
            continue
        r = json.loads(text)
        k = int(r["replicate"])
        if k in found:
            raise ValueError(f"replicate {k} of {out} is both in {where[k]} and in {name}; "
                             "remove the one that should not count")
        found[k], where[k] = r, name
    return found


def _packed_files(out: Path) -> list[str]:
    return [name for name in (PACKED, PLAIN) if (out / name).is_file()]


def _packed_lines(path: Path) -> list[str]:
    raw = path.read_bytes()
    return (gzip.decompress(raw) if path.name.endswith(".gz") else raw).decode().splitlines()


def is_packed(out) -> bool:
    """Whether ``out`` holds a packed file (gzipped or plain)."""
    return bool(_packed_files(Path(out)))


def finished(out) -> list[dict]:
    """The finished replicates of ``out`` in the order of their number."""
    found = load_replicates(out)
    return [found[k] for k in sorted(found)]


def pack(out) -> int:
    """Pack every finished replicate of ``out`` into :data:`PACKED` and remove the loose
    files (and their folder, if left empty) and a plain :data:`PLAIN`. The packed file is
    written whole before anything goes; packing the same replicates again writes the same
    bytes (the gzip header holds no time). Returns how many replicates the packed file
    holds."""
    out = Path(out)
    reps = finished(out)
    if not reps:
        raise ValueError(f"{out} holds no finished replicate ({LOOSE}/, {PACKED} or {PLAIN}); nothing to pack")
    text = "".join(json.dumps(r) + "\n" for r in reps)
    tmp = out / f".{PACKED}.tmp"
    tmp.write_bytes(gzip.compress(text.encode(), compresslevel=9, mtime=0))
    tmp.replace(out / PACKED)
    (out / PLAIN).unlink(missing_ok=True)
    for f in _loose_files(out):
        f.unlink()
    folder = out / LOOSE
    if folder.is_dir() and not any(folder.iterdir()):
        folder.rmdir()
    return len(reps)


def unpack(out) -> int:
    """Write every packed replicate of ``out`` back to its own file and remove
    the packed file (for example before :func:`study_calibration.raise_cap`, which moves
    files). Returns how many replicates were unpacked."""
    out = Path(out)
    reps = finished(out)
    for r in reps:
        if not replicate_path(out, r["replicate"]).exists():
            write_replicate(out, r["replicate"], r)
    for name in _packed_files(out):
        (out / name).unlink()
    return len(reps)
