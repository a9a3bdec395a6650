"""The specialised kernels (``_kernel.kernel_for``) against the general ``run_kernel``."""

import numpy as np
import pytest
from conftest import inverse_dynamics_force

from bayes_inerter import _kernel, paper_parameters
from bayes_inerter.models import build_network
from bayes_inerter.network import compile_network
from bayes_inerter.simulate import _augmented, _contacts


def kernel_arguments(network, setting, freq, *, scale=1.0, store=False, max_events=200):
    """run_kernel's arguments for a network driven as simulate drives it."""
    p = paper_parameters(setting)
    t, f = inverse_dynamics_force(p, freq, duration=2.0, ramp=0.4)
    compiled = compile_network(build_network(network, p))
    A, B = compiled.state_space(viscous=True)
    nodes, f0, mass = _contacts(compiled)
    n = A.shape[0]
    Abar = _augmented(A, B.reshape(n, 1), nodes, mass)
    return (Abar, n, 1, nodes, f0, mass, (scale * f).reshape(-1, 1), float(t[1] - t[0]), np.zeros(n), 0,
            store, max_events)


@pytest.mark.parametrize(
    "network, setting, freq, scale",
    [("reduced", "A3", 1.0, 1.0), ("reduced", "A0", 0.5, 0.9), ("reduced", "B2", 1.5, 1.0),
     ("full", "A3", 1.0, 1.0), ("rigid", "A2", 1.0, 0.95), ("linear", "A1", 1.0, 1.0)],
)
@pytest.mark.parametrize("store", [False, True])
def test_specialised_kernel_equals_general_bit_for_bit(network, setting, freq, scale, store):
    args = kernel_arguments(network, setting, freq, scale=scale, store=store)
    general = _kernel.run_kernel(*args)
    for pattern in (None, (args[0] != 0).tobytes()):  # dense, and the matrix's zeros left out
        special = _kernel.kernel_for(args[1], args[2], args[3], args[9], pattern)(*args)
        for a, b in zip(general[:3], special[:3]):
            np.testing.assert_array_equal(a, b)
        assert general[3] == special[3] == _kernel.STATUS_OK
        np.testing.assert_array_equal(general[4], special[4])
    if network != "linear":
        assert general[4][0] > 0  # the contacts switched: the rare path ran too


def test_specialised_kernel_gives_up_where_the_general_does():
    args = kernel_arguments("reduced", "A0", 0.5, scale=0.9, max_events=0)
    general = _kernel.run_kernel(*args)
    special = _kernel.kernel_for(args[1], args[2], args[3], args[9])(*args)
    assert general[3] == special[3] == _kernel.STATUS_TOO_MANY_EVENTS
    np.testing.assert_array_equal(general[0], special[0])
    assert np.isnan(special[0][-1])


def test_specialised_kernels_are_kept_per_shape():
    args = kernel_arguments("reduced", "A3", 1.0)
    fn = _kernel.kernel_for(args[1], args[2], args[3], args[9])
    assert _kernel.kernel_for(args[1], args[2], list(args[3]), args[9]) is fn
    assert _kernel.kernel_for(args[1], args[2], args[3][:1], args[9]) is not fn
    assert _kernel.kernel_for(args[1], args[2], args[3], args[9], (args[0] != 0).tobytes()) is not fn


def test_sparse_kernel_leaves_out_only_zero_terms():
    args = kernel_arguments("reduced", "A3", 1.0)
    src = _kernel._specialised_source(args[1], args[2], tuple(args[3]), args[9], (args[0] != 0).tobytes())
    dense = _kernel._specialised_source(args[1], args[2], tuple(args[3]), args[9])
    assert src.count(" * ") < dense.count(" * ")
    # every guard coefficient it reads is one the matrix can make nonzero
    nz = args[0] != 0
    for i, node in enumerate(args[3]):
        for j in range(nz.shape[1]):
            if f"vd{i}_{j} = VD" in src:
                assert nz[node, j]
            if f"VD[mode, {i}, {j}]" in src:  # the rare path's reads (``events``)
                assert nz[node, j]
    assert "VD[mode, 0, " in src and "VD[mode, 0, " in dense
    assert src.count("VD[mode, ") < dense.count("VD[mode, ")


@pytest.mark.slow
def test_kernel_compiled_in_memory_where_no_folder_can_be_written(monkeypatch, tmp_path):
    blocked = tmp_path / "file"
    blocked.write_text("not a folder")
    monkeypatch.setattr(_kernel, "_kernel_dirs", lambda: iter([blocked / "kernels"]))
    monkeypatch.setattr(_kernel, "_SPECIALISED", {})
    args = kernel_arguments("rigid", "A2", 1.0, scale=0.95)
    special = _kernel.kernel_for(args[1], args[2], args[3], args[9])(*args)
    np.testing.assert_array_equal(special[0], _kernel.run_kernel(*args)[0])
    assert not (blocked.parent / "kernels").exists()
