"""The demonstration: a generated paper record, simulated with the paper's networks."""

from __future__ import annotations

from pathlib import Path


from .device import paper_parameters
from .records import fit_accuracy, generate_record, lowpass, write_record
from .simulate import simulate

__all__ = ["run_demo"]


def run_demo(out: Path, *, setting: str = "A1", freq: float = 1.0, seed: int = 0) -> list[Path]:
    """Generate a record at the paper's parameters, simulate the reduced, rigid and linear
    networks from its force, plot them over its acceleration; return the files written."""
    import matplotlib.pyplot as plt

    from .plots import plot_fits, plot_record

    params = paper_parameters(setting)
    rec = generate_record(params, freq, rng=seed, setting_name=setting.upper())
    out.mkdir(parents=True, exist_ok=True)
    written = list(write_record(out / f"{setting.upper()}_{freq:g}Hz.csv", rec))
    measured = lowpass(rec.accel, rec.fs)
    fits = {}
    for name in ("reduced", "rigid", "linear"):
        a = lowpass(simulate(params, rec.time, rec.force, network=name), rec.fs)
        fits[name] = (a, float(fit_accuracy(a, measured)))
    cycle = 1.0 / freq
    t_mid = rec.time[-1] - 2 * cycle
    fig = plot_fits(
        rec.time, measured, fits, zoom=(t_mid, t_mid + cycle),
        title=f"setting {setting.upper()}, {freq:g} Hz: paper parameters, 30 Hz matched low-pass",
    )
    path = out / "demo_fits.png"
    fig.savefig(path, dpi=120)
    plt.close(fig)
    written.append(path)
    fig = plot_record(rec)
    path = out / "demo_record.png"
    fig.savefig(path, dpi=120)
    plt.close(fig)
    written.append(path)
    lines = ["network,phi"] + [f"{k},{v[1]:.6f}" for k, v in fits.items()]
    path = out / "demo_phi.csv"
    path.write_text("\n".join(lines) + "\n")
    written.append(path)
    return written
