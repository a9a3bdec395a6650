"""Parallel tempering against the default sampler: evaluations per autocorrelation time.

Issue 40, item 1 and issue 39, item 4: single-record chains are slow (tau of 100 to
2,000 steps) and results/chain-geometry found their posteriors far from one hump (a
third to two thirds of midpoints between two draws more than 10 nats down). Tempering
is the textbook answer to such shapes: besides the posterior (beta = 1), ensembles at
``--temps`` - 1 hotter targets prior x likelihood^beta (beta geometric from 1 down to
``--beta-min``) walk with the default ensemble moves (``sampler.default_moves``), and
after every step each walker of one temperature is offered a swap with a walker of the
next hotter one (a random pairing), accepted with probability
min(1, exp((beta_k - beta_k+1) (log L_j - log L_i))), which leaves the product of the
tempered targets invariant. The cold ensemble's chain is the posterior's. The sampler
has since taken it in as an option (``sampler.Tempering``, ``fit --tempering``); this
probe keeps its own loop so that results/chain-geometry's rows can be made again as
they were.

For each record, a default fit of ``--steps`` steps (``fit_record`` as the command line
runs it, seeded by the replicate, the laboratory or the grid record, as results/chain-geometry's,
``benchmarks/bench_misfit.py``'s and the noise-free study's fits; kept in ``--fits`` and reused) gives the baseline's largest autocorrelation
time and the walkers the tempered ensembles start from (temperature k from the
walkers of step ``-1 - 250 k``, so that no two walkers of an ensemble coincide); the
tempered run then makes as many evaluations of the log posterior as that fit's chain
(``--steps`` x walkers), and its cold chain's largest tau is read on its last two
thirds. Both start at the default chain's equilibrium or what it reached, which
favours the tempered run by the default's transient; the default's tau comes from the
same number of evaluations.

Records: ``sbc:SEED:REPLICATE`` (a replicate of the single-record calibration,
``study.study_calibration.replicate_device``, fitted under its priors as the coverage
chunks fit it) or ``paper:LABORATORY:SETTING:FREQ`` (a paper-like record,
``records.paper_like.paper_like_record``, 10 s, fitted with the package's defaults) or
``nf:K`` (record K of results/noise-free-chains-v3: the generator's noise-free record of
the paper's grid, its plate mode damped 2 %, fitted with the package's defaults).
``--check`` first runs the swaps on a bimodal target whose mode weights are known
(:class:`Bimodal`; rows to ``--out``/tempering_check.csv). Rows go to ``--out``/tempering.csv (a record's earlier rows of the same temperatures
replaced). Random draws: the swaps' from ``numpy.random.default_rng`` seeded by the
record and ladder, each ensemble's moves from a ``RandomState`` seeded the same way.

    python studies/tempering_probe.py [--check] --record sbc:11:1 --record paper:11:A3:1 [--temps 4]
        [--beta-min 0.1] [--steps 3000] [--out results/chain-geometry] [--fits runs/tempering]
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import zlib
from pathlib import Path

import emcee
import numpy as np

from _table import git_commit, read_rows, sampled_model, sbc_design_records, write_rows
from bayes_inerter.inference import LikelihoodSettings, PosteriorModel, fit_record
from bayes_inerter.inference.sampling.checkpoint import read_chain
from bayes_inerter.inference.sampling.convergence import Convergence, Monitor, integrated_time, why_not
from bayes_inerter.inference.sampling.sampler import default_moves
from bayes_inerter.records import GeneratorSettings, generate_record
from bayes_inerter.records.paper_like import PaperLike, paper_like_record
from bayes_inerter.study.noise_free import NOISE_FREE, grid_case
from bayes_inerter.study.noise_free import device as noise_free_device
from bayes_inerter.study.study_calibration import STUDY_SBC_PRIORS

ROOT = Path(__file__).resolve().parents[1]
#: The noise-free records' plate-mode damping ratio, results/noise-free-chains-v3's.
NOISE_FREE_ZETA_B = 0.02
FIELDS = ("record", "freq_hz", "commit", "temps", "beta_min", "steps", "walkers", "evaluations", "default_tau",
          "default_evaluations_per_tau", "tau", "slowest", "evaluations_per_tau", "ratio", "swap_rates", "b_truth",
          "default_b_3", "default_b_50", "default_b_97", "b_3", "b_50", "b_97", "seconds")


def record_of(spec: str):
    """(record, priors or None, likelihood, b's truth) of a ``--record`` spec."""
    kind, *rest = spec.split(":")
    if kind == "sbc" and len(rest) == 2:
        _, _, record, b_true = next(sbc_design_records(int(rest[0]), [int(rest[1])]))
        return record, STUDY_SBC_PRIORS, LikelihoodSettings(residual="motion"), float(b_true)
    if kind == "paper" and len(rest) == 3:
        rec = paper_like_record(rest[1], float(rest[2]), seed=int(rest[0]),
                                device=PaperLike(base=GeneratorSettings(duration=10.0)))
        return rec, None, LikelihoodSettings(), float(rec.metadata["true_parameters"]["b"])
    if kind == "nf" and len(rest) == 1:
        setting, freq = grid_case(int(rest[0]))
        p = noise_free_device(setting, NOISE_FREE_ZETA_B)
        return generate_record(p, freq, settings=NOISE_FREE, setting_name=setting), None, LikelihoodSettings(), p.b
    raise SystemExit(f"error: --record {spec!r} is none of sbc:SEED:REPLICATE, paper:LABORATORY:SETTING:FREQ, nf:K")


def default_fit(record, priors, likelihood, out: Path, steps: int, seed: int) -> None:
    """The baseline: ``fit_record`` for ``steps`` steps into ``out`` (kept if there)."""
    if not (out / "fit.json").exists():
        t0 = time.perf_counter()
        kwargs = {} if priors is None else {"priors": priors}
        fit_record(record, out, steps=steps, seed=seed, plots=False, likelihood=likelihood, **kwargs)
        (out / "seconds.txt").write_text(f"{time.perf_counter() - t0:.1f}\n")


class Tempered:
    """The log posterior's two parts in the sampler's coordinates: the prior with the
    coordinates' Jacobian, and the log-likelihood (both -inf outside)."""

    def __init__(self, model, coords):
        self.model, self.coords, self.calls = model, coords, 0

    def parts(self, u) -> tuple[float, float]:
        self.calls += 1
        theta, log_jac = self.coords.transform(np.atleast_2d(u))
        theta, log_jac = theta[0], float(log_jac[0])
        if not (np.all(np.isfinite(theta)) and np.isfinite(log_jac)):
            return -np.inf, -np.inf
        prior = self.model.log_prior(theta)
        got = self.model.log_likelihood(theta) if np.isfinite(prior) else None
        if got is None or not np.isfinite(got[0]):
            return -np.inf, -np.inf
        return prior + log_jac, float(got[0])

    def at(self, beta: float):
        """emcee's log-probability at temperature 1 / ``beta``, the log-likelihood its blob."""
        def log_prob(u):
            prior, loglik = self.parts(u)
            return (prior + beta * loglik, loglik) if np.isfinite(prior + loglik) else (-np.inf, -np.inf)
        return log_prob


def tempered_steps(target, moves, starts: list, betas: np.ndarray, seed: str):
    """Yield (the cold ensemble's state, the swaps accepted so far at each adjacent pair)
    after each step of every ensemble and the swaps (see module docstring)."""
    n, walkers = len(betas), starts[0].shape[0]
    samplers = [emcee.EnsembleSampler(walkers, starts[0].shape[1], target.at(float(beta)), moves=moves)
                for beta in betas]
    rng = np.random.default_rng(zlib.crc32(seed.encode()))
    # each ensemble's moves draw from the random state its State carries (emcee's seeding)
    states = [emcee.State(start.copy(), random_state=np.random.RandomState(zlib.crc32(f"{seed}-{k}".encode())).get_state())
              for k, start in enumerate(starts)]
    swaps = np.zeros(n - 1)
    while True:
        for k, s in enumerate(samplers):
            for states[k] in s.sample(states[k], iterations=1, store=False, skip_initial_state_check=True):
                pass
        for k in range(n - 2, -1, -1):  # swaps, hottest pair first
            a, b = states[k], states[k + 1]
            pair = rng.permutation(walkers)
            gain = (betas[k] - betas[k + 1]) * (b.blobs[pair] - a.blobs)
            take = np.isfinite(gain) & (np.log(rng.uniform(size=walkers)) < gain)
            for i in np.nonzero(take)[0]:
                j = pair[i]
                prior_i = a.log_prob[i] - betas[k] * a.blobs[i]
                prior_j = b.log_prob[j] - betas[k + 1] * b.blobs[j]
                L_i, L_j = a.blobs[i], b.blobs[j]
                a.coords[i], b.coords[j] = b.coords[j].copy(), a.coords[i].copy()
                a.log_prob[i], a.blobs[i] = prior_j + betas[k] * L_j, L_j
                b.log_prob[j], b.blobs[j] = prior_i + betas[k + 1] * L_i, L_i
            swaps[k] += take.mean()
        yield states[0], swaps


def tempered_chain(target, moves, starts: list, betas: np.ndarray, steps: int, seed: str):
    """The cold ensemble's chain (steps, walkers, d) and each adjacent pair's swap rate."""
    cold, swaps = [], None
    for state, swaps in tempered_steps(target, moves, starts, betas, seed):
        cold.append(state.coords.copy())
        if len(cold) == steps:
            return np.array(cold), swaps / steps


def tempered_to_rule(target, moves, starts, betas, seed: str, coords, conv: Convergence):
    """The cold chain run until the package's convergence rule ``conv`` holds on it
    (checked every ``conv.check_every`` steps, in theta) or ``conv.max_steps``: (chain,
    the last check, converged, swap rates)."""
    monitor = Monitor(conv)
    cold, lp = [], []
    for state, swaps in tempered_steps(target, moves, starts, betas, seed):
        cold.append(state.coords.copy())
        lp.append(state.log_prob.copy())
        n = len(cold)
        if n % conv.check_every == 0 or n >= conv.max_steps:
            chain = np.array(cold)
            check, ok = monitor.check(coords.to_theta(chain), np.array(lp))
            if ok or n >= conv.max_steps:
                return chain, check, ok, swaps / n


class Bimodal:
    """A check of the swaps: a box prior on [-10, 10]^2 and a likelihood of two narrow
    normals (sd 0.5) at (4, 4) and (-4, -4) with weights 0.3 and 0.7; emcee's moves
    alone, started in the lighter mode, never leave it."""

    WEIGHT = 0.3

    def __init__(self):
        self.calls = 0

    def at(self, beta: float):
        def log_prob(u):
            self.calls += 1
            if np.any(np.abs(u) > 10.0):
                return -np.inf, -np.inf
            loglik = np.logaddexp(np.log(self.WEIGHT) - 2.0 * np.sum((u - 4.0) ** 2),
                                  np.log(1.0 - self.WEIGHT) - 2.0 * np.sum((u + 4.0) ** 2))
            return beta * loglik, loglik
        return log_prob


def bimodal_check(seed: str, steps: int = 4000, walkers: int = 16) -> dict:
    """The cold chain's share of draws in the lighter mode (expected ``Bimodal.WEIGHT``)
    after its first quarter, four temperatures down to beta 0.01, every walker started
    in the lighter mode."""
    rng = np.random.default_rng(zlib.crc32(seed.encode()))
    starts = [4.0 + 0.3 * rng.standard_normal((walkers, 2)) for _ in range(4)]
    moves = [(emcee.moves.DEMove(), 0.6), (emcee.moves.DESnookerMove(), 0.1), (emcee.moves.StretchMove(), 0.3)]
    cold, swap = tempered_chain(Bimodal(), moves, starts, np.geomspace(1.0, 0.01, 4), steps, seed)
    return {"seed": seed, "steps": steps, "walkers": walkers, "expected": Bimodal.WEIGHT,
            "share": round(float(np.mean(cold[steps // 4:, :, 0] > 0.0)), 4), "swap_rates": " ".join(f"{s:.3f}" for s in swap)}


def b_quantiles(model, coords, draws: np.ndarray) -> dict:
    """b's 3, 50 and 97 % quantiles, kg, over ``draws`` (steps, walkers, d; sampler
    coordinates), by name ("3", "50", "97")."""
    theta = coords.transform(draws.reshape(-1, draws.shape[2]))[0]
    b = model.to_values(theta)[:, list(model.names).index("b")]
    return {q: round(float(v), 1) for q, v in zip(("3", "50", "97"), np.quantile(b, [0.03, 0.5, 0.97]))}


def setup(spec: str, steps: int, fits: Path):
    """(model, coordinates, the default chain, its largest tau, b's truth, frequency) of
    a record, its default fit made first where it is not in ``fits``."""
    record, priors, likelihood, b_true = record_of(spec)
    out = fits / spec.replace(":", "_")
    # the replicate's, the laboratory's or the grid record's, as their studies seed them
    seed = int(spec.split(":")[2 if spec.startswith("sbc") else 1])
    default_fit(record, priors, likelihood, out, steps, seed)
    model, coords = sampled_model(
        PosteriorModel(record, likelihood=likelihood, **({} if priors is None else {"priors": priors})), out / "chain.h5")
    default_tau = max(float(t) for t in json.loads((out / "fit.json").read_text())["tau"].values())
    return model, coords, read_chain(out / "chain.h5"), default_tau, b_true, record.metadata.get("drive_frequency_hz")


def probe(spec: str, temps: int, beta_min: float, steps: int, fits: Path, commit: str) -> dict:
    """The row of tempering.csv: the tempered run for the default fit's evaluations."""
    model, coords, base, default_tau, b_true, freq = setup(spec, steps, fits)
    walkers = base.shape[1]
    betas = np.geomspace(1.0, beta_min, temps)
    target = Tempered(model, coords)
    t0 = time.perf_counter()
    cold, swap = tempered_chain(target, default_moves(model, coordinates=coords),
                                [base[-1 - 250 * k] for k in range(temps)], betas, steps // temps,
                                f"{spec}-{temps}-{beta_min}")
    tau = integrated_time(cold[len(cold) // 3:])  # each parameter's, on the last two thirds
    per_step = target.calls / len(cold)
    row = {"record": spec, "freq_hz": freq, "commit": commit, "temps": temps,
           "beta_min": beta_min, "steps": len(cold), "walkers": walkers, "evaluations": target.calls,
           "default_tau": round(default_tau, 1), "default_evaluations_per_tau": round(default_tau * walkers),
           "tau": round(float(tau.max()), 1), "slowest": list(model.names)[int(tau.argmax())],
           "evaluations_per_tau": round(float(tau.max()) * per_step), "swap_rates": " ".join(f"{s:.3f}" for s in swap),
           "b_truth": round(b_true, 1), "seconds": round(time.perf_counter() - t0, 1)}
    row["ratio"] = round(row["evaluations_per_tau"] / row["default_evaluations_per_tau"], 3)
    for name, chain in (("default_b", base), ("b", cold)):  # each chain's last two thirds
        row.update({f"{name}_{q}": v for q, v in b_quantiles(model, coords, chain[len(chain) // 3:]).items()})
    return row


RULE_FIELDS = ("record", "freq_hz", "commit", "temps", "beta_min", "converged", "reason", "steps", "walkers",
               "evaluations", "default_steps", "tau", "slowest", "swap_rates", "b_truth", "b_3", "b_50", "b_97",
               "seconds")


def probe_rule(spec: str, temps: int, beta_min: float, steps: int, max_steps: int, fits: Path, commit: str) -> dict:
    """The row of tempering_rule.csv: the tempered run from the default fit's last
    walkers until the convergence rule holds on its cold chain (or ``max_steps``)."""
    model, coords, base, _, b_true, freq = setup(spec, steps, fits)
    betas = np.geomspace(1.0, beta_min, temps)
    target = Tempered(model, coords)
    t0 = time.perf_counter()
    conv = Convergence(max_steps=max_steps)
    chain, check, ok, swap = tempered_to_rule(target, default_moves(model, coordinates=coords),
                                              [base[-1 - 250 * k] for k in range(temps)], betas,
                                              f"{spec}-{temps}-{beta_min}-rule", coords, conv)
    tau = np.asarray(check.tau, dtype=float)
    row = {"record": spec, "freq_hz": freq, "commit": commit, "temps": temps, "beta_min": beta_min,
           "converged": bool(ok), "reason": "converged" if ok else why_not(len(chain), check, conv),
           "steps": len(chain), "walkers": chain.shape[1], "evaluations": target.calls, "default_steps": len(base),
           "tau": round(float(np.nanmax(tau)), 1), "slowest": list(model.names)[int(np.nanargmax(tau))],
           "swap_rates": " ".join(f"{s:.3f}" for s in swap), "b_truth": round(b_true, 1),
           "seconds": round(time.perf_counter() - t0, 1)}
    row.update({f"b_{q}": v for q, v in b_quantiles(model, coords, chain[check.warmup:]).items()})  # after the warm-up
    return row


def replace_row(path: Path, fields, row: dict) -> None:
    """Write ``row`` into the CSV file ``path`` in place of an earlier row of the same
    record and ladder (the other rows kept)."""
    key = (row["record"], str(row["temps"]), str(row["beta_min"]))
    kept = [r for r in read_rows(path) if (r["record"], r["temps"], r["beta_min"]) != key]
    write_rows(path, [{k: r.get(k, "") for k in fields} for r in kept + [row]])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--record", action="append", default=[], help="sbc:SEED:REPLICATE, paper:LAB:SETTING:FREQ or nf:K")
    ap.add_argument("--check", action="store_true",
                    help="first the swaps' check on a bimodal target (three seeds, tempering_check.csv)")
    ap.add_argument("--temps", type=int, default=4, help="temperatures, the posterior's included")
    ap.add_argument("--beta-min", type=float, default=0.1, help="the hottest ensemble's beta")
    ap.add_argument("--steps", type=int, default=3000, help="steps of the default fit (the evaluations' budget)")
    ap.add_argument("--converge", type=int, metavar="MAX_STEPS", default=0,
                    help="run the tempered chain to the convergence rule (at most MAX_STEPS cold steps) in place "
                         "of the fixed budget; rows to tempering_rule.csv")
    ap.add_argument("--out", default=str(ROOT / "results" / "chain-geometry"))
    ap.add_argument("--fits", default=str(ROOT / "runs" / "tempering"))
    args = ap.parse_args(argv)
    if args.temps < 2 or not 0.0 < args.beta_min < 1.0 or args.steps < 300 * args.temps:
        print("error: --temps must be at least 2, --beta-min in (0, 1) and --steps at least 300 x --temps",
              file=sys.stderr)
        return 2
    if not args.record and not args.check:
        print("error: give --record (one or more) or --check", file=sys.stderr)
        return 2
    commit = git_commit(ROOT)
    if args.check:
        rows = [{**bimodal_check(seed), "commit": commit} for seed in ("a", "b", "c")]
        for r in rows:
            print(f"bimodal check, seed {r['seed']}: share in the lighter mode {r['share']} (expected "
                  f"{r['expected']}); swaps {r['swap_rates']}", flush=True)
        write_rows(Path(args.out) / "tempering_check.csv", rows)
    for spec in args.record:
        if args.converge:
            row = probe_rule(spec, args.temps, args.beta_min, args.steps, args.converge, Path(args.fits), commit)
            print(f"{spec}: {row['reason']} after {row['steps']} cold steps, {row['evaluations']} evaluations, "
                  f"{row['seconds']} s; tau {row['tau']} ({row['slowest']}); swaps {row['swap_rates']}; b {row['b_50']} "
                  f"({row['b_3']} to {row['b_97']}), truth {row['b_truth']}", flush=True)
            replace_row(Path(args.out) / "tempering_rule.csv", RULE_FIELDS, row)
            continue
        row = probe(spec, args.temps, args.beta_min, args.steps, Path(args.fits), commit)
        print(f"{spec}: tau {row['tau']} steps ({row['slowest']}), {row['evaluations_per_tau']} evaluations per tau "
              f"against the default's {row['default_evaluations_per_tau']} (ratio {row['ratio']}); swaps "
              f"{row['swap_rates']}; b {row['b_50']} ({row['b_3']} to {row['b_97']}), default {row['default_b_50']}, "
              f"truth {row['b_truth']}", flush=True)
        replace_row(Path(args.out) / "tempering.csv", FIELDS, row)
    return 0


if __name__ == "__main__":
    sys.exit(main())
