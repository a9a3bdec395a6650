"""The generated kernels (``_kernel.kernel_for``) against the plain reference kernel
(``tests/reference_kernel.py``): the same algorithm written without speed tricks."""

import numpy as np
import pytest
from conftest import with_backlash
from reference_kernel import Reference

from bayes_inerter import paper_parameters
from bayes_inerter.simulate import _kernel, _piecewise
from bayes_inerter.friction import Coulomb, PiecewiseLinear
from bayes_inerter.networks import build_network
from bayes_inerter.network import compile_network
from bayes_inerter.simulate import _contacts
from bayes_inerter.simulate.reference import inverse_dynamics_force

CASES = [("reduced", "A3", 1.0, 1.0), ("reduced", "A0", 0.5, 0.9), ("reduced", "B2", 1.5, 1.0),
         # the full network's kernel and its plain reference take a minute on a busy
         # machine: with the slow tests (bash test.sh --all)
         pytest.param("full", "A3", 1.0, 1.0, marks=pytest.mark.slow), ("rigid", "A2", 1.0, 0.95),
         ("linear", "A1", 1.0, 1.0)]
#: The dense/sparse comparison compiles a dense kernel per case: one case in the quick
#: subset, the others with the slow tests.
DENSE_CASES = [CASES[0]] + [pytest.param(*(c.values if hasattr(c, "values") else c), marks=pytest.mark.slow)
                            for c in CASES[1:]]


def network_arrays(network, setting, freq, *, scale=1.0, duration=2.0):
    """The state space, contacts and force record of a network driven as simulate drives it."""
    p = paper_parameters(setting)
    t, f = inverse_dynamics_force(p, freq, duration=duration, ramp=0.4)
    compiled = compile_network(build_network(network, p))
    A, B = compiled.state_space(viscous=True)
    return A, B.reshape(-1, 1), *_contacts(compiled), (scale * f).reshape(-1, 1), float(t[1] - t[0])


def kernel_arguments(network, setting, freq, *, scale=1.0, store=False, max_events=200, duration=2.0):
    """The kernel's arguments for a network driven as simulate drives it."""
    A, B, nodes, f0, mass, inputs, h = network_arrays(network, setting, freq, scale=scale, duration=duration)
    n = A.shape[0]
    Abar = _piecewise.augmented(A, B, nodes, mass)
    return (Abar, n, 1, nodes, f0, mass, inputs, h, np.zeros(n), 0, store, max_events)


def generated(args, dense=False):
    return _kernel.kernel_for(args[1], args[2], args[3], args[9], None if dense else (args[0] != 0).tobytes())


def rel_error(a, ref):
    """Relative L2 error normalised as in the paper's eq. (5)."""
    return np.linalg.norm(a - ref) / np.linalg.norm(ref - ref.mean())


@pytest.mark.parametrize("network, setting, freq, scale", CASES)
def test_generated_kernel_follows_the_plain_reference(network, setting, freq, scale):
    A, B, nodes, f0, mass, inputs, h = network_arrays(network, setting, freq, scale=scale)
    accel, vel, states, status, stats = generated(kernel_arguments(network, setting, freq, scale=scale, store=True))(
        *kernel_arguments(network, setting, freq, scale=scale, store=True))
    r_accel, r_vel, r_states, ok, r_stats = Reference.coulomb(A, B, nodes, f0, mass, h).run(inputs)
    assert status == _kernel.STATUS_OK and ok
    # the same switches, located on the same ticks: the outputs agree to rounding
    assert stats[0] == r_stats[0]
    assert rel_error(accel, r_accel) < 1e-9
    assert rel_error(vel, r_vel) < 1e-9
    np.testing.assert_allclose(states, r_states, rtol=1e-8, atol=1e-12 * np.abs(r_states).max())
    if network != "linear":
        assert stats[0] > 0  # the contacts switched: the rare path ran too


@pytest.mark.slow  # 12 s from a fresh clone: the dense kernel is compiled for this test alone
@pytest.mark.parametrize("network, setting, freq, scale", DENSE_CASES)
@pytest.mark.parametrize("store", [False, True])
def test_dense_and_sparse_kernels_agree_bit_for_bit(network, setting, freq, scale, store):
    args = kernel_arguments(network, setting, freq, scale=scale, store=store)
    dense, sparse = generated(args, dense=True)(*args), generated(args)(*args)
    for a, b in zip(dense[:3], sparse[:3]):
        np.testing.assert_array_equal(a, b)
    assert dense[3] == sparse[3] == _kernel.STATUS_OK
    np.testing.assert_array_equal(dense[4], sparse[4])
    assert sparse[2].shape == ((len(args[6]) if store else 0), args[1])


def test_generated_kernel_gives_up_where_the_reference_does():
    args = kernel_arguments("reduced", "A0", 0.5, scale=0.9, max_events=0, duration=0.8)
    accel, _, _, status, _ = generated(args)(*args)
    A, B, nodes, f0, mass, inputs, h = network_arrays("reduced", "A0", 0.5, scale=0.9, duration=0.8)
    r_accel, _, _, ok, _ = Reference.coulomb(A, B, nodes, f0, mass, h).run(inputs, max_events=0)
    assert status == _kernel.STATUS_TOO_MANY_EVENTS and not ok
    np.testing.assert_array_equal(np.isnan(accel), np.isnan(r_accel))
    assert np.isnan(accel[-1]) and not np.isnan(accel[0])
    done = ~np.isnan(accel)
    np.testing.assert_allclose(accel[done], r_accel[done], rtol=1e-9, atol=1e-9 * np.abs(r_accel[done]).max())


def test_kernels_are_kept_per_shape():
    args = kernel_arguments("reduced", "A3", 1.0)
    fn = _kernel.kernel_for(args[1], args[2], args[3], args[9])
    assert _kernel.kernel_for(args[1], args[2], list(args[3]), args[9]) is fn
    assert _kernel.kernel_for(args[1], args[2], args[3][:1], args[9]) is not fn
    assert _kernel.kernel_for(args[1], args[2], args[3], args[9], (args[0] != 0).tobytes()) is not fn


def rich_case(network, setting, freq, friction, gap, *, duration=1.0, scale=1.0):
    """A network with piecewise-linear laws and a dead zone, its kernel's shape and arrays,
    and the plain reference for it."""
    p = paper_parameters(setting)
    t, f = inverse_dynamics_force(p, freq, duration=duration, ramp=0.4)
    net = build_network(network, p, friction)
    compiled = compile_network(with_backlash(net, gap) if gap else net)
    A, B = compiled.state_space(viscous=True)
    h = float(t[1] - t[0])
    shape, arrays = _piecewise.network_arrays(compiled, A, B, h)
    laws = [PiecewiseLinear.total(node) if node else None for node in compiled.laws]
    nodes = [i for i, law in enumerate(laws) if law is not None and law.f_s > 0]
    gaps = {j: g for j, g in enumerate(compiled.link_gap) if g > 0}
    ref = Reference(A, B.reshape(-1, 1), nodes, [laws[i] for i in nodes], compiled.masses[nodes], h,
                    compiled=compiled, gaps=gaps)
    return shape, arrays, ref, (scale * f).reshape(-1, 1)


#: The dead zone stays in the quick subset on the linear network (no contact: the smallest
#: kernel with a gap, the shape ``test_simulate.py``'s backlash check uses; the helpers of
#: every kernel for piecewise-linear laws, most of a first such kernel's compile, are
#: compiled before the workers start, ``tests/_warm.py``); Stribeck's pieces are there on
#: the rigid network (``test_simulate.py``'s hybrid reference). The other cases (each a
#: kernel of its own) run with the slow tests.
RICH_CASES = [("linear", "A3", 1.0, "coulomb", 2e-5)] + [
    pytest.param(*c, marks=pytest.mark.slow) for c in
    (("reduced", "A3", 1.0, "coulomb", 2e-5), ("reduced", "A1", 1.0, "stribeck", 2e-5),
     ("rigid", "A2", 1.0, "stribeck", 0.0), ("reduced", "B2", 1.5, "stribeck", 0.0))]


@pytest.mark.parametrize("network, setting, freq, friction, gap", RICH_CASES)
def test_rich_kernel_follows_the_plain_reference(network, setting, freq, friction, gap):
    """Piecewise-linear laws (Stribeck in 4 pieces) and a dead zone in the nut link."""
    shape, arrays, ref, inputs = rich_case(network, setting, freq, friction, gap)
    accel, vel, states, status, stats = _kernel.rich_kernel_for(shape)(arrays, inputs, np.zeros(shape.n), True, 200)
    r_accel, r_vel, r_states, ok, r_stats = ref.run(inputs)
    assert status == _kernel.STATUS_OK and ok
    assert stats[0] == r_stats[0] > 0
    assert rel_error(accel, r_accel) < 1e-9
    assert rel_error(vel, r_vel) < 1e-9
    np.testing.assert_allclose(states, r_states, rtol=1e-8, atol=1e-12 * np.abs(r_states).max())
    if gap:  # the gap was entered and left
        assert np.any(np.abs(states[:, shape.links[0]]) < gap) and np.any(np.abs(states[:, shape.links[0]]) > gap)


@pytest.mark.slow
def test_rich_kernel_on_coulomb_laws_is_the_coulomb_kernel():
    """Coulomb laws given as one-piece piecewise-linear laws take the general kernel for
    piecewise-linear laws: it must give the Coulomb kernel's simulation, to rounding."""
    args = kernel_arguments("reduced", "A0", 0.5, scale=0.9, store=True)
    coulomb = generated(args)(*args)
    shape, arrays, _, inputs = rich_case("reduced", "A0", 0.5, lambda f0, c: Coulomb(f0, c).piecewise(), 0.0,
                                         duration=2.0, scale=0.9)
    rich = _kernel.rich_kernel_for(shape)(arrays, inputs, np.zeros(shape.n), True, 200)
    assert rich[4][0] == coulomb[4][0] > 0
    assert rel_error(rich[0], coulomb[0]) < 1e-10
    np.testing.assert_allclose(rich[2], coulomb[2], rtol=1e-9, atol=1e-13 * np.abs(coulomb[2]).max())
