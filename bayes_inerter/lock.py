"""One run per output folder: an advisory lock on ``<folder>/.lock``.

A second ``fit`` or ``study`` into a folder that a running one holds is refused at once
(:class:`FolderBusy`, naming the holder's process id) and the first goes on undisturbed;
two runs writing one checkpoint would corrupt it. The lock is the operating system's
(``fcntl.flock``), tied to the open file: it goes with the process that holds it,
however that process ends, so a killed run never blocks the next. The file itself stays
behind, holding the last holder's process id, and means nothing when unlocked.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
from pathlib import Path

__all__ = ["FolderBusy", "folder_lock", "LOCK_FILE"]

LOCK_FILE = ".lock"


class FolderBusy(RuntimeError):
    """The folder is held by another running process."""


@contextlib.contextmanager
def folder_lock(folder):
    """Hold ``folder``'s lock for the ``with`` block; FolderBusy if another process does.

    A process that already holds it (a study's fit inside the study's folder is another
    folder) may not take it twice: the second attempt is refused like another process's.
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / LOCK_FILE
    fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(fd, 32, 0).decode(errors="replace").strip() or "unknown"
            raise FolderBusy(f"{folder} is in use by another run (process {holder}); wait for it to end, "
                             "or choose another --out") from None
        os.ftruncate(fd, 0)
        os.pwrite(fd, f"{os.getpid()}\n".encode(), 0)
        yield path
    finally:
        os.close(fd)  # closing releases the lock
