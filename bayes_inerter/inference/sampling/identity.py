"""What a checkpoint belongs to, as data: the run's identity and how two of them differ.

A checkpoint is continued only by a run of the same chain: the same records, model,
priors, sampler coordinates, kernel (adaptation and ensemble moves) and walkers. The
checkpoint stores :func:`run_identity` as one JSON document and a run compares it with
its own field by field (:func:`mismatch`): no text written for people (``describe()``)
takes part, so rewording one changes no identity, and a refusal names the field that
differs. :data:`CHECKPOINT_FORMAT` counts the versions of the document and of the files
around it; checkpoints of an earlier format are refused (their run must start over).
"""

from __future__ import annotations

import dataclasses
import hashlib
from dataclasses import dataclass

import numpy as np

__all__ = ["CHECKPOINT_FORMAT", "Mismatch", "run_identity", "mismatch"]

#: The checkpoint format: 2 since the identity is data (1: everything before, a digest
#: of text and the kernel's description; the pre-twin files too).
CHECKPOINT_FORMAT = 2

#: The fix for most mismatches.
_FRESH = "run with --fresh to start over, or use another --out"


def run_identity(model, coordinates, adaptation, moves, nwalkers: int, tempering=None) -> dict:
    """The identity of a run (see module docstring) as plain JSON data: the sha256 of each
    record's arrays, the model's name, parameters, masses, likelihood settings and priors,
    the sampler coordinates (``None``: theta itself), ``adaptation``'s settings (None:
    none), the ensemble ``moves`` ((move, weight) pairs) by name and weight, and the
    walkers, and the tempering ladder where there is one (``tempering.Tempering``; the
    field is left out without one, so checkpoints written before it existed match).
    ``model``: a ``PosteriorModel`` or a ``JointModel`` (``model.parts``)."""
    parts = getattr(model, "parts", None) or [model]
    identity = {
        "format": CHECKPOINT_FORMAT,
        "records": [{k: _sha256(getattr(p.record, k)) for k in ("time", "force", "accel")} for p in parts],
        "model": {"name": "joint" if getattr(model, "parts", None) else model.model, "parameters": list(model.names)},
        "masses": [{"m_s": float(p.m_s), "m_B": float(p.m_B)} for p in parts],
        "likelihood": _plain(dataclasses.asdict(model.likelihood)),
        "priors": {name: _prior(p) for name, p in model.all_priors.items()},
        "coordinates": None if coordinates is None else _coordinates(coordinates),
        "adaptation": None if adaptation is None else _adaptation(adaptation),
        "moves": [[type(m).__name__, float(w)] for m, w in moves],
        "nwalkers": int(nwalkers),
        "ndim": int(model.ndim),
        "reference": _plain(getattr(model, "reference", None)),
        "deviations": [_deviations(p) for p in parts],
    }
    if tempering is not None:
        identity["tempering"] = _plain(_without_later(dataclasses.asdict(tempering), LATER_TEMPERING))
    return identity


def _deviations(part):
    """The sha256 of the motion-in likelihood's marginalised deviations' basis (its windows,
    polynomials and law; ``motion.MotionData.basis``), None for the other likelihoods."""
    motion = getattr(part, "motion", None)
    return None if motion is None else _sha256(motion.basis)


def _sha256(values) -> str:
    return hashlib.sha256(np.ascontiguousarray(values, dtype=float).tobytes()).hexdigest()


def _plain(value):
    """``value`` as JSON data: numpy scalars and arrays, tuples as Python numbers and lists."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple, np.ndarray)):
        return [_plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    return value


def _prior(prior) -> dict:
    """A prior as its law's name and its settings (a dataclass's fields)."""
    settings = dataclasses.asdict(prior) if dataclasses.is_dataclass(prior) else {"repr": repr(prior)}
    return {"law": type(prior).__name__, **_plain(settings)}


#: Settings added after checkpoints were first written, with the value in effect before
#: each existed: an identity leaves a setting out while it holds that value, so a
#: checkpoint written before the setting existed still matches.
LATER_ADAPTATION = {"transport": False, "block_partners": "random"}
LATER_COORDINATES = {"series": None, "compliance": None}
LATER_TEMPERING = {"adapt_hot": False}
#: Likelihood settings added after checkpoints were written, with the value in effect
#: before: a stored identity without one is read as holding that value (the run's own
#: identity keeps every setting, so checkpoints written since stay as they are).
LATER_LIKELIHOOD = {"reversals": True, "form_sd": 0.0, "form_friction": 0.0}


def stored_likelihood(settings):
    """Likelihood settings as a checkpoint or a fit's record stored them, with those of
    :data:`LATER_LIKELIHOOD` they lack at the value in effect before (anything but a
    dict, as it is)."""
    return {**LATER_LIKELIHOOD, **settings} if isinstance(settings, dict) else settings


def _with_later(fields: dict, later: dict) -> dict:
    """``fields`` with those of ``later`` it leaves out at the value ``later`` gives them
    (the inverse of :func:`_without_later`), less what is no part of the kernel
    (:func:`_kernel_fields`)."""
    return _kernel_fields({**later, **fields})


def _kernel_fields(fields: dict) -> dict:
    """An adaptation's settings less how block moves would pick their coordinates where
    it has no block moves: that is no part of its kernel."""
    return {k: v for k, v in fields.items() if not (k == "block_partners" and not fields.get("blocks"))}


def _without_later(fields: dict, later: dict) -> dict:
    """``fields`` less those of ``later`` that hold the value ``later`` gives them."""
    return {k: v for k, v in fields.items() if not (k in later and v == later[k])}


def _adaptation(adaptation) -> dict:
    """The adaptation's settings (its dataclass's fields; see :data:`LATER_ADAPTATION`
    and :func:`_kernel_fields`)."""
    return _plain(_without_later(_kernel_fields(dataclasses.asdict(adaptation)), LATER_ADAPTATION))


def _coordinates(coords) -> dict:
    """The sampler coordinates as their kind and settings (their dataclass's fields; see
    :data:`LATER_COORDINATES`)."""
    fields = {f.name: getattr(coords, f.name) for f in dataclasses.fields(coords)}
    fields = _without_later(fields, LATER_COORDINATES)
    imp = fields.get("impedance")
    if imp is not None:
        fields["impedance"] = dataclasses.asdict(imp)
    return _plain(fields)


@dataclass(frozen=True)
class Mismatch:
    """How a checkpoint's identity differs from a run's: the first field that does, the
    clause that says so ("for another record (record 2's arrays differ)") and the fix."""

    field: str
    what: str
    fix: str = _FRESH


#: The order of comparison, and how each field's difference is named.
_NAMES = {
    "records": "for another record",
    "model": "for another model",
    "masses": "with other masses",
    "likelihood": "with other likelihood settings",
    "priors": "with other priors",
    "coordinates": "in other sampler coordinates",
    "adaptation": "with another kernel",
    "moves": "with other ensemble moves",
    "nwalkers": "for another number of walkers",
    "ndim": "for another number of parameters",
    "reference": "with its likelihood's normaliser at another reference point",
    "deviations": "with another basis of its likelihood's marginalised deviations",
    "tempering": "with another tempering ladder",
}


def mismatch(stored: dict, current: dict) -> Mismatch | None:
    """The first difference between a checkpoint's identity ``stored`` (read back from
    JSON; ``{}`` for a checkpoint without one) and a run's ``current``, or None when they
    are the same chain's. Numbers compare as numbers (1 == 1.0)."""
    if stored.get("format", 1) != current["format"]:
        age = "an older" if stored.get("format", 1) < current["format"] else "a newer"
        return Mismatch("format", f"by {age} version of bayes-inerter (checkpoint format "
                        f"{stored.get('format', 1)}; this one reads {current['format']})",
                        "run with --fresh to start over (or remove the folder)")
    if "likelihood" in stored:
        stored = {**stored, "likelihood": stored_likelihood(stored["likelihood"])}
    if isinstance(stored.get("adaptation"), dict) and isinstance(current.get("adaptation"), dict):
        # a setting left out as its earlier value is named by that value, then and now
        stored = {**stored, "adaptation": _with_later(stored["adaptation"], LATER_ADAPTATION)}
        current = {**current, "adaptation": _with_later(current["adaptation"], LATER_ADAPTATION)}
    keys = list(_NAMES) + [k for k in current if k not in _NAMES and k != "format"]
    for key in keys:
        found = _first_difference(stored.get(key), current.get(key), ())
        if found is not None:
            path = found[0][: _DEPTH.get(key, len(found[0]))]
            return _say(key, path, _at(stored.get(key), path), _at(current.get(key), path),
                        len(current.get("records", ())) == 1)
    return None


#: How deep a difference is named: a prior, the model's name or parameter list, the
#: moves as a whole are shown entire, not the one number in them that differs.
_DEPTH = {"records": 1, "priors": 1, "model": 1, "moves": 0, "adaptation": 1, "likelihood": 1}


def _at(value, path: tuple):
    """The part of ``value`` at ``path`` (None where it has none)."""
    for p in path:
        if isinstance(value, dict):
            value = value.get(p)
        elif isinstance(value, list) and isinstance(p, int) and p < len(value):
            value = value[p]
        else:
            return None
    return value


def _first_difference(a, b, path: tuple):
    """(path, a's value, b's value) at the first place where ``a`` and ``b`` differ, or None."""
    if isinstance(a, dict) and isinstance(b, dict):
        for k in list(b) + [k for k in a if k not in b]:
            found = _first_difference(a.get(k), b.get(k), path + (k,))
            if found is not None:
                return found
        return None
    if isinstance(a, list) and isinstance(b, list) and len(a) == len(b):
        for i, (x, y) in enumerate(zip(a, b)):
            found = _first_difference(x, y, path + (i,))
            if found is not None:
                return found
        return None
    return None if a == b else (path, a, b)


def _say(key: str, path: tuple, then, now, single: bool) -> Mismatch:
    """The :class:`Mismatch` of field ``key`` at ``path`` (``then``: the checkpoint's value;
    ``single``: the run has one record)."""
    name = _NAMES.get(key, f"with another {key}")
    if key == "nwalkers":
        return Mismatch(key, f"for {then} walkers (this run has {now})",
                        "use the same --walkers, or --fresh to start over, or another --out")
    if key == "tempering" and not path:  # with and without tempering
        then, now = ("no tempering" if v is None else f"{v['temps']} temperatures to beta {v['beta_min']:g}"
                     for v in (then, now))
        return Mismatch(key, f"{name} ({then} then, {now} now)",
                        "run with the same --tempering setting, or --fresh to start over, or another --out")
    if key == "adaptation":
        if not path:  # with and without adaptation
            then, now = ("no adaptation" if v is None else "adaptation" + _show(v) for v in (then, now))
        else:
            then, now = _show(then), _show(now)
        return Mismatch(key, f"{name} ({_where(('adaptation',) + path if path else ())}{then} then, {now} now)",
                        "continuing would change the kernel mid-chain: run with the same adaptation setting "
                        "(--no-adaptation or not, --block-partners), or --fresh to start over, or another --out")
    record = "the record" if single else f"record {path[0] + 1}" if path and isinstance(path[0], int) else ""
    if key == "records" and len(path) == 1 and isinstance(then, dict) and isinstance(now, dict):
        arrays = ", ".join(k for k in now if then.get(k) != now[k])
        return Mismatch(key, f"{name} ({record}'s arrays differ: {arrays})")
    if key == "masses" and len(path) == 2:
        return Mismatch(key, f"{name} ({record}'s {path[1]}: {_show(then)} then, {_show(now)} now)")
    if key == "records" and isinstance(then, list) and isinstance(now, list) and len(then) != len(now):
        return Mismatch(key, f"{name} ({len(then)} records then, {len(now)} now)")
    if key == "moves":
        return Mismatch(key, f"{name} ({_show_moves(then)} then, {_show_moves(now)} now)")
    return Mismatch(key, f"{name} ({_where(path)}{_show(then)} then, {_show(now)} now)")


def _where(path: tuple) -> str:
    """``path`` as "b_A3 low: " (list positions as [i]), "" for the field itself."""
    if not path:
        return ""
    text = "".join(f"[{p}]" if isinstance(p, int) else f" {p}" for p in path).strip()
    return text + ": "


def _show(value) -> str:
    """A value on one line: a prior as "LogUniform(low=100.0, high=100000.0)"."""
    if value is None:
        return "none"
    if isinstance(value, dict):
        inner = ", ".join(f"{k}={_show(v)}" for k, v in value.items() if k != "law")
        return f"{value.get('law', '')}({inner})"
    if isinstance(value, list):
        return "[" + ", ".join(_show(v) for v in value) + "]"
    return repr(value) if isinstance(value, (float, str)) else str(value)


def _show_moves(moves) -> str:
    return ", ".join(f"{m[0]} {m[1]!r}" for m in moves or []) or "none"
