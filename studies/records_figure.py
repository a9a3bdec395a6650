"""Figure: two generated records (A0 at 0.5 Hz and B2 at 1.5 Hz) as a person would look at them.

Writes results/records/records.png. The records themselves (800 kB of CSV each) are
remade by the same two calls, so they are not committed: ``--records DIR`` writes them
there as well. Run: ``python studies/records_figure.py [--records runs/records]``.
"""

import argparse
from pathlib import Path

from bayes_inerter import paper_parameters
from bayes_inerter.plots import plot_records
from bayes_inerter.records import generate_record, write_record
from bayes_inerter.study.manifest import script_configuration, write_manifest

OUT = Path(__file__).resolve().parents[1] / "results" / "records"


def main():
    import matplotlib.pyplot as plt  # after bayes_inerter.plots, which picks the Agg backend

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--records", default=None, help="a folder to write the two records into (default: none)")
    args = ap.parse_args()
    OUT.mkdir(parents=True, exist_ok=True)
    write_manifest(OUT, script_configuration())
    records, labels = [], []
    for seed, (name, freq) in enumerate((("A0", 0.5), ("B2", 1.5))):
        rec = generate_record(paper_parameters(name), freq, rng=seed, setting_name=name)
        if args.records:
            Path(args.records).mkdir(parents=True, exist_ok=True)
            write_record(Path(args.records) / f"{name}_{freq:g}Hz.csv", rec)
        records.append(rec)
        labels.append(f"{name} at {freq:g} Hz (paper parameters, default generator)")
    fig = plot_records(records, labels=labels)
    fig.savefig(OUT / "records.png", dpi=110)
    plt.close(fig)
    print(f"wrote {OUT / 'records.png'}")


if __name__ == "__main__":
    main()
