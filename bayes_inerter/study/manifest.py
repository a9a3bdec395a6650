"""What made a results folder: the commit, the command, the package versions, the machine.

A study's run adds one entry to ``manifest.json`` in the folder it writes (a study run
in chunks, over several sessions, adds one a chunk): the source's commit (``-dirty``
where tracked files had changes, None outside a git clone), the configuration it was
given, the versions of the package and the libraries that shape its numbers
(:func:`..inference.fit.versions`), the machine's processor and cores, and the date.
A run (one process, named by a token drawn when the module is imported) adds one entry
however many times it writes into the folder with the same configuration.
"""

from __future__ import annotations

import datetime
import json
import os
import subprocess
import sys
import uuid
from pathlib import Path

from ..inference.fit import versions

__all__ = ["MANIFEST", "RUN", "source_commit", "manifest_entry", "write_manifest", "script_configuration"]

#: The file's name in a results folder.
MANIFEST = "manifest.json"

_SOURCE = Path(__file__).resolve().parents[2]
#: This process's run: a pid may come again in a later session, a token does not.
RUN = uuid.uuid4().hex
#: (manifest path, configuration) this run has written its entry for.
_WRITTEN: set = set()


def source_commit(folder: Path = _SOURCE) -> str | None:
    """The short commit of the clone ``folder`` lies in, ``-dirty`` where tracked files
    differ from it; None outside a clone (an installed package) or without git."""
    def git(*args):
        return subprocess.run(["git", *args], cwd=folder, capture_output=True, text=True)

    try:
        top = git("rev-parse", "--show-toplevel")
        # a clone's own source, not a package installed into a folder inside some clone
        if top.returncode != 0 or Path(top.stdout.strip()).resolve() != Path(folder).resolve():
            return None
        head = git("rev-parse", "--short", "HEAD")
        if head.returncode != 0:
            return None
        dirty = git("status", "--porcelain", "--untracked-files=no").stdout.strip()
    except OSError:
        return None
    return head.stdout.strip() + ("-dirty" if dirty else "")


def manifest_entry(configuration: dict) -> dict:
    """This run's entry: ``configuration`` (what JSON cannot hold, by its repr) with the commit,
    versions, machine and date (UTC)."""
    return {"commit": source_commit(), "date": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
            "configuration": configuration, "versions": versions(), "cores": os.cpu_count(), "run": RUN}


def write_manifest(folder, configuration: dict) -> Path:
    """Add this run's entry to ``folder``/manifest.json (made where it is new; this run's
    entry with the same configuration already there is left as it is). Returns the
    file's path."""
    path = Path(folder) / MANIFEST
    configuration = json.loads(json.dumps(configuration, default=repr))  # as the file will hold it
    key = (str(path.resolve()), json.dumps(configuration, sort_keys=True))
    if key in _WRITTEN and path.exists():  # a study writing row by row reads the file once
        return path
    runs = []
    if path.exists():
        try:
            runs = json.loads(path.read_text())["runs"]
        except (ValueError, KeyError, TypeError):
            raise ValueError(f"{path} is not a manifest this package wrote; move it aside") from None
    if any(r.get("run") == RUN and r.get("configuration") == configuration for r in runs):
        _WRITTEN.add(key)
        return path
    runs.append(manifest_entry(configuration))
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_name(f".{MANIFEST}.{os.getpid()}.tmp")
    tmp.write_text(json.dumps({"runs": runs}, indent=1) + "\n")
    os.replace(tmp, path)
    _WRITTEN.add(key)
    return path


def script_configuration() -> dict:
    """A script's configuration as its command line gave it: the script and its arguments."""
    return {"script": Path(sys.argv[0]).name, "arguments": sys.argv[1:]}
