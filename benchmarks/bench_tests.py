"""Benchmark: the quick subset's time from a clean clone, as CI meets it.

The repository's HEAD is cloned into a temporary folder and run there with an empty home
folder (so an empty ``~/.cache``: no compiled kernels), in two timed phases:

- **setup**: ``scripts/env.sh`` makes the clone's virtual environment and installs the
  package with its test extras (what ``.ci/run`` does before the tests; the packages
  come from pip's own cache only if the home folder has one, which here it has not);
- **tests**: ``bash test.sh -q -p no:randomly``, the README's test command in a fixed
  order, wall time; beside it the time pytest prints. pytest's clock starts after
  ``tests/conftest.py`` has compiled the shared kernels (``tests/_warm.py``), so the
  difference is that compile phase and pytest's start-up.

A row goes to results/performance/tests.csv. The target (the developers' brief): the
quick subset under four minutes of wall time on two cores.

    python benchmarks/bench_tests.py

Other work on the machine slows every phase: pause it for a measurement worth keeping.
"""

import os
import re
import subprocess
import tempfile
import time
from pathlib import Path

from _timing import ROOT, record_row

TARGET_SECONDS = 240.0


def _timed(cmd, cwd, env) -> tuple[float, subprocess.CompletedProcess]:
    t0 = time.perf_counter()
    done = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True)
    return time.perf_counter() - t0, done


def main():
    with tempfile.TemporaryDirectory() as tmp:
        clone, home = Path(tmp) / "clone", Path(tmp) / "home"
        home.mkdir()
        subprocess.run(["git", "clone", "-q", str(ROOT), str(clone)], check=True)
        env = {k: v for k, v in os.environ.items() if not k.startswith(("BAYES_INERTER", "NUMBA", "PYTHON"))}
        env["HOME"] = str(home)
        setup_s, done = _timed(["bash", "-c", "source scripts/env.sh"], clone, env)
        if done.returncode:
            raise SystemExit(f"error: the environment could not be made: {done.stderr.strip()[-300:]}")
        print(f"setup: {setup_s:.1f} s", flush=True)
        tests_s, done = _timed(["bash", "test.sh", "-q", "-p", "no:randomly"], clone, env)
        last = done.stdout.strip().splitlines()[-1] if done.stdout.strip() else ""
        found = re.search(r"(\d+) passed.* in ([\d.]+)s", last)
        if not found:
            raise SystemExit(f"error: the tests did not report a time: {last or done.stderr.strip()[-300:]}")
        passed, pytest_s = int(found.group(1)), float(found.group(2))
        failed = re.search(r"(\d+) failed", last)
        for line in done.stdout.splitlines():  # pytest's -ra summary names each failure
            if line.startswith(("FAILED", "ERROR")):
                print(line)
    print(f"tests: {tests_s:.1f} s of wall time; pytest printed {pytest_s:.1f} s; "
          f"before pytest's clock {tests_s - pytest_s:.1f} s ({(tests_s - pytest_s) / tests_s:.0%})")
    print(f"wall / target {tests_s / TARGET_SECONDS:.2f} (target {TARGET_SECONDS:.0f} s)")
    path = record_row("tests", {"setup_s": round(setup_s, 1), "tests_wall_s": round(tests_s, 1),
                                "pytest_s": round(pytest_s, 1), "passed": passed,
                                "failed": int(failed.group(1)) if failed else 0,
                                "met": tests_s <= TARGET_SECONDS})
    print(f"wrote a row to {path.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
