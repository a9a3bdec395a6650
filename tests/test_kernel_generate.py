"""The generated kernel source: golden files for the paper's networks, and what it reads.

The golden files ``tests/golden/kernel_<network>.py`` are the generator's output for the
paper's networks (A3 parameters, the augmented matrix's nonzero pattern, as ``simulate``
asks for them), so that any change of the generated code shows in review. After a
deliberate change of the generator, rewrite them with

    BAYES_INERTER_REGENERATE_GOLDEN=1 python -m pytest tests/test_kernel_generate.py

and read the diff before committing it.
"""

import os
from pathlib import Path

import numpy as np
import pytest
from test_kernel import kernel_arguments

from bayes_inerter.simulate._kernel.generate import Shape, expand, kernel_source
from bayes_inerter.networks import NETWORKS

GOLDEN = Path(__file__).parent / "golden"
REGENERATE = os.environ.get("BAYES_INERTER_REGENERATE_GOLDEN") == "1"


def shape_of(network, *, dense=False):
    args = kernel_arguments(network, "A3", 1.0)
    return Shape(args[1], args[2], tuple(int(x) for x in args[3]), args[9], None if dense else (args[0] != 0).tobytes())


@pytest.mark.parametrize("network", sorted(NETWORKS))
def test_generated_source_is_the_golden_file(network):
    path = GOLDEN / f"kernel_{network}.py"
    source = kernel_source(shape_of(network))
    if REGENERATE:
        path.write_text(source)
    assert path.exists(), f"{path} is missing: regenerate it (see this module's docstring)"
    assert source == path.read_text(), f"the generated kernel for {network!r} changed (see this module's docstring)"


def test_sparse_kernel_leaves_out_only_zero_terms():
    args = kernel_arguments("reduced", "A3", 1.0)
    src = kernel_source(shape_of("reduced"))
    dense = kernel_source(shape_of("reduced", dense=True))
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


def test_bounds_and_table_entries_have_their_own_names():
    """Contact i's Coulomb bound was once a local named like table entry (0, i), so the
    common step compared a stuck contact's holding force with a table entry and left
    every stuck interval to the rare path (right, but slow)."""
    src = kernel_source(shape_of("full"))
    for i in range(3):
        assert f"bound{i} = f0[{i}]" in src
        assert f"> bound{i}" in src
    assert "f0_0 = F[mode, 0, 0, 0]" in src and "f0_0 = f0" not in src


def test_expand_fills_blocks_with_their_indentation():
    lines = expand("a = {x}\nif a:\n    $block(p, q)\n    $empty\n", x=1, block=lambda p, q: [f"{p} = {q}", "b = 2"],
                   empty=[])
    assert lines == ["a = 1", "if a:", "    p = q", "    b = 2", "    pass"]


def test_golden_files_compile():
    for network in sorted(NETWORKS):
        compile((GOLDEN / f"kernel_{network}.py").read_text(), network, "exec")
    assert np.all([(GOLDEN / f"kernel_{n}.py").stat().st_size > 0 for n in NETWORKS])
