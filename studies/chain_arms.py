"""Where a stored chain keeps the nut-and-bearing compliance, block by block.

Reads a fit's checkpoint (``--fit``: a folder ``bayes-inerter fit`` wrote, with its
chain.h5) and the record it fitted (``--record``), maps every walker step to theta in the
coordinates the chain walked in (read from the checkpoint, ``_table.sampled_model``),
and for each block of ``--block`` steps reports the share of walker steps whose
bearing is stiff beside the nut: log10(|z_B| / |z_n|) > ``--decades`` at the drive
frequency, with z_B = k_B / omega the bearing's spring and z_n = c_n + k_n / (i omega)
the nut's spring and damper. Beside it the block means of log b, log10 k_B and
log10 |z_n|. The posterior recomputed at the chain's last walkers is checked against
the stored log-probabilities before anything is read, so a record or model other than
the fit's stops the script.

    python studies/chain_arms.py --fit runs/full-untempered/fits/two-port/A0_1Hz \
        --record runs/full-untempered/records/A0_1Hz.csv [--block 1000] [--decades 1]
        [--label impedance-1Hz] [--out results/chain-geometry/arms.csv]

With --out, the blocks go to that CSV under ``--label`` (default: the fit folder's
name), replacing that label's earlier rows and keeping the others'.

Exit codes: 0 done, 2 a missing fit or record, or a record that is not the fit's.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

from _table import read_rows, sampled_model, write_table
from bayes_inerter.inference import LikelihoodSettings, PosteriorModel
from bayes_inerter.inference.sampling.checkpoint import read_chain
from bayes_inerter.inference.sampling.coordinates import drive_omega
from bayes_inerter.records import read_record


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fit", type=Path, required=True, help="a fit's output folder (with chain.h5)")
    ap.add_argument("--record", type=Path, required=True, help="the record that fit read")
    ap.add_argument("--block", type=int, default=1000, help="steps per block (1000)")
    ap.add_argument("--decades", type=float, default=1.0,
                    help="a walker step counts as a stiff bearing where |z_B| / |z_n| exceeds 10 ** this (1)")
    ap.add_argument("--label", default=None, help="the chain's name in --out (the fit folder's name)")
    ap.add_argument("--out", type=Path, default=None, help="write the blocks to this CSV")
    a = ap.parse_args(argv)
    checkpoint = a.fit / "chain.h5"
    for path in (checkpoint, a.record):
        if not path.is_file():
            print(f"error: {path} does not exist; give a fit folder holding chain.h5 and the record it fitted",
                  file=sys.stderr)
            return 2
    chain, log_prob = read_chain(checkpoint, log_prob=True)
    steps, walkers, ndim = chain.shape
    record = read_record(a.record)
    model, coords = sampled_model(PosteriorModel(record, likelihood=LikelihoodSettings(residual="motion")),
                                  checkpoint)
    theta, log_jac = coords.transform(chain[-1])
    again = np.array([model.log_prob(t)[0] for t in theta]) + log_jac
    stored = log_prob[-1]
    if not np.allclose(again, stored, atol=1e-6, rtol=0):
        print(f"error: the posterior at the chain's last walkers differs from the stored one by up to "
              f"{np.max(np.abs(again - stored)):.3g} nats; give the record and defaults that fit used",
              file=sys.stderr)
        return 2
    theta = coords.to_theta(chain.reshape(-1, ndim)).reshape(chain.shape)
    names = model.names
    omega = drive_omega(record)
    k_b, k_n, c_n = (np.exp(theta[..., names.index(n)]) for n in ("k_B", "k_n", "c_n"))
    z_n = np.hypot(c_n, k_n / omega)
    ratio = np.log10(k_b / omega / z_n)
    rows = []
    for start in range(0, steps, a.block):
        s = slice(start, start + a.block)
        rows.append({"chain": a.label or a.fit.name, "steps": f"{start}-{min(start + a.block, steps)}",
                     "stiff_bearing_share": round(float(np.mean(ratio[s] > a.decades)), 3),
                     "mean_log_b": round(float(np.mean(theta[s, :, names.index("b")])), 4),
                     "mean_log10_k_B": round(float(np.mean(theta[s, :, names.index("k_B")]) / math.log(10)), 3),
                     "mean_log10_z_n": round(float(np.mean(np.log10(z_n[s]))), 3)})
    for r in rows:
        print(f"steps {r['steps']:>12}: stiff bearing {r['stiff_bearing_share']:.3f}, "
              f"mean log b {r['mean_log_b']:.4f}, log10 k_B {r['mean_log10_k_B']:.3f}, "
              f"log10 |z_n| {r['mean_log10_z_n']:.3f}")
    if a.out is not None:
        kept = [r for r in read_rows(a.out) if r["chain"] != rows[0]["chain"]]
        write_table(a.out, kept + rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
