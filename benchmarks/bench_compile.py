"""Benchmark: what the first use of the simulator costs in compilation, on an empty cache.

Each case runs in a fresh Python process with its own empty numba cache
(``NUMBA_CACHE_DIR``) and kernel folder (``BAYES_INERTER_KERNEL_DIR``), so nothing is
loaded that an earlier process compiled:

- **slice / loops**: one small compiled function that copies two arrays into a larger
  one, by slice assignment (``Z[:n, :n] = A``) and element by element. Numba compiles
  the slice assignment's shape check with an error message naming both shapes; its
  compilation is what the package's compiled code avoids by copying with loops
  (docs/simulator.md). The ratio slice / loops is printed.
- **networks**: the first simulation of the paper's reduced, rigid and linear networks
  from a force (``simulate``), the compilation of their kernels included.

Each case is timed ``--repeats`` times (a fresh process and cache each) and the median
kept; a row goes to results/performance/compile.csv.

    python benchmarks/bench_compile.py [--repeats 3]

The machine is shared and noisy: the ratio within a run is what to read.
"""

import argparse
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

from _timing import record_row

CASES = {
    "slice": """
import numpy as np
from numba import njit

@njit
def copy(A, B):
    n, k = A.shape[0], B.shape[1]
    Z = np.zeros((n + k, n + k))
    Z[:n, :n] = A
    Z[:n, n:n + k] = B
    return Z

copy(np.eye(3), np.ones((3, 1)))
""",
    "loops": """
import numpy as np
from numba import njit

@njit
def copy(A, B):
    n, k = A.shape[0], B.shape[1]
    Z = np.zeros((n + k, n + k))
    for i in range(n):
        for j in range(n):
            Z[i, j] = A[i, j]
        for q in range(k):
            Z[i, n + q] = B[i, q]
    return Z

copy(np.eye(3), np.ones((3, 1)))
""",
    "networks": """
import numpy as np
from bayes_inerter import paper_parameters
from bayes_inerter.simulate import simulate

p = paper_parameters("A2")
t = np.arange(301) / 1000.0
f = 2000.0 * np.sin(2 * np.pi * t) * np.clip(t / 0.1, 0, 1)
for name in ("reduced", "rigid", "linear"):
    simulate(p, t, f, network=name)
""",
}


def _numba_warm() -> None:
    """Import numba once, so the first timed process does not pay for the files' first read."""
    subprocess.run([sys.executable, "-c", "import numba, numpy"], check=True)


def time_case(source: str) -> float:
    """Seconds of one fresh process running ``source`` with empty caches."""
    with tempfile.TemporaryDirectory() as tmp:
        env = {**os.environ, "NUMBA_CACHE_DIR": os.path.join(tmp, "numba"),
               "BAYES_INERTER_KERNEL_DIR": os.path.join(tmp, "kernels")}
        t0 = time.perf_counter()
        subprocess.run([sys.executable, "-c", source], env=env, check=True)
        return time.perf_counter() - t0


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=3, help="fresh processes per case (3)")
    args = parser.parse_args()
    _numba_warm()
    seconds = {}
    for name, source in CASES.items():
        times = []
        for k in range(args.repeats):
            times.append(time_case(source))
            print(f"{name}: run {k + 1} of {args.repeats}: {times[-1]:.1f} s", flush=True)
        seconds[name] = float(np.median(times))
    ratio = seconds["slice"] / seconds["loops"]
    print(f"slice assignment {seconds['slice']:.1f} s, loops {seconds['loops']:.1f} s: ratio {ratio:.2f}")
    print(f"the paper's three networks, first simulation with empty caches: {seconds['networks']:.1f} s")
    path = record_row("compile", {"repeats": args.repeats, "slice_s": round(seconds["slice"], 2),
                                  "loops_s": round(seconds["loops"], 2), "ratio": round(ratio, 2),
                                  "networks_s": round(seconds["networks"], 2)})
    print(f"wrote a row to {path}")


if __name__ == "__main__":
    main()
