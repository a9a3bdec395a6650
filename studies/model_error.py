"""Coverage of b's intervals on records of a device richer than the model.

Run from the project root:

    python studies/model_error.py --replicates 100 --out results/model-error [--processes 2]
        [--methods two-port two-port-rich joint] [--duration 10] [--seed 0]

Each replicate is one paper-like laboratory (``records.paper_like``, seed = replicate
number + ``--seed`` x 100,000) and one flywheel setting drawn uniformly from the nine; its
records are that setting at 0.5, 1 and 1.5 Hz. A single-record method fits the record at
one frequency drawn uniformly from the three; ``joint`` fits the setting's three records
together (one b). Every draw's seed is written to replicates.csv.

Each fit is summarised by the normal (Laplace) approximation of its posterior at the
optimum the sampler would start from (``optimize.find_start``, then
``optimize.laplace_covariance``), in log b: the intervals are exp(mu +- z sd) at 50 % and
94 %. ``--mcmc N`` also runs the default sampler (``fit_record``) on the first N
replicates' single records, to check the approximation against the posterior itself.
Methods whose name has ``+sensors`` add the sensors' calibration uncertainty
(``records.sensitivity.SensorCalibration``'s defaults) to the interval, ``+discrepancy``
the harmonic model discrepancy's share (``inference.discrepancy``).

Writes replicates.csv (one row per replicate and method), coverage.csv (per method:
replicates, coverage of the 50 % and 94 % intervals with binomial standard errors, median
relative width of the 94 % interval, median relative error of the centre) and
coverage.png.
"""

import argparse
import csv
import math
import sys
import time
from pathlib import Path

import numpy as np

from bayes_inerter.device import FREQUENCIES_HZ, SETTINGS
from bayes_inerter.executor import make_executor
from bayes_inerter.inference.discrepancy import harmonic_discrepancy
from bayes_inerter.inference.joint import JointModel
from bayes_inerter.inference.model import PosteriorModel
from bayes_inerter.inference.optimize import NM_RESTARTS, find_start, laplace_covariance, local_optimum
from bayes_inerter.records.generator import GeneratorSettings
from bayes_inerter.records.paper_like import PaperLike, paper_like_record
from bayes_inerter.records.sensitivity import SensorCalibration

Z50, Z94 = 0.6744897501960817, 1.8807936081512509  # normal quantiles of 0.75 and 0.97
METHODS = ("two-port", "two-port+sensors", "two-port+discrepancy", "two-port+discrepancy+sensors",
           "two-port-stribeck", "two-port-backlash", "two-port-rich", "two-port-rich+discrepancy", "joint",
           "joint+sensors", "joint+discrepancy", "joint+discrepancy+sensors")


def _laplace_b(model, theta, name: str) -> tuple[float, float]:
    """(mu, sd) of log b in the Laplace approximation at ``theta``."""
    cov = laplace_covariance(model, theta)
    i = model.names.index(name)
    return float(theta[i]), float(math.sqrt(max(cov[i, i], 0.0)))


def _single(rec, model_name: str, rng) -> dict:
    pm = PosteriorModel(rec, model_name)
    theta, _ = find_start(pm, rng)
    mu, sd = _laplace_b(pm, theta, "b")
    return {"mu": mu, "sd": sd, "phi": pm.log_prob(theta)[1],
            "discrepancy": harmonic_discrepancy(pm, theta).sd_log_b}


def _joint(recs, setting: str, rng) -> dict:
    jm = JointModel(tuple(recs))
    centres = [part.values(find_start(part, rng)[0]) for part in jm.parts]
    theta, _ = local_optimum(jm, jm.start(centres), restarts=NM_RESTARTS)
    mu, sd = _laplace_b(jm, theta, f"b_{setting}")
    # each record's discrepancy at the joint optimum, combined as independent evidence
    parts = [harmonic_discrepancy(part, jm.part_theta(theta, k)).sd_log_b for k, part in enumerate(jm.parts)]
    precision = sum(1.0 / v ** 2 for v in parts if v > 0)
    return {"mu": mu, "sd": sd, "phi": jm.log_prob(theta)[1],
            "discrepancy": math.sqrt(1.0 / precision) if precision > 0 else 0.0}


def _interval(mu: float, sd: float, z: float) -> tuple[float, float]:
    return math.exp(mu - z * sd), math.exp(mu + z * sd)


def replicate(job) -> list[dict]:
    k, args = job
    seed = k + 100_000 * args.seed
    rng = np.random.default_rng([args.seed, k])
    setting = str(rng.choice(list(SETTINGS)))
    freq = float(rng.choice(FREQUENCIES_HZ))
    device = PaperLike(base=GeneratorSettings(duration=args.duration))
    recs = {f: paper_like_record(setting, f, seed=seed, device=device) for f in
            (FREQUENCIES_HZ if "joint" in args.methods else (freq,))}
    rec = recs[freq]
    truth = rec.metadata["true_parameters"]["b"]
    gen = rec.metadata["generator"]
    rows = []
    fits = {}  # one fit per model; its variants add terms to the same posterior
    for method in args.methods:
        t0 = time.perf_counter()
        fit_rng = np.random.default_rng([args.seed, k, 1])
        model_name = method.split("+")[0]
        if model_name not in fits:
            fits[model_name] = (_joint(list(recs.values()), setting, fit_rng) if model_name == "joint" else
                                _single(rec, model_name, fit_rng))
        got = fits[model_name]
        sd = got["sd"]
        if "+discrepancy" in method:
            sd = math.hypot(sd, got["discrepancy"])
        if method.endswith("+sensors"):
            cal = SensorCalibration()
            m = rec.metadata["m_s"] + rec.metadata["m_B"]
            b = math.exp(got["mu"])
            sd = math.hypot(sd, cal.inertance_sd(b, 0.0, m) / b)
        lo50, hi50 = _interval(got["mu"], sd, Z50)
        lo94, hi94 = _interval(got["mu"], sd, Z94)
        rows.append({
            "replicate": k, "seed": seed, "setting": setting, "freq_hz": freq if model_name != "joint" else "all",
            "method": method, "b_true": truth, "b_centre": math.exp(got["mu"]), "sd_log_b": sd,
            "lo50": lo50, "hi50": hi50, "lo94": lo94, "hi94": hi94,
            "covered50": int(lo50 <= truth <= hi50), "covered94": int(lo94 <= truth <= hi94),
            "phi": got["phi"], "stribeck_ratio": gen["stribeck_ratio"], "stribeck_velocity": gen["stribeck_velocity"],
            "backlash": gen["backlash"], "force_gain": gen["force_gain"], "accel_gain": gen["accel_gain"],
            "seconds": round(time.perf_counter() - t0, 2),
        })
    return rows


def coverage(rows: list[dict]) -> list[dict]:
    out = []
    for method in dict.fromkeys(r["method"] for r in rows):
        mine = [r for r in rows if r["method"] == method]
        n = len(mine)
        row = {"method": method, "replicates": n}
        for level in ("50", "94"):
            p = float(np.mean([r[f"covered{level}"] for r in mine]))
            row[f"coverage{level}"] = round(p, 3)
            row[f"se{level}"] = round(math.sqrt(p * (1 - p) / n), 3)
        row["median_width94_pct"] = round(100 * float(np.median([(r["hi94"] - r["lo94"]) / r["b_true"] for r in mine])), 3)
        row["median_abs_error_pct"] = round(100 * float(np.median([abs(r["b_centre"] / r["b_true"] - 1) for r in mine])), 3)
        out.append(row)
    return out


_NUMBERS = ("b_true", "b_centre", "sd_log_b", "lo50", "hi50", "lo94", "hi94", "phi")


def _read(path: Path) -> list[dict]:
    """Rows written by an earlier run (numbers as numbers), or none."""
    if not path.exists():
        return []
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        r.update({k: float(r[k]) for k in _NUMBERS}, covered50=int(r["covered50"]), covered94=int(r["covered94"]))
    return rows


def _append(path: Path, rows: list[dict]) -> None:
    new = not path.exists()
    with open(path, "a", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        if new:
            w.writeheader()
        w.writerows(rows)


def _write(path: Path, rows: list[dict]) -> None:
    with open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def _figure(path: Path, table: list[dict]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 3.6))
    y = np.arange(len(table))
    for level, colour, nominal in (("50", "tab:blue", 0.5), ("94", "tab:red", 0.94)):
        ax.errorbar([r[f"coverage{level}"] for r in table], y, xerr=[2 * r[f"se{level}"] for r in table], fmt="o",
                    color=colour, label=f"{level} % interval (2 se)")
        ax.axvline(nominal, color=colour, ls=":", lw=1)
    ax.set_yticks(y, [r["method"] for r in table])
    ax.set_xlim(0, 1)
    ax.set_xlabel("share of replicates whose interval covers the true b")
    ax.set_title(f"b's intervals on paper-like records ({table[0]['replicates']} replicates)")
    ax.legend(loc="lower left", fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--replicates", type=int, default=100)
    ap.add_argument("--out", default="runs/model-error")
    ap.add_argument("--methods", nargs="+", default=["two-port", "two-port+sensors", "two-port+discrepancy",
                                                      "two-port+discrepancy+sensors", "joint", "joint+sensors",
                                                      "joint+discrepancy", "joint+discrepancy+sensors"])
    ap.add_argument("--duration", type=float, default=10.0, help="record length, s (%(default)s)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--processes", type=int, default=2)
    args = ap.parse_args()
    unknown = set(args.methods) - set(METHODS)
    if unknown:
        sys.exit(f"error: unknown methods {', '.join(sorted(unknown))}; choose from {', '.join(METHODS)}")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    partial = out / "replicates.partial.csv"  # each replicate's rows as it ends: a rerun goes on from them
    rows = _read(partial)
    done = {int(r["replicate"]) for r in rows}
    todo = [(k, args) for k in range(args.replicates) if k not in done]
    t0 = time.perf_counter()
    with make_executor(args.processes) as ex:
        for n, got in enumerate(ex.as_completed(replicate, todo), len(done) + 1):
            if not got.ok:
                sys.exit(f"error: replicate {todo[got.index][0]}: {got.error}")
            _append(partial, got.value)
            rows.extend(got.value)
            print(f"{n}/{args.replicates} replicates ({time.perf_counter() - t0:.0f} s)", file=sys.stderr, flush=True)
    rows = [r for r in rows if int(r["replicate"]) < args.replicates and r["method"] in args.methods]
    rows.sort(key=lambda r: (int(r["replicate"]), args.methods.index(r["method"])))
    _write(out / "replicates.csv", rows)
    table = coverage(rows)
    _write(out / "coverage.csv", table)
    _figure(out / "coverage.png", table)
    for row in table:
        print(", ".join(f"{k} {v}" for k, v in row.items()))


if __name__ == "__main__":
    main()
