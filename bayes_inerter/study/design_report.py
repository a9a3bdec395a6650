"""The design study's REPORT.md (``study.design``), written from its tables."""

from __future__ import annotations

from pathlib import Path

from .markdown import table
from .report import NOT_IDENTIFIED

__all__ = ["design_report"]


def design_report(out: Path, rows: list[dict], shifts: list[dict], names: list[str], versions: dict,
                  seed: int) -> Path:
    """``out``/REPORT.md of the design study (``study.design``), written from its tables."""
    base_label = rows[0]["design"]
    settings = list(dict.fromkeys(r["setting"] for r in rows))
    lines = ["# What the experiments identify, and what a richer device does to b", "",
             "Laplace (normal) approximations at the generating parameters, no sampling: exact for a posterior "
             "that is normal in the sampled scale, optimistic where it is not. Records generated at the paper's "
             f"parameters, noise seed {seed}.", "",
             "Read the contractions with care: they come out near 0 or 1, because the normal approximation either "
             "sees curvature in a direction or gives it the prior's spread. A posterior pressed against a prior "
             "bound (the Coulomb share lies at 0.996 of its [0, 1] range) or flat up to a one-sided cliff (the nut "
             "stiffness) is beyond it: such entries flip between neighbouring designs and are noise. The robust "
             "findings are the patterns that hold across settings; the sampled contraction of the full study "
             "(`results/full/contraction.csv`) is the measure for the paper's own design.", "",
             "## Design sensitivity", ""]
    for s in settings:
        sub = [r for r in rows if r["setting"] == s]
        base = next(r for r in sub if r["design"] == base_label)
        weak = [n for n in names if base[n] < NOT_IDENTIFIED]
        parts = []
        for n in weak:
            best = max(sub, key=lambda r: r[n])
            parts.append(f"{n} {base[n]:.2f} -> {best[n]:.2f} with '{best['design']}'"
                         if best[n] > base[n] + 0.05 else f"{n} {base[n]:.2f}, no design here does better")
        lines.append(f"- **{s}**: under '{base_label}' not identified (contraction below {NOT_IDENTIFIED}): "
                     + ("; ".join(parts) if parts else "none") + f". Relative sd of b: {100 * base['b_rel_sd']:.2f} %.")
    lines += ["", "![design](design.png)", "",
              table(rows, ["design", "setting", "force_peak", "b_rel_sd"] + names,
                     {"force_peak": "{:.0f}", "b_rel_sd": "{:.4f}"} | {n: "{:.2f}" for n in names}), "",
              "`force_peak` (N) is what the actuator must deliver; `b_rel_sd` the sd of log b.", "",
              "## Fitting the two-port model to a richer device", ""]
    ref = {(r["setting"], r["freq_hz"]): r for r in shifts if r["truth"] == "model's own"}
    for r in shifts:
        if r["truth"] == "model's own":
            continue
        own = ref.get((r["setting"], r["freq_hz"]))
        lines.append(f"- {r['setting']} {r['freq_hz']:g} Hz, truth with {r['truth']}: b {r['b_optimum']:.1f} kg "
                     f"against {r['b_true']:.1f} ({r['shift_pct']:+.2f} %, {r['shift_sd']:+.1f} sd)"
                     + (f"; on the model's own device the same fit is {own['shift_pct']:+.2f} % "
                        f"({own['shift_sd']:+.1f} sd)." if own else "."))
    lines += ["", "The optimum of the model's log posterior that Nelder-Mead reaches from the device's parameters, and "
              "its Laplace sd; a shift of several sd means the interval would miss the device's b.", "",
              table(shifts, ["setting", "freq_hz", "truth", "b_true", "b_optimum", "b_sd", "shift_pct", "shift_sd",
                              "phi"], {"b_true": "{:.1f}", "b_optimum": "{:.1f}", "b_sd": "{:.1f}",
                                       "shift_pct": "{:+.2f}", "shift_sd": "{:+.1f}", "phi": "{:.4f}"}), "",
              "Versions: " + ", ".join(f"{k} {v}" for k, v in versions.items()) + ".", ""]
    path = Path(out) / "REPORT.md"
    path.write_text("\n".join(lines))
    return path
