"""What a miscalibrated sensor does to the identified inertance, against
``records.sensitivity``'s formula b_id = s (b + m) - m, s = g_F / g_a.

For each setting, two noise-free records at one frequency with ideal sensor bandwidths
(so that only the gains differ): one with exact sensitivities, one with the load cell
reading ``--force-gain`` and the accelerometer ``--accel-gain`` times the truth. Each is
fitted by the restarted Nelder-Mead from the generating parameters (the optimum, not a
posterior: noise-free records have no noise to average). Writes
``--out``/gains.csv and prints it.

    python studies/sensor_gains.py [--settings A0,B2] [--freq 1] [--force-gain 1.012]
        [--accel-gain 0.993] [--out results/sensitivity]

b itself lies on the nut's ridge (b against k_n, see ``studies/ridge_profile.py``) even
without noise, so the formula is compared on b_app, the inertance seen through the nut,
which the records fix.
"""

import argparse
import sys
from pathlib import Path

from _table import write_rows

ROOT = Path(__file__).resolve().parents[1]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--settings", default="A0,B2")
    ap.add_argument("--freq", type=float, default=1.0)
    ap.add_argument("--force-gain", type=float, default=1.012)
    ap.add_argument("--accel-gain", type=float, default=0.993)
    ap.add_argument("--out", default=str(ROOT / "results" / "sensitivity"))
    args = ap.parse_args()

    from tqdm import tqdm

    from bayes_inerter.device import apparent_inertance, paper_parameters
    from bayes_inerter.inference.posterior.model import PosteriorModel
    from bayes_inerter.inference.sampling.optimize import NM_RESTARTS, local_optimum
    from bayes_inerter.records.generator import GeneratorSettings, paper_record

    settings = [s.strip().upper() for s in args.settings.split(",") if s.strip()]
    quiet = dict(force_noise=0.0, accel_noise=0.0, disp_noise=0.0, force_bandwidth=None, accel_bandwidth=None)
    cases = [(name, gains) for name in settings for gains in ((1.0, 1.0), (args.force_gain, args.accel_gain))]
    rows = []
    try:
        for name, (g_f, g_a) in tqdm(cases, desc="fits", unit="fit", file=sys.stderr):
            gen = GeneratorSettings(**quiet, force_gain=g_f, accel_gain=g_a)
            rec = paper_record(name, args.freq, settings=gen)
            model = PosteriorModel(rec)
            p = paper_parameters(name)
            theta, lp = local_optimum(model, model.to_theta(p, sigma=1e-4, rho=0.5), restarts=NM_RESTARTS)
            v = model.values(theta)
            s, m = g_f / g_a, p.m_s + p.m_B
            app = apparent_inertance(p.b, p.k_n, p.c_n)
            rows.append({"setting": name, "freq_hz": args.freq, "force_gain": g_f, "accel_gain": g_a,
                         "b_truth": p.b, "b_app_truth": round(app, 2), "b_id": round(v["b"], 2),
                         "b_app_id": round(v["b_app"], 2), "b_app_formula": round(s * (app + m) - m, 2),
                         "b_app_corrected": round((v["b_app"] + m) / s - m, 2), "log_post": round(lp, 1)})
    except ValueError as exc:
        sys.exit(f"error: {exc}")
    print(f"wrote {write_rows(Path(args.out) / 'gains.csv', rows)}")


if __name__ == "__main__":
    main()
