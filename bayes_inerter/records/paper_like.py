"""Paper-like records: a device richer than any model the package fits.

The records of :func:`.generator.paper_grid` are made by the very network the study
fits; a real ball-screw inerter is not. :class:`PaperLike` describes a richer device and
its acquisition, every part of it an **assumption** with its default here (the paper
states none of them), sized so that the paper's reduced model, fitted by least squares,
reproduces a record about as well as the paper's Table 2 says it reproduced the
experiments (``studies/paper_like_phi.py`` measures that; ``results/paper-like/``):

- the full network (the nut's sin(theta) friction, :func:`..networks.full`);
- Stribeck friction on both contacts, break-away ``ratio`` times the Coulomb force,
  falling to it over ``velocity``;
- a dead zone of half-width ``backlash`` in the nut link;
- the sensors' sensitivities off by draws from their stated calibration uncertainty
  (:class:`.sensitivity.SensorCalibration`'s defaults);
- coloured sensor noise (a second-order low-pass at ``noise_corner``).

One seed is one laboratory: its device's effect sizes (and its pair of sensors) are
drawn once from the ranges below and shared by every record made with that seed, as
one ball screw and one pair of sensors serve all nine flywheel settings; each record
has its own noise. The true b per setting stays the paper's identified one
(:func:`..device.paper_parameters`), so a study can be held against it.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from ..device import FREQUENCIES_HZ, SETTINGS, paper_parameters
from .generator import GeneratorSettings, generate_record
from .record import Record
from .sensitivity import SensorCalibration

__all__ = ["PaperLike", "laboratory", "paper_like_record", "paper_like_grid"]


@dataclass(frozen=True)
class PaperLike:
    """The richer device's effect sizes: each a (low, high) range a record's value is
    drawn from (uniform; ``velocity`` and ``backlash`` uniform in log scale).

    Attributes
    ----------
    ratio : Stribeck break-away over Coulomb force, dimensionless.
    velocity : Stribeck velocity, m/s.
    backlash : nut backlash half-width, m.
    noise_corner : the sensors' noise colour, Hz (-3 dB of a second-order low-pass).
    force_delay, accel_delay : the sensors' pure delays, s (default 0: none; the
        generator's ``GeneratorSettings.force_delay``).
    force_noise, accel_noise : sensor noise rms, N and m/s^2.
    calibration : the sensors' relative standard uncertainties; each record's
        sensitivities are drawn normal about 1 with them.
    base : every other generator setting.
    """

    ratio: tuple[float, float] = (1.15, 1.35)
    velocity: tuple[float, float] = (5e-3, 2e-2)
    backlash: tuple[float, float] = (1e-6, 4e-6)
    noise_corner: float = 50.0
    force_delay: float = 0.0
    accel_delay: float = 0.0
    force_noise: float = 2.0
    accel_noise: float = 0.01
    calibration: SensorCalibration = SensorCalibration()
    base: GeneratorSettings = GeneratorSettings()

    def __post_init__(self) -> None:
        for name in ("ratio", "velocity", "backlash"):
            lo, hi = getattr(self, name)
            if not (math.isfinite(lo) and math.isfinite(hi) and 0 < lo <= hi):
                raise ValueError(f"paper-like {name} range must be 0 < low <= high, got {(lo, hi)}")
        if self.ratio[0] < 1.0:
            raise ValueError(f"paper-like break-away ratio must be at least 1, got {self.ratio}")

    def draw(self, rng: np.random.Generator) -> GeneratorSettings:
        """One record's generator settings."""
        def log_uniform(lo, hi):
            return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))

        return dataclasses.replace(
            self.base, network="full", friction="stribeck", stribeck_ratio=float(rng.uniform(*self.ratio)),
            stribeck_velocity=log_uniform(*self.velocity), backlash=log_uniform(*self.backlash),
            force_gain=float(1.0 + self.calibration.force * rng.standard_normal()),
            accel_gain=float(1.0 + self.calibration.accel * rng.standard_normal()),
            noise_corner=self.noise_corner, force_delay=self.force_delay, accel_delay=self.accel_delay,
            force_noise=self.force_noise, accel_noise=self.accel_noise)


def _streams(seed: int, frequencies, names) -> list:
    """The seed's streams: the laboratory's first, then one per record in the grid's order."""
    return np.random.SeedSequence(seed).spawn(1 + len(list(names)) * len(list(frequencies)))


def laboratory(seed: int, *, device: PaperLike | None = None, frequencies=FREQUENCIES_HZ,
               names=tuple(SETTINGS)) -> GeneratorSettings:
    """The generator settings every record of ``seed`` is made with (its device's effect
    sizes and its pair of sensors, ``force_gain`` and ``accel_gain`` among them): what a
    study needs to tell an error the sensors' calibration explains from the rest."""
    return (device or PaperLike()).draw(np.random.default_rng(_streams(seed, frequencies, names)[0]))


def paper_like_record(name: str, freq: float, *, seed: int = 0, device: PaperLike | None = None,
                      frequencies=FREQUENCIES_HZ, names=tuple(SETTINGS), duration: float | None = None) -> Record:
    """The paper-like record of setting ``name`` at ``freq``: the device drawn from the
    first stream spawned from ``seed`` (the same for every record of that seed), the
    noise from the record's own stream, spawned after it in the grid's order (as
    :func:`.generator.paper_record`), so each record can be made alone. ``duration``:
    the record's length, s, ramp included (None: the generator's, the paper's 10 s); the
    same laboratory and sensors, a longer record (its noise is drawn anew)."""
    names, frequencies = list(names), list(frequencies)
    if name not in names or freq not in frequencies:
        raise ValueError(f"no setting {name!r} at {freq:g} Hz in the grid")
    seeds = _streams(seed, frequencies, names)
    settings = laboratory(seed, device=device, frequencies=frequencies, names=names)
    if duration is not None:
        settings = dataclasses.replace(settings, duration=float(duration))
    rng = np.random.default_rng(seeds[1 + names.index(name) * len(frequencies) + frequencies.index(freq)])
    rec = generate_record(paper_parameters(name), freq, settings=settings, rng=rng, setting_name=name)
    rec.metadata["truth"] = "paper-like"
    return rec


def paper_like_grid(*, seed: int = 0, device: PaperLike | None = None, frequencies=FREQUENCIES_HZ,
                    names=tuple(SETTINGS)):
    """The 27 paper-like records (nine settings, three frequencies); yields (setting,
    frequency, Record)."""
    for name in names:
        for freq in frequencies:
            yield name, freq, paper_like_record(name, freq, seed=seed, device=device, frequencies=frequencies,
                                                names=names)
