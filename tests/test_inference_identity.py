"""A run's identity is data: the same run gives the same identity whatever its
descriptions say, and a difference is named by its field."""

import dataclasses
import json

import emcee
import pytest

from bayes_inerter import paper_parameters
from bayes_inerter.inference import LikelihoodSettings, LogUniform, PosteriorModel
from bayes_inerter.inference.sampling.coordinates import Coordinates, default_coordinates
from bayes_inerter.inference.sampling.identity import CHECKPOINT_FORMAT, mismatch, run_identity
from bayes_inerter.inference.posterior.joint import JointModel
from bayes_inerter.inference.posterior.priors import LogNormal, Uniform
from bayes_inerter.inference.sampling.sampler import Adaptation, default_moves
from bayes_inerter.records import GeneratorSettings, generate_record

#: 5.5 s: three steady drive periods after the first at 1 Hz, as the default likelihood
#: (motion in, force out) needs.
SHORT = GeneratorSettings(duration=5.5, ramp=0.5)


@pytest.fixture(scope="module")
def records():
    return [generate_record(paper_parameters(s), f, settings=SHORT, rng=seed, setting_name=s)
            for s, f, seed in [("A2", 1.0, 2), ("A0", 1.0, 3), ("A2", 1.5, 4)]]


def _identity(model, kind="impedance", adaptation=Adaptation(), moves=None, nwalkers=24):
    coords = default_coordinates(model, kind)
    return run_identity(model, coords, adaptation, moves or default_moves(model, coordinates=coords), nwalkers)


def _stored(identity):
    """The identity as a checkpoint gives it back (through JSON)."""
    return json.loads(json.dumps(identity, allow_nan=False))


def test_identity_is_plain_data_and_survives_json(records):
    model = PosteriorModel(records[0])
    ident = _identity(model)
    assert ident["format"] == CHECKPOINT_FORMAT
    assert set(ident["records"][0]) == {"time", "force", "accel"}
    assert all(len(h) == 64 for h in ident["records"][0].values())  # sha256, hex
    assert ident["model"] == {"name": "two-port", "parameters": list(model.names)}
    assert ident["masses"] == [{"m_s": model.m_s, "m_B": model.m_B}]
    assert ident["likelihood"] == dataclasses.asdict(LikelihoodSettings())
    assert ident["priors"]["b"] == {"law": "LogUniform", "low": 100.0, "high": 1e5}
    assert isinstance(ident["priors"]["b"]["low"], float)  # floats as floats, not text
    assert ident["priors"]["f_share"] == {"law": "Uniform", "low": 0.0, "high": 1.0}
    assert ident["coordinates"]["kind"] == "impedance" and ident["coordinates"]["impedance"]["b_index"] == [0]
    # the transport map's switch and the block moves' partners appear only away from the
    # values of the checkpoints written before them: those match
    assert ident["adaptation"] == {k: v for k, v in dataclasses.asdict(Adaptation()).items()
                                   if k not in ("transport", "block_partners")}
    assert ident["moves"] == [["DEMove", 0.6], ["DESnookerMove", 0.1], ["StretchMove", 0.3]]
    assert (ident["nwalkers"], ident["ndim"]) == (24, model.ndim)
    assert _stored(ident) == ident
    assert mismatch(_stored(ident), ident) is None
    assert _identity(PosteriorModel(records[0])) == ident  # the same run, built again
    assert run_identity(model, None, None, [], 24)["coordinates"] is None


def test_rewording_a_description_changes_no_identity(records, monkeypatch):
    model = PosteriorModel(records[0], priors={"k_n": LogNormal(1e7, 1.0)})
    before = _identity(model)
    for cls in (LogUniform, Uniform, LogNormal, Coordinates, Adaptation):
        monkeypatch.setattr(cls, "describe", lambda self: "reworded entirely", raising=True)
    assert Adaptation().describe() == "reworded entirely"
    after = _identity(model)
    assert after == before
    assert mismatch(_stored(before), after) is None


def test_numbers_compare_as_numbers():
    stored = _stored({"format": CHECKPOINT_FORMAT, "adaptation": {"dof": 10.0}, "nwalkers": 24})
    assert mismatch(stored, {"format": CHECKPOINT_FORMAT, "adaptation": {"dof": 10}, "nwalkers": 24}) is None


def test_a_checkpoint_written_before_a_likelihood_setting_existed_holds_its_earlier_value(records):
    """``LikelihoodSettings.reversals`` came after checkpoints were written: a stored
    identity without it matches a run that keeps the reversals' deviations (the value in
    effect before) and is refused by one that leaves them out."""
    ident = _identity(PosteriorModel(records[0]))
    older = _stored(ident)
    del older["likelihood"]["reversals"]
    assert mismatch(older, ident) is None
    without = _identity(PosteriorModel(records[0], likelihood=LikelihoodSettings(reversals=False)))
    found = mismatch(older, without)
    assert found is not None and found.what == "with other likelihood settings (reversals: True then, False now)"


def test_a_difference_is_named_by_its_field(records):
    model = PosteriorModel(records[0])
    stored = _stored(_identity(model))

    def said(**change):
        found = mismatch(stored, _identity(**{"model": model, **change}))
        assert found is not None
        return found

    other = said(model=PosteriorModel(records[1]))
    assert other.field == "records" and other.what == "for another record (the record's arrays differ: force, accel)"
    assert "--fresh" in other.fix and "another --out" in other.fix
    priors = said(model=PosteriorModel(records[0], priors={"b": LogUniform(10.0, 1e5)}))
    assert priors.what == ("with other priors (b: LogUniform(low=100.0, high=100000.0) then, "
                           "LogUniform(low=10.0, high=100000.0) now)")
    masses = said(model=PosteriorModel(records[0], m_s=3.0))
    assert masses.field == "masses" and f"m_s: {model.m_s!r} then, 3.0 now" in masses.what
    lk = said(model=PosteriorModel(records[0], likelihood=LikelihoodSettings(cutoff=20.0)))
    assert lk.what == "with other likelihood settings (cutoff: 30.0 then, 20.0 now)"
    rigid = said(model=PosteriorModel(records[0], "rigid"))
    assert rigid.field == "model" and "'two-port' then, 'rigid' now" in rigid.what
    coords = said(kind="unconstrained")
    assert coords.what.startswith("in other sampler coordinates (kind: 'impedance' then, 'unconstrained' now")
    none = said(adaptation=None)
    assert none.field == "adaptation" and none.what.endswith("then, no adaptation now)")
    assert "kernel mid-chain" in none.fix and "--fresh" in none.fix
    assert said(adaptation=Adaptation(every=30)).what == "with another kernel (adaptation every: 250 then, 30 now)"
    moves = said(moves=[(emcee.moves.StretchMove(), 1.0)])
    assert moves.what == ("with other ensemble moves (DEMove 0.6, DESnookerMove 0.1, StretchMove 0.3 then, "
                          "StretchMove 1.0 now)")
    walkers = said(nwalkers=26)
    assert walkers.what == "for 24 walkers (this run has 26)"
    assert walkers.fix.startswith("use the same --walkers, or --fresh")


def test_another_basis_of_the_deviations_is_refused(records, monkeypatch):
    """A checkpoint written with other reversal polynomials (or any other basis of the
    marginalised deviations) samples another posterior: it is not continued."""
    from bayes_inerter.inference.posterior import reversals

    stored = _stored(_identity(PosteriorModel(records[0])))
    assert mismatch(stored, _identity(PosteriorModel(records[0]))) is None
    monkeypatch.setattr(reversals, "DEGREES", reversals.DEGREES + 2)
    found = mismatch(stored, _identity(PosteriorModel(records[0])))
    assert found is not None and found.field == "deviations"
    assert found.what.startswith("with another basis of its likelihood's marginalised deviations")


def test_a_joint_models_records_are_named_by_their_place(records):
    joint = JointModel(records)
    stored = _stored(_identity(joint))
    swapped = mismatch(stored, _identity(JointModel([records[0], records[1], records[0]])))
    assert swapped.what == "for another record (record 3's arrays differ: force, accel)"
    fewer = mismatch(stored, _identity(JointModel(records[:2])))
    assert fewer.what == "for another record (3 records then, 2 now)"


def test_a_checkpoint_of_another_format_is_refused_as_older_or_newer():
    current = {"format": CHECKPOINT_FORMAT, "nwalkers": 24}
    old = mismatch({}, current)  # no identity at all: written before it was data
    assert old.field == "format" and old.what.startswith("by an older version of bayes-inerter")
    assert old.fix == "run with --fresh to start over (or remove the folder)"
    newer = mismatch({"format": CHECKPOINT_FORMAT + 1, "nwalkers": 24}, current)
    assert newer.what.startswith("by a newer version of bayes-inerter")
