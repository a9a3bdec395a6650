import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from bayes_inerter import paper_parameters
from bayes_inerter.friction import Coulomb
from bayes_inerter.networks import NETWORKS, build_network, lead_angle
from bayes_inerter.network import (
    Deformation,
    Friction,
    Inerter,
    Mass,
    abcd,
    accel_response,
    cascade,
    compile_network,
)

OMEGA = np.logspace(-2, 4, 400)


def state_space_response(network, omega):
    """a/F from the compiled state space: C (sI - A)^-1 B + D with C, D from row 0."""
    A, B = compile_network(network).state_space(viscous=True)
    C, D = A[0], B[0]
    out = []
    for w in omega:
        x = np.linalg.solve(1j * w * np.eye(len(A)) - A, B)
        out.append(C @ x + D)
    return np.array(out)


@pytest.mark.parametrize("name", sorted(NETWORKS))
@pytest.mark.parametrize("setting", ["A0", "A3", "B2"])
def test_cascade_equals_state_space(name, setting):
    net = build_network(name, paper_parameters(setting))
    h_cascade = accel_response(net, OMEGA)
    h_ss = state_space_response(net, OMEGA)
    np.testing.assert_allclose(h_cascade, h_ss, rtol=1e-8)


def test_accelerance_limits_of_reduced_network():
    p = paper_parameters("A1")
    net = build_network("reduced", p)
    # far above every resonance only the plate moves: a/F -> 1/m_B
    assert abs(accel_response(net, [1e7])[0]) == pytest.approx(1 / p.m_B, rel=1e-3)
    # at rest the viscous frictions hold: a/F -> s / (c_f1 + c_f2) -> 0
    w = 1e-4
    assert abs(accel_response(net, [w])[0]) == pytest.approx(w / (p.c_f1 + p.c_f2), rel=1e-2)
    # the plate-on-bearing resonance (MODEL.md: near 170 Hz) is the peak of |a/F|
    omega = np.linspace(200, 3000, 20000)
    peak = omega[np.argmax(np.abs(accel_response(net, omega)))]
    assert peak / (2 * np.pi) == pytest.approx(170, rel=0.05)


def test_single_mass():
    h = accel_response(cascade(Mass(3.0)), OMEGA)
    np.testing.assert_allclose(h, 1 / 3.0)


def test_identity_blocks_change_nothing():
    p = paper_parameters("A2")
    net = build_network("reduced", p)
    with_null = cascade(net.blocks[0], Friction(Coulomb(0.0, 0.0)), *net.blocks[1:])
    np.testing.assert_allclose(abcd(with_null, 1j * OMEGA), abcd(net, 1j * OMEGA))


def test_cascade_is_associative_and_accepts_networks():
    blocks = [Mass(2.0), Deformation(3.0, 400.0), Mass(1.0), Deformation(5.0, 100.0), Inerter(7.0)]
    left = cascade(cascade(*blocks[:2]), *blocks[2:])
    right = cascade(*blocks[:3], cascade(*blocks[3:]))
    assert left.blocks == right.blocks
    s = 1j * OMEGA
    np.testing.assert_allclose(
        abcd(left, s), abcd(cascade(*blocks[:2]), s) @ abcd(cascade(*blocks[2:]), s)
    )


@pytest.mark.parametrize(
    "block",
    [Mass(2.0), Inerter(500.0), Deformation(10.0, 1e5), Friction(Coulomb(3.0, 4.0))],
)
def test_blocks_are_reciprocal(block):
    # a passive mechanical two-port of this kind has det T = 1
    np.testing.assert_allclose(np.linalg.det(block.abcd(1j * OMEGA)), 1.0)


positive = st.floats(1e-2, 1e7, allow_nan=False)
non_negative = st.floats(0.0, 1e7, allow_nan=False)


@settings(max_examples=150, deadline=None)
@given(
    st.sampled_from(sorted(NETWORKS)),
    st.fixed_dictionaries(
        {
            "b": positive, "m_s": positive, "m_B": positive, "c_n": non_negative,
            "k_n": positive, "c_B": non_negative, "k_B": positive, "f1_0": non_negative,
            "c_f1": non_negative, "f2_0": non_negative, "c_f2": non_negative,
        }
    ),
)
def test_linear_part_is_passive(name, values):
    """Positive parameters give a positive-real driving-point mobility: Re(v/F) >= 0."""
    p = dataclasses.replace(paper_parameters("A0"), **values)
    net = build_network(name, p)
    omega = np.logspace(-3, 6, 300)
    mobility = accel_response(net, omega) / (1j * omega)
    assert np.all(np.isfinite(mobility))
    assert np.all(mobility.real >= -1e-9 * np.abs(mobility))


def test_compile_reduced():
    p = paper_parameters("A1")
    c = compile_network(build_network("reduced", p))
    np.testing.assert_allclose(c.masses, [p.m_B, p.m_s, p.b])
    np.testing.assert_allclose(c.link_c, [p.c_B, p.c_n])
    np.testing.assert_allclose(c.link_k, [p.k_B, p.k_n])
    np.testing.assert_allclose(c.coulomb_bounds, [p.f1_0, 0.0, p.f2_0])
    np.testing.assert_allclose(c.viscous, [p.c_f1, 0.0, p.c_f2])
    assert c.all_coulomb


def test_eigenvalues_of_reduced_network_match_model_md():
    # MODEL.md section 6: about -1.25e5 1/s, a pair near 1070 rad/s, slow modes
    A, _ = compile_network(build_network("reduced", paper_parameters("A1"))).state_space()
    ev = np.linalg.eigvals(A)
    assert ev.real.min() == pytest.approx(-1.25e5, rel=0.05)
    pair = ev[np.abs(ev.imag) > 100]
    assert np.abs(pair[0]) == pytest.approx(1070, rel=0.05)
    assert np.all(ev.real < 0)


def test_rigid_network_is_one_body():
    p = paper_parameters("A4")
    c = compile_network(build_network("rigid", p))
    np.testing.assert_allclose(c.masses, [p.m_B + p.m_s + p.b])
    np.testing.assert_allclose(c.coulomb_bounds, [p.f1_0 + p.f2_0])


def test_full_network_adds_sin_theta_friction():
    p = paper_parameters("A1")
    c = compile_network(build_network("full", p))
    t = np.tan(lead_angle())
    np.testing.assert_allclose(c.coulomb_bounds, [p.f1_0, t * p.f2_0, p.f2_0])
    assert 0.1 < t < 0.15  # a 7 degree lead angle
    c0 = compile_network(build_network("full", p, nut_share=0.0))
    np.testing.assert_allclose(c0.coulomb_bounds, [p.f1_0, 0.0, p.f2_0])


def test_bad_network_input():
    with pytest.raises(ValueError, match="unknown network 'fig7'"):
        build_network("fig7", paper_parameters("A0"))
    with pytest.raises(ValueError, match="node 1 has no mass"):
        compile_network(cascade(Mass(1.0), Deformation(1.0, 1.0)))
    with pytest.raises(ValueError, match="Mass: m must be positive"):
        Mass(-1.0)
    with pytest.raises(ValueError, match="Deformation: k must be non-negative"):
        Deformation(1.0, -2.0)
    with pytest.raises(ValueError, match="cannot both be zero"):
        Deformation(0.0, 0.0)
    with pytest.raises(ValueError, match="nut_share"):
        build_network("full", paper_parameters("A0"), nut_share=2.0)
    with pytest.raises(ValueError, match="a network holds blocks"):
        cascade(Mass(1.0), "spring")


@pytest.mark.parametrize("name", ["reduced", "full", "rigid", "linear"])
def test_linear_chain_gives_the_compiled_arrays(name):
    from bayes_inerter.networks import FIELDS, linear_chain

    chain = linear_chain(name)
    rng = np.random.default_rng(4)
    for setting in ("A0", "A6", "B2"):
        p = dataclasses.replace(paper_parameters(setting), **{
            f: getattr(paper_parameters(setting), f) * rng.uniform(0.2, 5.0) for f in FIELDS})
        compiled = compile_network(build_network(name, p))
        got = chain.arrays(np.array([getattr(p, f) for f in FIELDS]))
        want = (compiled.masses, compiled.link_c, compiled.link_k, compiled.viscous, compiled.coulomb_bounds)
        for g, w in zip(got, want):
            np.testing.assert_allclose(g, w, rtol=1e-15, atol=0)


def test_linear_chain_reads_the_full_networks_nut_share_exactly():
    from bayes_inerter.networks import FIELDS, NUT_SHARE, lead_angle, linear_chain

    chain = linear_chain("full")
    bounds = chain.coef[-chain.sizes[-1]:]  # each node's Coulomb bound as a form of the parameters
    share = math.tan(lead_angle()) * NUT_SHARE
    assert bounds[1, FIELDS.index("f2_0")] == share and bounds[2, FIELDS.index("f2_0")] == 1.0
    assert bounds[0, FIELDS.index("f1_0")] == 1.0 and np.count_nonzero(bounds) == 3


def test_linear_chain_refuses_a_network_that_is_not_linear_in_its_parameters(monkeypatch):
    import bayes_inerter.networks as networks

    def squared(p, friction="coulomb"):  # a mass that grows as b squared
        return cascade(Mass(p.m_B), Inerter(p.b * p.b))

    monkeypatch.setitem(networks.NETWORKS, "squared", squared)
    networks.linear_chain.cache_clear()
    try:
        assert networks.linear_chain("squared") is None
    finally:
        networks.linear_chain.cache_clear()

