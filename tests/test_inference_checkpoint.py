"""Opening a checkpoint: its identity decides whether it is continued, a refusal is one
line that names what differs and the fix, and checkpoints of an earlier format (no
identity, or no twin file) are refused, never read or overwritten. (Damaged files,
kills and the continued chain: tests/test_inference_fit.py and test_inference_sampler.py.)"""

import json

import emcee
import h5py
import numpy as np
import pytest

from bayes_inerter.inference.sampling.checkpoint import (IDENTITY_ATTR, CheckpointError, new_checkpoint, open_checkpoint,
                                                read_chain, stored_identity, twin_path)
from bayes_inerter.inference.sampling.identity import CHECKPOINT_FORMAT

IDENTITY = {"format": CHECKPOINT_FORMAT, "model": {"name": "two-port", "parameters": ["b", "sigma"]},
            "priors": {"b": {"law": "LogUniform", "low": 100.0, "high": 1e5}},
            "adaptation": None, "nwalkers": 4, "ndim": 2}


def _with_steps(path, n=3, identity=IDENTITY, rows=False):
    """A new checkpoint at ``path`` holding ``n`` steps, both files up to date; with
    ``rows``, each step's per-step rows too (step k's hot walkers all k, its labels
    0..11 + k)."""
    backend = new_checkpoint(path, identity=identity, write_seconds=0.0)
    rng = np.random.default_rng(0)
    backend.grow(n, None)
    for k in range(n):
        state = emcee.State(rng.normal(size=(4, 2)), log_prob=rng.normal(size=4),
                            random_state=np.random.RandomState(k).get_state())
        step_rows = {"hot_chain": np.full((2, 4, 2), float(k)), "replicas": np.arange(12, dtype=np.int32) + k}
        backend.save_step(state, np.ones(4, dtype=bool), rows=step_rows if rows else None)
    backend.flush()
    return backend


def test_a_new_checkpoint_holds_its_identity_as_json(tmp_path):
    path = tmp_path / "chain.h5"
    _with_steps(path)
    for p in (path, twin_path(path)):
        with h5py.File(p, "r") as f:
            g = f["mcmc"]
            assert json.loads(g.attrs[IDENTITY_ATTR]) == IDENTITY
            assert g.attrs["parameter_names"] == "b,sigma"  # read by studies/long_chain.py
            assert (int(g.attrs["nwalkers"]), int(g.attrs["ndim"])) == (4, 2)
    opened = open_checkpoint(path, identity=json.loads(json.dumps(IDENTITY)))
    assert opened.steps == 3 and not opened.recovered
    assert read_chain(path).shape == (3, 4, 2)
    chain, log_prob = read_chain(path, log_prob=True)
    with h5py.File(path, "r") as f:
        np.testing.assert_array_equal(chain, f["mcmc"]["chain"][:3])
        np.testing.assert_array_equal(log_prob, f["mcmc"]["log_prob"][:3])


@pytest.mark.parametrize("change, said", [
    ({"priors": {"b": {"law": "LogUniform", "low": 10.0, "high": 1e5}}},
     "written with other priors (b: LogUniform(low=100.0, high=100000.0) then, LogUniform(low=10.0, "
     "high=100000.0) now); run with --fresh to start over, or use another --out"),
    ({"nwalkers": 6}, "written for 4 walkers (this run has 6); use the same --walkers, or --fresh"),
    ({"adaptation": {"every": 250}}, "written with another kernel (no adaptation then, adaptation(every=250) now)"),
])
def test_a_checkpoint_of_another_run_is_refused_and_left_as_it_is(tmp_path, change, said):
    path = tmp_path / "chain.h5"
    _with_steps(path)
    kept = path.read_bytes(), twin_path(path).read_bytes()
    with pytest.raises(CheckpointError) as err:
        open_checkpoint(path, identity={**IDENTITY, **change})
    assert str(err.value).startswith(f"{path}: the checkpoint was ") and said in str(err.value)
    assert "\n" not in str(err.value)
    assert (path.read_bytes(), twin_path(path).read_bytes()) == kept
    assert open_checkpoint(path, identity={**IDENTITY, **change}, fresh=True) is None  # --fresh: gone
    assert not path.exists() and not twin_path(path).exists()


def _older_with_twin(path):
    """A checkpoint as this package wrote it before the identity was data: sealed twin
    files, a digest of text and the kernel's description, no identity."""
    _with_steps(path)
    for p in (path, twin_path(path)):
        with h5py.File(p, "a") as f:
            g = f["mcmc"]
            del g.attrs[IDENTITY_ATTR]
            g.attrs["bayes_inerter_digest"] = "0123456789abcdef"
            g.attrs["bayes_inerter_kernel"] = "ensemble moves alone (no adaptation)"


def _older_without_twin(path):
    """A checkpoint as written before the twin file: emcee's one file, a sha256 of its
    chain and log probabilities beside it, no seal, no identity."""
    backend = emcee.backends.HDFBackend(str(path))
    backend.reset(4, 2)
    backend.grow(2, None)
    rng = np.random.default_rng(1)
    for k in range(2):
        backend.save_step(emcee.State(rng.normal(size=(4, 2)), log_prob=rng.normal(size=4),
                                      random_state=np.random.RandomState(k).get_state()), np.ones(4, dtype=bool))
    with h5py.File(path, "a") as f:
        g = f["mcmc"]
        g.attrs["bayes_inerter_digest"] = "0123456789abcdef"
        g.attrs["bayes_inerter_chain_sha256"] = "00" * 32
        g.attrs["bayes_inerter_summed_steps"] = 2


@pytest.mark.parametrize("older", [_older_with_twin, _older_without_twin])
def test_a_checkpoint_of_an_earlier_format_is_refused_until_fresh(tmp_path, older):
    path = tmp_path / "chain.h5"
    older(path)
    files = [p for p in (path, twin_path(path)) if p.exists()]
    kept = [p.read_bytes() for p in files]
    with pytest.raises(CheckpointError) as err:
        open_checkpoint(path, identity=IDENTITY)
    text = str(err.value)
    assert "\n" not in text and "written by an older version of bayes-inerter" in text
    assert "run with --fresh to start over (or remove the folder)" in text
    assert [p.read_bytes() for p in files] == kept  # neither read into a run nor overwritten
    with pytest.raises(CheckpointError, match="older version"):
        read_chain(path)
    assert open_checkpoint(path, identity=IDENTITY, fresh=True) is None
    new_checkpoint(path, identity=IDENTITY)
    assert open_checkpoint(path, identity=IDENTITY).steps == 0


def test_a_checkpoint_of_a_newer_format_is_refused(tmp_path):
    path = tmp_path / "chain.h5"
    _with_steps(path, identity={**IDENTITY, "format": CHECKPOINT_FORMAT + 1})
    with pytest.raises(CheckpointError, match="written by a newer version of bayes-inerter"):
        open_checkpoint(path, identity=IDENTITY)


def test_an_empty_checkpoints_identity_pins_nothing(tmp_path):
    """A chain whose start failed leaves a checkpoint with an identity and no step: the
    next run must choose its own coordinates, so no identity is reported for it."""
    empty = tmp_path / "empty.h5"
    new_checkpoint(empty, identity=IDENTITY, write_seconds=0.0).flush()
    assert stored_identity(empty) is None
    _with_steps(tmp_path / "held.h5")
    assert stored_identity(tmp_path / "held.h5") == IDENTITY


def test_per_step_rows_are_kept_sealed_and_read_back(tmp_path):
    from bayes_inerter.inference.sampling.twin_backend import GROUP

    path = tmp_path / "chain.h5"
    backend = _with_steps(path, rows=True)
    assert backend.has_rows("hot_chain")
    assert np.array_equal(backend.get_rows("hot_chain")[:, 0, 0, 0], [0.0, 1.0, 2.0])
    assert np.array_equal(backend.get_rows("replicas", 1)[:, 0], [1, 2])
    assert open_checkpoint(path, identity=IDENTITY).steps == 3
    with h5py.File(path, "a") as f:  # a row spoilt: the seal no longer vouches for the file
        f[GROUP]["hot_chain"][1] = -1.0
    opened = open_checkpoint(path, identity=IDENTITY)
    assert opened.steps == 3 and "chain.h5" in opened.recovered  # continued from the intact twin
    assert np.array_equal(opened.backend.get_rows("hot_chain")[:, 0, 0, 0], [0.0, 1.0, 2.0])


def test_a_chain_that_kept_no_rows_from_its_first_step_never_does(tmp_path):
    backend = _with_steps(tmp_path / "chain.h5")
    assert not backend.has_rows("hot_chain")
    state = emcee.State(np.zeros((4, 2)), log_prob=np.zeros(4), random_state=np.random.RandomState(9).get_state())
    backend.grow(1, None)
    backend.save_step(state, np.ones(4, dtype=bool),
                      rows={"hot_chain": np.zeros((2, 4, 2)), "replicas": np.arange(12, dtype=np.int32)})
    backend.flush()
    assert not backend.has_rows("hot_chain") and backend.iteration == 4
    assert open_checkpoint(tmp_path / "chain.h5", identity=IDENTITY).steps == 4  # and the file stays sealed
    for partial in ({"other": np.zeros(2)}, {"hot_chain": np.zeros((2, 4, 2))}):
        with pytest.raises(ValueError, match="per-step rows must be all of"):
            backend.save_step(state, np.ones(4, dtype=bool), rows=partial)
