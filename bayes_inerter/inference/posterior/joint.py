"""The joint model: all records at once, one inertance per flywheel setting.

The paper tuned one set of friction and deformation parameters for every flywheel
setting and one inertance per setting (its Tables I and 2). The joint model says the same:

- shared by all records: the two-port model's friction sums and shares, the nut and
  bearing stiffness and damping (``f_0, f_share, c_f, c_share, c_n, k_n, c_B, k_B``);
- one ``b_<setting>`` per flywheel setting among the records;
- each record's likelihood is the single-record model's, through the interface both
  share (``PosteriorModel.log_likelihood``). Under the default, motion in and force out
  at the harmonics, the discrepancy's ``tau`` (and ``alpha`` where sampled) is one per
  drive frequency (``PER_FREQUENCY``) and the channels' ``gain`` one for every record.
  Under the time-domain residuals each record's AR(1) scale sigma is **marginalised
  analytically** under the scale-invariant prior p(sigma) ~ 1/sigma (the single-record
  prior is log-uniform, the same law with bounds far from the data), so 27 records do
  not add 27 dimensions:

      log p(r | rho) = 0.5 log(1 - rho^2) + lgamma(n/2) - log 2 - (n/2) log(pi S),
      S = (1 - rho^2) r_0^2 + sum_t (r_t - rho r_{t-1})^2

  with one AR(1) coefficient ``rho_<f>Hz`` per drive frequency (an **assumption**: the
  residual's correlation is set by the signal's spectrum, which the frequency sets; a
  record's own rho differs from its frequency's by a few hundredths in the single-record
  fits).

The masses m_s and m_B of each record come from its metadata as in the single-record
model. ``log_prob`` returns (log posterior, mean phi over the records).
"""

from __future__ import annotations

import dataclasses
import math
from contextlib import contextmanager
from dataclasses import dataclass, field

import numpy as np

from ...device import SETTINGS, apparent_inertance
from ...executor import make_executor
from .likelihood import ar1_marginal
from .model import LikelihoodSettings, PosteriorModel

__all__ = ["JointModel", "ar1_marginal", "pooled_log_prob", "PER_FREQUENCY", "SPLIT_GAP", "RECORD_STARTS"]

#: The likelihood's parameters shared by the records of one drive frequency (the
#: residual's colour and the discrepancy are set by the signal's spectrum, which the
#: frequency sets: an **assumption**); the others (the channels' ``gain``: one pair of
#: sensors) by every record.
PER_FREQUENCY = ("rho", "tau", "alpha")


@dataclass
class JointModel:
    """Log-posterior of several records of one device (see module docstring).

    ``records`` are :class:`Record` objects whose metadata name their flywheel
    ``setting`` (the grid's records do; a user's need it). ``model``: the single-record
    model every record is fitted with (``model.MODELS``, the two-port model or a richer
    one; a richer one's effects are the device's, shared by every record).
    """

    records: tuple
    priors: dict = field(default_factory=dict)
    likelihood: LikelihoodSettings = field(default_factory=LikelihoodSettings)
    model: str = "two-port"
    #: the joint theta whose records' noise the motion-in likelihood's normaliser takes
    #: (``LikelihoodSettings.normaliser``; :meth:`with_reference`), each record at its
    #: own part of it
    reference: tuple | None = None

    def __post_init__(self) -> None:
        self.records = tuple(self.records)
        if len(self.records) < 2:
            raise ValueError("the joint model needs at least two records")
        settings = []
        for i, rec in enumerate(self.records):
            s = str(rec.metadata.get("setting") or "").upper()
            if s not in SETTINGS:
                raise ValueError(f"record {i}: its metadata must name a flywheel setting ({', '.join(SETTINGS)})")
            settings.append(s)
        if not self.model.startswith("two-port"):
            raise ValueError(f"the joint model shares the two-port model's parameters; got model {self.model!r}")
        # each record's settings with the joint fit's draws of the input noise made explicit
        part_likelihood = dataclasses.replace(self.likelihood, input_noise=self.likelihood.input_noise_draws())
        parts = [PosteriorModel(rec, self.model, priors=self.priors, likelihood=part_likelihood)
                 for rec in self.records]
        if any(p.truncations for p in parts):
            raise ValueError("the joint model takes no truncation of the prior (priors.TRUNCATIONS); "
                             "fit the records one at a time to use one")
        self.parts = parts
        self.records = tuple(p.record for p in parts)  # each with its drive frequency settled
        freqs = [p.drive.hz for p in parts]
        self.setting_of = settings
        self.freq_of = freqs
        self.settings = [s for s in SETTINGS if s in settings]
        self.frequencies = sorted(set(freqs))
        first = parts[0]
        shared = [n for n in first.names[: first.n_phys] if n != "b"]
        self.shared = shared
        hyper = [n for n in first.names[first.n_phys:] if n != "sigma"]  # sigma: marginalised
        self.per_frequency = [f"{n}_{f:g}Hz" for n in hyper if n in PER_FREQUENCY for f in self.frequencies]
        self.rhos = [n for n in self.per_frequency if n.startswith("rho_")]
        self.names = ([f"b_{s}" for s in self.settings] + shared + self.per_frequency
                      + [n for n in hyper if n not in PER_FREQUENCY])
        #: the inertance each setting shows through the nut (``device.apparent_inertance``)
        self.derived_names = [f"b_app_{s}" for s in self.settings]
        base = first.all_priors
        self.all_priors = {**{n: base[n] for n in self.names if n in base},
                           **{f"b_{s}": base["b"] for s in self.settings},
                           **{n: base[n.split("_")[0]] for n in self.per_frequency}}
        self._log = np.array([self.all_priors[n].log_scale for n in self.names])
        # where each part's theta comes from: index into the joint theta (sigma: none)
        pos = {n: i for i, n in enumerate(self.names)}
        self._maps = []
        for part, s, f in zip(parts, self.setting_of, self.freq_of):
            idx = []
            for n in part.names:
                if n == "b":
                    idx.append(pos[f"b_{s}"])
                elif n == "sigma":
                    idx.append(-1)
                elif n in PER_FREQUENCY:
                    idx.append(pos[f"{n}_{f:g}Hz"])
                else:
                    idx.append(pos[n])
            self._maps.append(np.array(idx))
        if self.reference is not None:
            ref = np.asarray(self.reference, dtype=float)
            if len(ref) != self.ndim:
                raise ValueError(f"the reference has {len(ref)} parameters; the joint model samples {self.ndim}")
            self.parts = [p.with_reference(self.part_theta(ref, k)) for k, p in enumerate(self.parts)]

    @property
    def needs_reference(self) -> bool:
        """True where the records' likelihood waits for a reference point
        (``PosteriorModel.needs_reference``; :meth:`with_reference`)."""
        return any(p.needs_reference for p in self.parts)

    def with_reference(self, theta) -> JointModel:
        """This model with each record's normaliser noise taken at its part of ``theta``
        (``PosteriorModel.with_reference``); the model itself where no record's likelihood
        has such a normaliser."""
        if not any(p.needs_reference or p.reference is not None for p in self.parts):
            return self
        return dataclasses.replace(self, records=self.records,
                                   reference=tuple(float(v) for v in np.asarray(theta, dtype=float)))

    @property
    def ndim(self) -> int:
        return len(self.names)

    def bounds(self) -> np.ndarray:
        return np.array([self.all_priors[n].bounds for n in self.names])

    def to_values(self, theta):
        theta = np.asarray(theta, dtype=float)
        return np.where(self._log, np.exp(np.where(self._log, theta, 0.0)), theta)

    def part_theta(self, theta, k: int) -> np.ndarray:
        """Record ``k``'s single-record theta (its sigma set to 1: marginalised here)."""
        idx = self._maps[k]
        return np.where(idx >= 0, np.asarray(theta, dtype=float)[idx], 0.0)

    def derived(self, values: dict) -> dict:
        """``b_app_<setting>`` from sampled values by name (works on arrays)."""
        return {f"b_app_{s}": apparent_inertance(values[f"b_{s}"], values["k_n"], values["c_n"])
                for s in self.settings}

    def log_prior(self, theta) -> float:
        return float(sum(self.all_priors[n].logpdf(t) for n, t in zip(self.names, theta)))

    def log_prob(self, theta):
        """(log posterior, mean phi over the records) at theta."""
        theta = np.asarray(theta, dtype=float)
        lp = self.log_prior(theta)
        if not math.isfinite(lp):
            return -math.inf, math.nan
        return self.combine(lp, self.terms(theta, range(len(self.parts))))

    def terms(self, theta, ks) -> list:
        """Each record ``k`` in ``ks``: (its marginal log-likelihood, its phi) at theta, or
        None where its simulation fails (then the rest are not computed). Records are
        independent given theta, so they can be computed anywhere (:func:`pooled_log_prob`)
        and added by :meth:`combine`."""
        theta = np.asarray(theta, dtype=float)
        out = []
        for k in ks:
            # the part's prior is the joint's: no need to ask it
            got = self.parts[k].log_likelihood(self.part_theta(theta, k), marginal_scale=True)
            if got is None:
                return out + [None]
            out.append(got)
        return out

    @staticmethod
    def combine(log_prior: float, terms: list):
        """(log posterior, mean phi) from the log prior and every record's :meth:`terms`,
        added in the records' order (the same sum wherever the terms were computed)."""
        if any(t is None for t in terms):
            return -math.inf, math.nan
        lp = log_prior
        for ll, _ in terms:
            lp += ll
        if not math.isfinite(lp):
            return -math.inf, math.nan
        return lp, float(np.mean([phi for _, phi in terms]))

    def start(self, medians: list[dict]) -> np.ndarray:
        """A starting theta from single-record posterior medians (one dict of sampled
        values per record, in the records' order): each shared parameter's median over
        the records (in the sampled scale), each b the median over its setting's
        records, each rho the median over its frequency's."""
        if len(medians) != len(self.records):
            raise ValueError(f"need one median per record ({len(self.records)}), got {len(medians)}")

        scale = self._median
        theta = []
        for n in self.names:
            if n.startswith("b_"):
                vals = [m["b"] for m, s in zip(medians, self.setting_of) if s == n[2:]]
            elif n in self.per_frequency:
                base = n.split("_")[0]
                vals = [m[base] for m, f in zip(medians, self.freq_of) if f"{base}_{f:g}Hz" == n]
            else:
                vals = [m[n] for m in medians]
            theta.append(scale(n, vals))
        lo, hi = self.bounds().T
        return np.clip(np.array(theta), lo, hi)

    def start_candidates(self, medians: list[dict]) -> list[np.ndarray]:
        """Starting thetas for the joint search: :meth:`start` of every record's centre,
        then one per group of records: the shared parameters the group's medians, the
        rest as in the first. Up to :data:`RECORD_STARTS` records each record is a group;
        beyond, the groups are those of the friction split, records whose centres put
        ``f_share`` more than :data:`SPLIT_GAP` apart (none where all lie closer). Each
        record's own optimum sits in the mode its data favour; the median of two modes
        lies between them and a local search from it reaches either (measured on the
        joint calibration's replicates whose chains settled in a mode 40 and 420 nats
        below the one that held the truth, the second with its records' f_share 0.097
        apart)."""
        first = self.start(medians)
        n = len(medians)
        if n <= RECORD_STARTS:
            groups = [[k] for k in range(n)]
        elif "f_share" in self.names:
            order = sorted(range(n), key=lambda k: medians[k]["f_share"])
            groups, group = [], [order[0]]
            for a, b in zip(order, order[1:]):
                if medians[b]["f_share"] - medians[a]["f_share"] > SPLIT_GAP:
                    groups.append(group)
                    group = []
                group.append(b)
            groups.append(group)
        else:
            groups = []
        if len(groups) <= 1:
            return [first]
        out = [first]
        shared = [i for i, name in enumerate(self.names) if name in self.shared]
        lo, hi = self.bounds().T
        for group in groups:
            theta = first.copy()
            for i in shared:
                name = self.names[i]
                theta[i] = np.clip(self._median(name, [medians[k][name] for k in group]), lo[i], hi[i])
            if not any(np.array_equal(theta, t) for t in out):
                out.append(theta)
        return out

    def _median(self, name: str, values) -> float:
        """The median of ``values`` of ``name`` in its sampled scale."""
        x = np.asarray(values, dtype=float)
        return float(np.median(np.log(x) if self.all_priors[name].log_scale else x))


#: Where the records' own optima put the friction's split (``f_share``) in groups further
#: apart than this, the joint search starts from each group too
#: (:meth:`JointModel.start_candidates`), where there are more than RECORD_STARTS records.
SPLIT_GAP = 0.1
#: Up to this many records the joint search starts from each record's own optimum too
#: (:meth:`JointModel.start_candidates`): one Nelder-Mead pass each.
RECORD_STARTS = 4


def _terms(model: JointModel, args):
    theta, ks = args
    return model.terms(theta, ks)


@contextmanager
def pooled_log_prob(model: JointModel, processes: int):
    """``model.log_prob`` with its records' terms computed on ``processes`` forked worker
    processes, a share of the records each, for one point at a time (Nelder-Mead's start-up
    search, where the walkers' own parallelism has nothing to share). The same numbers as
    ``model.log_prob``, bit for bit: the terms are added in the records' order. With one
    process, ``model.log_prob`` itself."""
    if processes <= 1:
        yield model.log_prob
        return
    n = len(model.parts)
    # every processes-th record to each worker: neighbours in the records' order (one
    # setting's records, alike in cost) go to different workers
    chunks = [list(range(i, n, processes)) for i in range(min(processes, n))]
    with make_executor(len(chunks), state=model) as executor:

        def log_prob(theta):
            theta = np.asarray(theta, dtype=float)
            lp = model.log_prior(theta)
            if not math.isfinite(lp):
                return -math.inf, math.nan
            terms = [None] * n  # a record whose simulation failed, or after it, stays None
            for ks, got in zip(chunks, executor.map_state(_terms, [(theta, ks) for ks in chunks])):
                for k, t in zip(ks, got):
                    terms[k] = t
            return model.combine(lp, terms)  # -inf where any is None

        yield log_prob
