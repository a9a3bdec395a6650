"""Benchmark: the exact kernel (``bayes_inerter/simulate/_kernel/``) against its earlier version.

Run by hand from the project root: ``python benchmarks/bench_kernel.py``.

The earlier version is read from git (``git show 4e20f7c3f24f:bayes_inerter/_kernel.py``, the
kernel as it was before it was tuned (tables stored by rows and the current mode's level-0 table copied
into a contiguous array at each mode change; the products summed five rows at a time in
registers; the guards at the bisection's left end carried along, not recomputed; the
output taken from a guard derivative when a sliding contact sits at the output node).
The script needs the project's git history; the tuning changes no sum's order, so the outputs
should agree exactly. On a few of the study's records (generated as the study generates them, seed 0), with the
paper's parameters and random perturbations of them, the script

- checks that the earlier kernel and today's, generated for the network
  (``_kernel.kernel_for``, as ``simulate`` runs it), give the same accel and vel (largest
  relative difference, scaled by each output's largest magnitude) and the same stats
  (switches, bisections);
- times them side by side in one run, alternating old and new call by call, and prints
  the medians and the ratio median(old) / median(new) per record.

(Until the kernel was split into a package, the general compiled ``run_kernel`` was
timed as well; the generated kernel is now the only one, and
``tests/reference_kernel.py`` the plain one it is tested against.)

The machine is shared and noisy: read the ratios, not the absolute times.
"""

import argparse
import dataclasses
import importlib.util
import statistics
import time
from pathlib import Path

import numpy as np

from _timing import record_row
from bayes_inerter.simulate import _kernel as new_kernel
from bayes_inerter.simulate._piecewise import augmented as _augmented
from bayes_inerter.device import paper_parameters
from bayes_inerter.networks import build_network
from bayes_inerter.network import compile_network
from bayes_inerter.records.generator import paper_record
from bayes_inerter.simulate import MAX_EVENTS_PER_STEP, _contacts, check_record

ROOT = Path(__file__).resolve().parents[1]
DEFAULT_RECORDS = ["A0_0.5Hz", "A1_1Hz", "A3_1Hz", "B2_1.5Hz", "B1_1Hz", "A2_1.5Hz"]


#: The last commit with the kernel as it was before it was tuned.
BEFORE = "4e20f7c3f24f"


def _load_old_kernel():
    """The kernel of commit :data:`BEFORE`, imported from a copy in a temporary folder
    (numba caches its compiled code beside it there)."""
    import subprocess
    import tempfile

    try:
        source = subprocess.run(["git", "show", f"{BEFORE}:bayes_inerter/_kernel.py"], cwd=ROOT, check=True,
                                capture_output=True, text=True).stdout
    except (OSError, subprocess.CalledProcessError) as exc:
        raise SystemExit(f"error: cannot read the earlier kernel from git ({exc}); run from a clone of the project")
    path = Path(tempfile.mkdtemp(prefix="kernel_before_")) / "_kernel_before.py"
    path.write_text(source)
    spec = importlib.util.spec_from_file_location("_kernel_before", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def kernel_args(record, params):
    """The kernel's arguments for a record under the given parameters (as simulate does)."""
    compiled = compile_network(build_network("reduced", params, "coulomb"))
    A, B = compiled.state_space(viscous=True)
    nodes, f0, mass = _contacts(compiled)
    n = A.shape[0]
    B = B.reshape(n, -1)
    n_in = B.shape[1]
    Abar = _augmented(A, B, nodes, mass)
    _, (force,), h = check_record(record.time, record.force)
    inputs = np.ascontiguousarray(force, dtype=float).reshape(-1, n_in)
    return (Abar, n, n_in, nodes, f0, mass, inputs, h, np.zeros(n), 0, False, MAX_EVENTS_PER_STEP)


def perturbed(params, rng, scale):
    fields = {f.name: getattr(params, f.name) for f in dataclasses.fields(params)}
    return dataclasses.replace(params, **{k: v * (1.0 + scale * rng.standard_normal()) for k, v in fields.items()})


def rel_diff(a, b):
    scale = max(np.max(np.abs(a)), np.max(np.abs(b)), 1e-300)
    return float(np.max(np.abs(a - b)) / scale)


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--records", nargs="*", default=DEFAULT_RECORDS)
    ap.add_argument("--repeats", type=int, default=30, help="timed calls of each kernel per record")
    ap.add_argument("--perturbations", type=int, default=4, help="random parameter sets per record")
    ap.add_argument("--scale", type=float, default=0.05, help="relative size of the perturbations")
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args()

    old_kernel = _load_old_kernel()
    rng = np.random.default_rng(args.seed)
    worst = 0.0
    mismatches = 0
    ratios = []
    for name in args.records:
        setting, freq = name.split("_")
        record = paper_record(setting, float(freq.removesuffix("Hz")), seed=0)  # the full study's record
        base = paper_parameters(record.metadata["setting"])
        sets = [base] + [perturbed(base, rng, args.scale) for _ in range(args.perturbations)]
        for params in sets:
            a = kernel_args(record, params)
            ra = old_kernel.run_kernel(*a)
            rb = special(a)(*a)
            d = max(rel_diff(ra[0], rb[0]), rel_diff(ra[1], rb[1]))
            same = ra[3] == rb[3] and np.array_equal(ra[4], rb[4])
            worst = max(worst, d)
            mismatches += not same
            print(f"{name:10s} check: max rel diff {d:.2e}, status {ra[3]}/{rb[3]}, "
                  f"stats {ra[4].tolist()}/{rb[4].tolist()}{'' if same else '  MISMATCH'}")

        a = kernel_args(record, base)
        t_old, t_new = [], []
        for _ in range(args.repeats):
            for fn, store in ((old_kernel.run_kernel, t_old), (special(a), t_new)):
                t0 = time.perf_counter()
                fn(*a)
                store.append(time.perf_counter() - t0)
        mo, mn = statistics.median(t_old), statistics.median(t_new)
        ratios.append(mo / mn)
        print(f"{name:10s} timing ({args.repeats} alternating repeats): old {mo * 1e3:.3f} ms, "
              f"generated {mn * 1e3:.3f} ms; ratio old/generated {mo / mn:.3f}")
    print(f"largest output difference: {worst:.2e}; status or stats mismatches: {mismatches}; "
          f"median ratio old/generated {statistics.median(ratios):.3f}")
    path = record_row("kernel", {"records": len(args.records), "repeats": args.repeats, "mismatches": mismatches,
                                 "ratio_old_over_generated": round(statistics.median(ratios), 3)})
    print(f"wrote a row to {path}")


def special(a):
    """The kernel generated for these arguments' network (``_kernel.kernel_for``)."""
    return new_kernel.kernel_for(a[1], a[2], a[3], a[9], (a[0] != 0).tobytes())


if __name__ == "__main__":
    main()
