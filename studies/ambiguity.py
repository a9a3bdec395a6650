"""What the records cannot tell apart: the inertance b that the same data give as the
parameters they do not identify move.

    python studies/ambiguity.py [--out results/sensitivity/ambiguity.csv]

A record fixes the driving-point impedance of the network's linear part at its drive
frequency: its inertial part M = Im Z / omega and its resistive part C = Re Z
(``inference.sampling.coordinates``). For every setting and drive frequency of the paper's grid
(paper parameters), this holds M and C at the generating values and solves b exactly
(the impedance coordinates' inverse) while one unidentified parameter moves:

- the share of the viscous friction on the plate (0, 0.5, 1; the paper's: about 0);
- the nut stiffness k_n (1e3 N/m, the prior's lower end; the paper's 4.35e5; 1e7 N/m,
  near where the records' likelihood falls off at these frequencies).

To first order b (1 - 2 c_f2 / c_n + b k_n / c_n^2) is what stays: the rows show how far
b can move at the same data, which is how wide b's posterior must be where these
parameters are not identified. No sampling; seconds.
"""

import argparse
import math
from pathlib import Path

import numpy as np

from _table import write_rows

ROOT = Path(__file__).resolve().parents[1]


def _solved_b(pm, coords, u, name, value):
    """b from u with the sampled parameter ``name`` set to ``value`` (M and C kept)."""
    i = pm.names.index(name)
    lo, hi = pm.bounds()[i]
    x = math.log(value) if pm.all_priors[name].log_scale else value
    p = min(max((x - lo) / (hi - lo), 1e-9), 1 - 1e-9)  # a value on the prior's bound: just inside
    v = u.copy()
    v[i] = math.log(p) - math.log1p(-p)  # the logit coordinate of its place in the prior box
    return float(np.exp(coords.to_theta(v)[pm.names.index("b")]))


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--out", default=str(ROOT / "results" / "sensitivity" / "ambiguity.csv"))
    args = ap.parse_args()

    from bayes_inerter import paper_parameters
    from bayes_inerter.device import FREQUENCIES_HZ, SETTINGS
    from bayes_inerter.inference import PosteriorModel
    from bayes_inerter.inference.sampling.coordinates import default_coordinates
    from bayes_inerter.records import GeneratorSettings, generate_record

    short = GeneratorSettings(duration=1.0, ramp=0.3, force_noise=0, accel_noise=0, disp_noise=0)
    rows = []
    for setting in SETTINGS:
        p = paper_parameters(setting)
        for freq in FREQUENCIES_HZ:
            # the record only carries the drive frequency and masses here: no simulation of it is used
            pm = PosteriorModel(generate_record(p, freq, settings=short, setting_name=setting))
            coords = default_coordinates(pm)
            u = coords.to_u(pm.to_theta(p, 3e-3, 0.1))
            row = {"setting": setting, "freq_hz": freq, "b_truth": p.b}
            for label, share in (("0", 0.0), ("0.5", 0.5), ("1", 1.0)):
                row[f"b_share_{label}"] = round(_solved_b(pm, coords, u, "c_share", share), 2)
            for label, k in (("1e3", 1e3), ("paper", p.k_n), ("1e7", 1e7)):
                row[f"b_k_n_{label}"] = round(_solved_b(pm, coords, u, "k_n", k), 2)
            row["spread_share_%"] = round(100 * (row["b_share_1"] / row["b_share_0"] - 1), 3)
            row["spread_k_n_%"] = round(100 * (row["b_k_n_1e7"] / row["b_k_n_1e3"] - 1), 3)
            rows.append(row)
    write_rows(args.out, rows)


if __name__ == "__main__":
    main()
