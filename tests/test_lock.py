"""One run per folder: a second holder is refused, a dead holder blocks nothing."""

import os
import signal
import subprocess
import sys

import pytest

from bayes_inerter.lock import FolderBusy, folder_lock

HOLD = """
import sys, time
from bayes_inerter.lock import folder_lock
with folder_lock(sys.argv[1]):
    print("held", flush=True)
    time.sleep(60)
"""


def test_second_holder_refused_naming_the_first_and_a_killed_one_blocks_nothing(tmp_path):
    proc = subprocess.Popen([sys.executable, "-c", HOLD, str(tmp_path)], stdout=subprocess.PIPE, text=True)
    try:
        assert proc.stdout.readline().strip() == "held"
        with pytest.raises(FolderBusy, match=rf"in use by another run \(process {proc.pid}\)"):
            with folder_lock(tmp_path):
                pass
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    with folder_lock(tmp_path) as path:  # the killed run left its file, not its lock
        assert path.read_text().strip() == str(os.getpid())


def test_the_same_process_cannot_take_it_twice(tmp_path):
    with folder_lock(tmp_path):
        with pytest.raises(FolderBusy):
            with folder_lock(tmp_path):
                pass
    with folder_lock(tmp_path):
        pass
