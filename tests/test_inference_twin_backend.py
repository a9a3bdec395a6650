"""The emcee internals the twin-file back end relies on, pinned one by one: an emcee
upgrade that changes one of them fails here with a message naming it. (The back end's
own behaviour, kills and damaged files: tests/test_inference_fit.py.)

What ``inference/sampling/twin_backend.py`` takes from emcee's ``backends.HDFBackend``: ``open``
(copied, without HDF5's lock), the attributes it reads (``filename``, ``name``,
``read_only``, ``dtype``, ``dtype_set``), ``reset``'s layout (group attributes
``nwalkers``, ``ndim``, ``has_blobs``, ``iteration``; datasets ``accepted``, ``chain``,
``log_prob``), ``grow`` (from the file's step count; makes ``blobs``), the properties
``iteration``, ``shape``, ``accepted``, ``random_state`` (attributes
``random_state_0``...) and ``has_blobs()``, the private ``_check(state, accepted)``, and
``get_value``, through which emcee's getters read; from ``EnsembleSampler``: ``grow``
once, then ``save_step`` for each step.
"""

import inspect

import emcee
import h5py
import numpy as np
import pytest

from bayes_inerter.inference.sampling.twin_backend import GROUP, SEAL, _Backend, write_empty

HDF = emcee.backends.HDFBackend


def _changed(what: str) -> str:
    return (f"emcee {emcee.__version__}: {what} changed; bayes_inerter/inference/sampling/twin_backend.py relies on it: "
            "review the back end there, then this pin")


#: ``HDFBackend.open`` of emcee 3.1.6, which ``_Backend.open`` copies (whitespace aside).
OPEN_SOURCE = '''
    def open(self, mode="r"):
        if self.read_only and mode != "r":
            raise RuntimeError(
                "The backend has been loaded in read-only "
                "mode. Set `read_only = False` to make "
                "changes."
            )
        f = h5py.File(self.filename, mode)
        if not self.dtype_set and self.name in f:
            g = f[self.name]
            if "chain" in g:
                self.dtype = g["chain"].dtype
                self.dtype_set = True
        return f
'''


def _squeeze(text: str) -> str:
    return "".join(text.split())


def test_hdf_open_is_the_logic_the_unlocked_open_copies(tmp_path):
    assert _squeeze(inspect.getsource(HDF.open)) == _squeeze(OPEN_SOURCE), _changed(
        "HDFBackend.open (_Backend.open copies it, opening without HDF5's lock)")
    params = inspect.signature(HDF.__init__).parameters
    assert list(params)[:4] == ["self", "filename", "name", "read_only"] and "dtype" in params, _changed(
        "HDFBackend.__init__(filename, name=, read_only=, dtype=)")
    path = tmp_path / "f32.h5"
    HDF(str(path), name=GROUP, dtype=np.float32).reset(4, 2)
    for cls in (HDF, _Backend):  # the same behaviour, emcee's and the copy
        b = cls(str(path), name=GROUP)
        assert (b.filename, b.name, b.read_only, b.dtype_set) == (str(path), GROUP, False, False), _changed(
            f"the attributes HDFBackend.__init__ sets ({cls.__name__})")
        with b.open() as f:
            assert GROUP in f
        assert b.dtype_set and b.dtype == np.float32, _changed(f"{cls.__name__}.open's reading of the chain's dtype")
        with pytest.raises(RuntimeError):
            cls(str(path), name=GROUP, read_only=True).open("a")


def test_reset_lays_out_the_group_that_the_seal_covers(tmp_path):
    path = tmp_path / "c.h5"
    write_empty(path, 4, 3, {"mine": "here"})
    with h5py.File(path, "r") as f:
        g = f[GROUP]
        attrs = {k: g.attrs[k] for k in ("nwalkers", "ndim", "has_blobs", "iteration")}
        assert attrs == {"nwalkers": 4, "ndim": 3, "has_blobs": False, "iteration": 0}, _changed(
            "HDFBackend.reset's group attributes")
        assert g.attrs["mine"] == "here" and SEAL in g.attrs
        assert g["accepted"].shape == (4,), _changed("HDFBackend.reset's 'accepted' dataset")
        assert (g["chain"].shape, g["chain"].maxshape) == ((0, 4, 3), (None, 4, 3)), _changed(
            "HDFBackend.reset's 'chain' dataset")
        assert (g["log_prob"].shape, g["log_prob"].maxshape) == ((0, 4), (None, 4)), _changed(
            "HDFBackend.reset's 'log_prob' dataset")
        assert "blobs" not in g


def test_grow_counts_from_the_files_steps_and_makes_the_blobs(tmp_path):
    path = tmp_path / "c.h5"
    write_empty(path, 4, 2, {})
    b = _Backend(str(path), name=GROUP)
    b.grow(3, np.zeros(4))
    with h5py.File(path, "a") as f:
        g = f[GROUP]
        assert g["chain"].shape[0] == g["log_prob"].shape[0] == 3, _changed("HDFBackend.grow's resizing")
        assert (g["blobs"].shape, g["blobs"].maxshape) == ((3, 4), (None, 4)), _changed(
            "HDFBackend.grow's 'blobs' dataset")
        assert bool(g.attrs["has_blobs"]), _changed("HDFBackend.grow's has_blobs attribute")
        g.attrs["iteration"] = 2  # as TwinBackend leaves it after writing two steps
    b.grow(3, np.zeros(4))
    with h5py.File(path, "r") as f:
        assert f[GROUP]["chain"].shape[0] == 5, _changed("HDFBackend.grow sizing from the file's 'iteration'")


def test_the_files_facts_are_properties_over_its_attributes(tmp_path):
    for name in ("iteration", "shape", "accepted", "random_state"):
        assert isinstance(inspect.getattr_static(HDF, name), property), _changed(
            f"HDFBackend.{name} (TwinBackend reads it through the property's fget)")
    assert callable(inspect.getattr_static(HDF, "has_blobs")), _changed("HDFBackend.has_blobs()")
    path = tmp_path / "c.h5"
    write_empty(path, 4, 2, {})
    state = np.random.RandomState(7).get_state()
    with h5py.File(path, "a") as f:
        g = f[GROUP]
        g.attrs["iteration"] = 2
        g["accepted"][:] = [1, 2, 0, 2]
        for i, v in enumerate(state):  # as TwinBackend writes them
            g.attrs[f"random_state_{i}"] = v
    b = _Backend(str(path), name=GROUP)
    assert int(b.iteration) == 2, _changed("HDFBackend.iteration (the 'iteration' attribute)")
    assert tuple(int(v) for v in b.shape) == (4, 2), _changed("HDFBackend.shape (the 'nwalkers', 'ndim' attributes)")
    assert b.accepted.tolist() == [1, 2, 0, 2], _changed("HDFBackend.accepted (the 'accepted' dataset)")
    assert not b.has_blobs(), _changed("HDFBackend.has_blobs (the 'has_blobs' attribute)")
    rs = b.random_state
    assert rs[0] == state[0] and np.array_equal(rs[1], state[1]) and list(rs[2:]) == list(state[2:]), _changed(
        "HDFBackend.random_state (the attributes random_state_0 to random_state_4, in order)")


class _Facts(HDF):
    """A back end that answers from memory, as TwinBackend does, over a file that does
    not exist: whatever opens the file fails."""

    shape = (4, 2)
    iteration = 0

    def has_blobs(self):
        return False


def test_check_asks_only_shape_has_blobs_and_iteration(tmp_path):
    assert list(inspect.signature(emcee.backends.Backend._check).parameters) == ["self", "state", "accepted"], \
        _changed("Backend._check(state, accepted)")
    b = _Facts(str(tmp_path / "none.h5"), name=GROUP)
    good = emcee.State(np.zeros((4, 2)), log_prob=np.zeros(4))
    b._check(good, np.ones(4, dtype=bool))  # no file opened
    for state, accepted in [(emcee.State(np.zeros((3, 2)), log_prob=np.zeros(3)), np.ones(4, dtype=bool)),
                            (good, np.ones(3, dtype=bool)),
                            (emcee.State(np.zeros((4, 2)), log_prob=np.zeros(4), blobs=np.zeros(4)),
                             np.ones(4, dtype=bool))]:
        with pytest.raises(ValueError):
            b._check(state, accepted)


def test_emcees_getters_read_through_get_value(tmp_path):
    params = inspect.signature(HDF.get_value).parameters
    assert list(params) == ["self", "name", "flat", "thin", "discard"], _changed(
        "HDFBackend.get_value(name, flat, thin, discard)")
    asked = []

    class Recording(_Facts):
        iteration = 3
        initialized = True
        random_state = ("MT19937", np.zeros(624, dtype=np.uint32), 0, 0, 0.0)

        def get_value(self, name, flat=False, thin=1, discard=0):
            asked.append(name)
            shapes = {"chain": (self.iteration - discard, 4, 2), "log_prob": (self.iteration - discard, 4)}
            return np.ones(shapes[name]) if name in shapes else None

    b = Recording(str(tmp_path / "none.h5"), name=GROUP)
    last = b.get_last_sample()
    assert sorted(asked) == ["blobs", "chain", "log_prob"], _changed(
        "Backend.get_last_sample (reading through get_value, which TwinBackend overrides)")
    assert last.random_state is Recording.random_state, _changed("Backend.get_last_sample's random state")
    asked.clear()
    b.get_chain(), b.get_log_prob(), b.get_blobs()
    assert asked == ["chain", "log_prob", "blobs"], _changed("Backend.get_chain, get_log_prob, get_blobs")


def test_the_sampler_grows_once_then_saves_each_step():
    calls = []

    class Recording(emcee.backends.Backend):
        def grow(self, ngrow, blobs):
            calls.append(("grow", ngrow))
            super().grow(ngrow, blobs)

        def save_step(self, state, accepted):
            calls.append(("save_step", state.random_state is not None))
            super().save_step(state, accepted)

    sampler = emcee.EnsembleSampler(4, 2, lambda x: -0.5 * float(x @ x), backend=Recording())
    start = emcee.State(np.random.default_rng(0).normal(size=(4, 2)), random_state=np.random.RandomState(1).get_state())
    for _ in sampler.sample(start, iterations=3, store=True):
        pass
    assert calls == [("grow", 3)] + [("save_step", True)] * 3, _changed(
        "EnsembleSampler.sample's calls to its backend (grow, then save_step with the random state)")
