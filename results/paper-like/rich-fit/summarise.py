"""Usage: python summarise.py REC.csv OUT.csv FIT_FOLDER[=WALL_S] ...

One row per fit: b's median and 94 % HDI from all kept draws (fit.json's burn-in and
thin over chain.h5, as summary.csv takes them), against the record's true b."""
import csv, json, sys
import arviz as az
import h5py
import numpy as np
from bayes_inerter.records.io import read_record
from bayes_inerter.inference.posterior.model import LikelihoodSettings, PosteriorModel
from bayes_inerter.inference.sampling.coordinates import default_coordinates
from bayes_inerter.inference.sampling.checkpoint import read_chain

rec_path, out_csv = sys.argv[1], sys.argv[2]
record = read_record(rec_path)
meta = record.metadata
true_b = meta["true_parameters"]["b"]
gen = meta["generator"]
rows = []
for arg in sys.argv[3:]:  # FOLDER or FOLDER=WALL_SECONDS (the shell's `time`, all legs)
    folder, _, wall = arg.partition("=")
    fit = json.load(open(f"{folder}/fit.json"))
    pm = PosteriorModel(record, fit["model"], m_s=fit["m_s"], m_B=fit["m_B"], likelihood=LikelihoodSettings())
    coords = default_coordinates(pm, fit.get("coordinates", "impedance").split()[0])
    chain = read_chain(f"{folder}/chain.h5")
    assert len(chain) == fit["iterations"], (len(chain), fit["iterations"])
    burn, thin = fit["burn_in"], fit["thin"]
    keep = slice(burn + thin - 1, None, thin)  # emcee get_chain(discard, thin)
    theta = coords.to_theta(chain[keep])
    values = pm.to_values(theta)
    with h5py.File(f"{folder}/chain.h5", "r", locking=False) as f:
        phi = f["mcmc/blobs"][: fit["iterations"]][keep]
    draws = {n: values[..., i].ravel() for i, n in enumerate(pm.names)}
    draws["phi"] = np.asarray(phi, float).ravel()
    summ = {r["name"]: r for r in csv.DictReader(open(f"{folder}/summary.csv"))}
    assert abs(np.mean(draws["b"]) / float(summ["b"]["mean"]) - 1) < 1e-9, "not summary.csv's draws"

    def stat(name):
        x = draws[name]
        lo, hi = az.hdi(x, hdi_prob=0.94)
        return float(np.median(x)), float(lo), float(hi)

    b, blo, bhi = stat("b")
    ph, phlo, phhi = stat("phi")
    rhat = max(float(r["r_hat"]) for r in summ.values())
    ess = min(float(r["ess_bulk"]) for r in summ.values())
    row = dict(model=fit["model"], steps=fit["iterations"], walkers=fit["walkers"], kept_draws=draws["b"].size,
               converged=fit["converged"], tau_max=round(max(fit["tau"].values()), 1),
               max_rhat=round(rhat, 3), min_ess_bulk=round(ess), true_b=true_b,
               b_median=round(b, 1), b_hdi94_lo=round(blo, 1), b_hdi94_hi=round(bhi, 1),
               covers=bool(blo <= true_b <= bhi), rel_error_pct=round(100 * (b - true_b) / true_b, 3),
               phi_median=round(ph, 4), phi_hdi94_lo=round(phlo, 4), phi_hdi94_hi=round(phhi, 4),
               sampling_s=round(fit["timings_s"]["sampling_all_runs"], 1),
               wall_s=round(float(wall), 1) if wall else "")
    for name, truth in (("r_s", gen["stribeck_ratio"]), ("v_s", gen["stribeck_velocity"]), ("gap", gen["backlash"])):
        if name in draws:
            m, lo, hi = stat(name)
            row.update({f"{name}_median": f"{m:.4g}", f"{name}_hdi94_lo": f"{lo:.4g}", f"{name}_hdi94_hi": f"{hi:.4g}"})
        else:
            row.update({f"{name}_median": "", f"{name}_hdi94_lo": "", f"{name}_hdi94_hi": ""})
        row[f"{name}_device"] = f"{truth:.4g}"
    for name in ("f1_0", "f2_0"):
        src = draws[name] if name in draws else pm.derived({n: values[..., i] for i, n in enumerate(pm.names)})[name].ravel()
        row[f"{name}_median"] = f"{float(np.median(src)):.4g}"
        row[f"{name}_true"] = f"{meta['true_parameters'][name]:.4g}"
    rows.append(row)
with open(out_csv, "w", newline="") as f:
    w = csv.DictWriter(f, fieldnames=list(rows[0]))
    w.writeheader(); w.writerows(rows)
for r in rows:
    print(r)
