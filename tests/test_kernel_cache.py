"""The on-disk cache of generated kernels (``_kernel.cache``)."""

import numpy as np
import pytest
from test_kernel import kernel_arguments

from bayes_inerter import _kernel
from bayes_inerter._kernel import cache


def test_a_kernel_is_written_once_named_by_its_source(monkeypatch, tmp_path):
    monkeypatch.setenv(cache.KERNEL_DIR_ENV, str(tmp_path))
    source = "@_jit\ndef kernel(x):\n    return 2 * x\n"
    fn = cache.load(source)
    assert fn(3) == 6
    files = sorted(tmp_path.glob("bayes_inerter_kernel_*.py"))
    assert len(files) == 1 and files[0].read_text().endswith(source)
    cache.load(source)
    assert sorted(tmp_path.glob("bayes_inerter_kernel_*.py")) == files
    cache.load(source.replace("2 * x", "3 * x"))
    assert len(list(tmp_path.glob("bayes_inerter_kernel_*.py"))) == 2


@pytest.mark.slow
def test_kernel_compiled_in_memory_where_no_folder_can_be_written(monkeypatch, tmp_path):
    args = kernel_arguments("rigid", "A2", 1.0, scale=0.95)
    on_disk = _kernel.kernel_for(args[1], args[2], args[3], args[9])(*args)
    blocked = tmp_path / "file"
    blocked.write_text("not a folder")
    monkeypatch.setattr(cache, "kernel_dirs", lambda: iter([blocked / "kernels"]))
    monkeypatch.setattr(_kernel, "_SPECIALISED", {})
    in_memory = _kernel.kernel_for(args[1], args[2], args[3], args[9])(*args)
    np.testing.assert_array_equal(in_memory[0], on_disk[0])
    assert not (blocked.parent / "kernels").exists()
