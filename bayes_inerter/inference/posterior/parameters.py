"""The one map between the sampled parameters and the network's physical ones.

Two reparametrisations, each an option of :class:`ParameterMap`:

- ``split``: the two Coulomb forces and the two viscous coefficients are sampled as
  their sums and the plate's shares, ``f_0 = f1_0 + f2_0``, ``f_share = f1_0 / f_0``,
  ``c_f = c_f1 + c_f2``, ``c_share = c_f1 / c_f`` (the data fix the sums well and the
  shares poorly: MODEL.md section 7);
- ``modal``: the bearing's damper is sampled as the damping ratio of the plate's mode,
  ``zeta_B = c_B / (2 sqrt(k_B m_B))`` (**assumption**: the plate of mass m_B on the
  bearing's spring k_B is the mode's mass and stiffness; the records, low-passed at
  30 Hz, do not see the 170 Hz mode, so its damping comes from its prior,
  ``priors.MODAL_PRIORS``, as real structures' 0.5 to 10 %).

Every function works on scalars and on arrays of draws alike.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["ParameterMap", "FRICTION_PAIRS", "SPLIT_NAMES"]

#: The raw friction parameters the split replaces, and what replaces them.
FRICTION_PAIRS = ("f1_0", "f2_0", "c_f1", "c_f2")
SPLIT_NAMES = ("f_0", "f_share", "c_f", "c_share")


@dataclass(frozen=True)
class ParameterMap:
    """Sampled <-> physical parameters (see module docstring). ``m_B``: the plate's mass,
    kg, for ``modal``."""

    split: bool = True
    modal: bool = False
    m_B: float = 1.0

    def sampled_names(self, free) -> list[str]:
        """The sampled names standing for the physical ``free`` ones, in their order (the
        split's four where the friction pair was)."""
        names = [n for n in free if not (self.split and n in FRICTION_PAIRS)]
        if self.split:
            names[1:1] = list(SPLIT_NAMES)
        if self.modal:
            names = ["zeta_B" if n == "c_B" else n for n in names]
        return names

    def physical(self, values: dict) -> dict:
        """The physical parameters the sampled ``values`` (by name) stand for; the other
        entries passed through."""
        out = dict(values)
        if self.split:
            f0, fs, c, cs = (values[n] for n in SPLIT_NAMES)
            out.update(f1_0=f0 * fs, f2_0=f0 * (1.0 - fs), c_f1=c * cs, c_f2=c * (1.0 - cs))
        if self.modal and "zeta_B" in values:
            out["c_B"] = 2.0 * values["zeta_B"] * np.sqrt(values["k_B"] * self.m_B)
        return out

    def sampled(self, phys: dict) -> dict:
        """The sampled quantities (by name) at the physical parameters ``phys``, where they
        can be formed; the other entries passed through."""
        out = dict(phys)
        if self.split and all(k in phys for k in FRICTION_PAIRS):
            f0, c = phys["f1_0"] + phys["f2_0"], phys["c_f1"] + phys["c_f2"]
            out.update(f_0=f0, c_f=c, f_share=phys["f1_0"] / f0 if f0 > 0 else 0.5,
                       c_share=phys["c_f1"] / c if c > 0 else 0.5)
        if self.modal and "c_B" in phys and "k_B" in phys:
            out["zeta_B"] = phys["c_B"] / (2.0 * np.sqrt(phys["k_B"] * self.m_B))
        return out
