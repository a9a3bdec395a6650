"""Device files (TOML) and where each mass comes from."""

import math

import pytest

from bayes_inerter.device import DEFAULT_GEOMETRY, SMALL_FLYWHEEL, TABLE_I, theoretical_inertance
from bayes_inerter.device_file import DeviceFileError, read_device
from bayes_inerter.masses import resolve_masses
from bayes_inerter.records import Record

import numpy as np

PAPER_A3 = f"""
m_B = 57.2
m_s = 21.688
[geometry]
lead = {DEFAULT_GEOMETRY.lead!r}
J_screw = {DEFAULT_GEOMETRY.J_screw!r}
[[geometry.flywheels]]
diameter = {SMALL_FLYWHEEL['diameter']}
thickness = {SMALL_FLYWHEEL['thickness']}
mass = {SMALL_FLYWHEEL['mass']}
count = 3
"""


def test_the_paper_device_gives_the_paper_theory(tmp_path):
    p = tmp_path / "a3.toml"
    p.write_text(PAPER_A3)
    dev = read_device(p)
    assert dev.m_B == 57.2 and dev.m_s == 21.688
    assert dev.theoretical_inertance == pytest.approx(theoretical_inertance("A3"), rel=1e-12)


def test_flywheel_by_density_and_screw_as_a_disc(tmp_path):
    p = tmp_path / "d.toml"
    p.write_text("""
[geometry]
lead = 0.02
screw = { mass = 15.0, diameter = 0.05 }
[[geometry.flywheels]]
diameter = 0.2
thickness = 0.01
density = 7850
""")
    dev = read_device(p)
    m = 7850 * math.pi * 0.1**2 * 0.01
    J = 0.5 * 15.0 * 0.025**2 + 0.5 * m * 0.1**2
    assert dev.theoretical_inertance == pytest.approx((2 * math.pi / 0.02) ** 2 * J)
    assert dev.m_B is None


@pytest.mark.parametrize("text, message", [
    ("m_B = -1", "m_B must be a positive number"),
    ("mass = 3", "unknown key 'mass'"),
    ("m_B = [", "not valid TOML"),
    ("[geometry]\nJ_screw = 0.01", "key 'lead' is missing"),
    ("[geometry]\nlead = 0.02", "give J_screw"),
    ("[geometry]\nlead = 0.02\nJ_screw = 0.01\n[[geometry.flywheels]]\ndiameter = 0.2", "give mass"),
])
def test_bad_device_files_refused(tmp_path, text, message):
    p = tmp_path / "bad.toml"
    p.write_text(text)
    with pytest.raises(DeviceFileError, match=message):
        read_device(p)


def _rec(**meta):
    t = np.arange(200) / 1000.0
    return Record(time=t, force=t, accel=t, metadata=meta)


def test_masses_precedence_and_sources(tmp_path):
    p = tmp_path / "dev.toml"
    p.write_text("m_B = 40.0\nm_s = 12.0\n")
    dev = read_device(p)
    m = resolve_masses(_rec(), device=dev)
    assert (m.m_s, m.m_B) == (12.0, 40.0) and "device file" in m.m_s_source and "device file" in m.m_B_source
    m = resolve_masses(_rec(m_s=20.0, m_B=50.0), device=dev)
    assert (m.m_s, m.m_B) == (20.0, 50.0) and m.m_B_source == "record metadata m_B"
    m = resolve_masses(_rec(m_s=20.0, m_B=50.0), m_s=1.0, m_B=2.0, device=dev)
    assert (m.m_s, m.m_B) == (1.0, 2.0) and m.m_B_source == "option --m-b"
    m = resolve_masses(_rec(setting="A3"))
    assert m.m_B == TABLE_I["m_B"] and "paper's Table I" in m.m_B_source and "setting A3" in m.m_s_source
    with pytest.raises(ValueError, match="m_s is unknown"):
        resolve_masses(_rec())
