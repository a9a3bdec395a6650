"""Why the per-record chains do not converge: one record sampled for long, the ridge
between the nut stiffness k_n and the inertance b that the walkers cross slowly.

    python studies/long_chain.py [--setting A3] [--freq 1] [--record FILE.csv]
        [--steps 5000] [--seed 0] [--processes 1] [--out runs/long-chain]

The record is the full study's (the paper grid generated with seed 0, default
generator settings) for ``--setting`` and ``--freq``, or a record file.

Writes into ``--out``/<record name>/ the fit's usual outputs (a rerun continues its
checkpoint), ``tau.csv`` (the autocorrelation time and R-hat on growing stretches of the
chain), ``ridge.csv`` (b, c_f and the log posterior in bins of log k_n, and the share of
the samples in each) and ``ridge.png``, and prints where the generating values lie.
"""

import argparse
import csv
import sys
from pathlib import Path

import numpy as np

from bayes_inerter.study.manifest import script_configuration, write_manifest

ROOT = Path(__file__).resolve().parents[1]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--setting", default="A3")
    ap.add_argument("--freq", type=float, default=1.0)
    ap.add_argument("--record", default=None, help="a record file instead of the generated one")
    ap.add_argument("--steps", type=int, default=5000)
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--processes", type=int, default=1)
    ap.add_argument("--out", default=str(ROOT / "runs" / "long-chain"))
    args = ap.parse_args()
    write_manifest(Path(args.out), script_configuration())

    import emcee
    import h5py
    from tqdm import tqdm

    from bayes_inerter.inference import PosteriorModel, fit_record
    from bayes_inerter.inference.sampling.coordinates import default_coordinates
    from bayes_inerter.inference.sampling.diagnostics import rhat_ess
    from bayes_inerter.records import read_record
    from bayes_inerter.records.generator import paper_record

    if args.record:
        try:
            rec = read_record(args.record)
        except (OSError, ValueError) as exc:
            sys.exit(f"error: {exc}")
        name = Path(args.record).stem
    else:
        try:
            rec = paper_record(args.setting, args.freq, seed=0)
        except ValueError as exc:
            sys.exit(f"error: {exc}")
        name = f"{args.setting}_{args.freq:g}Hz"
    out = Path(args.out) / name
    bar = tqdm(total=args.steps, desc="sampling", unit="step", file=sys.stderr)

    def progress(iteration, target):
        bar.n = iteration
        bar.refresh()

    fit_record(rec, out, steps=args.steps, seed=args.seed, processes=args.processes, progress=progress)
    bar.close()
    with h5py.File(out / "chain.h5", "r") as f:
        g = f["mcmc"]
        n = int(g.attrs["iteration"])
        walked, lp = g["chain"][:n], g["log_prob"][:n]
        names = g.attrs["parameter_names"].split(",")
    # the checkpoint holds the walkers in the sampler's coordinates: back to theta
    coords = default_coordinates(PosteriorModel(rec))
    chain, lp = coords.to_theta(walked), lp - coords.log_jacobian(walked)

    rows = []
    for stop in [s for s in (1000, 2000, 3000, 4000, 5000, 7500, 10000) if s <= n] or [n]:
        tau = emcee.autocorr.integrated_time(chain[:stop], tol=0)
        rhat, ess = rhat_ess(chain[int(2 * tau.max()) : stop] if stop > 4 * tau.max() else chain[stop // 2 : stop])
        rows.append({"steps": stop, **{f"tau_{p}": round(float(t), 1) for p, t in zip(names, tau)},
                     "max_rhat": round(float(np.nanmax(rhat)), 3), "min_ess": round(float(np.nanmin(ess)), 1)})
    with open(out / "tau.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)

    keep = chain[n // 5 :]  # the first fifth as burn-in
    lpk = lp[n // 5 :].ravel()
    i_b, i_k, i_cf = names.index("b"), names.index("k_n"), names.index("c_f")
    b, lk, cf = np.exp(keep[..., i_b].ravel()), keep[..., i_k].ravel(), np.exp(keep[..., i_cf].ravel())
    edges = np.arange(np.floor(lk.min()), np.ceil(lk.max()) + 1.0)
    ridge = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        m = (lk >= lo) & (lk < hi)
        if m.sum() >= 10:
            ridge.append({"log_k_n_from": lo, "log_k_n_to": hi, "share": round(float(m.mean()), 4),
                          "b_mean": round(float(b[m].mean()), 2), "b_sd": round(float(b[m].std()), 2),
                          "c_f_mean": round(float(cf[m].mean()), 1), "log_post_mean": round(float(lpk[m].mean()), 2)})
    with open(out / "ridge.csv", "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(ridge[0]))
        w.writeheader()
        w.writerows(ridge)

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    truth = rec.metadata.get("true_parameters") or {}
    fig, (a, c) = plt.subplots(1, 2, figsize=(12, 4.5))
    a.hist2d(lk / np.log(10), b, bins=60, cmap="Greys")
    if "k_n" in truth and "b" in truth:
        a.plot(np.log10(truth["k_n"]), truth["b"], "r*", ms=12, label="generating values")
        a.legend()
    a.set_xlabel("log10 k_n (N/m)")
    a.set_ylabel("b (kg)")
    a.set_title(f"{out.name}: b against the nut stiffness (after burn-in)")
    walkers = chain[..., i_k] / np.log(10)
    c.plot(np.arange(n), walkers, lw=0.4, alpha=0.7)
    c.set_xlabel("step")
    c.set_ylabel("log10 k_n of each walker")
    c.set_title(f"{chain.shape[1]} walkers, {n} steps; last R-hat {rows[-1]['max_rhat']}")
    fig.tight_layout()
    fig.savefig(out / "ridge.png", dpi=100)
    plt.close(fig)
    print(f"wrote {out}/tau.csv, ridge.csv, ridge.png; tau at {rows[-1]['steps']} steps: "
          f"b {rows[-1]['tau_b']}, k_n {rows[-1]['tau_k_n']}; max R-hat {rows[-1]['max_rhat']}")
    if truth:
        print(f"generating values: b {truth.get('b')}, k_n {truth.get('k_n')}")


if __name__ == "__main__":
    main()
