"""The on-disk cache of generated kernels (``_kernel.cache``)."""

import os
import platform
import subprocess
import sys
from pathlib import Path

import numba
import numpy as np
import pytest
from test_kernel import kernel_arguments

import bayes_inerter
from bayes_inerter.simulate import _kernel
from bayes_inerter.simulate._kernel import cache

#: A kernel that calls a helper returning an array (the compiled ``_compiled.tables``).
TABLES_HEADER = "import numpy as np\nfrom numba import njit\nfrom bayes_inerter.simulate._kernel._compiled import tables\n\n"
TABLES_SOURCE = "@_jit\ndef kernel(A, h, J):\n    return tables(A, h, J)\n"


def test_a_kernel_is_written_once_named_by_its_source(monkeypatch, tmp_path):
    monkeypatch.setenv(cache.KERNEL_DIR_ENV, str(tmp_path))
    folder = tmp_path / cache.environment_key()
    source = "@_jit\ndef kernel(x):\n    return 2 * x\n"
    fn = cache.load(source)
    assert fn(3) == 6
    files = sorted(folder.glob("bayes_inerter_kernel_*.py"))
    assert len(files) == 1 and files[0].read_text().endswith(source)
    cache.load(source)
    assert sorted(folder.glob("bayes_inerter_kernel_*.py")) == files
    cache.load(source.replace("2 * x", "3 * x"))
    assert len(list(folder.glob("bayes_inerter_kernel_*.py"))) == 2
    assert not list(tmp_path.glob("*.py"))  # everything in the environment's own folder


def test_each_environment_and_clone_has_its_own_folder(monkeypatch, tmp_path):
    """Environments (virtual environments, clones, versions, processors) never share a
    kernel folder, so none loads machine code another compiled; the same environment
    always finds its own."""
    monkeypatch.setenv(cache.KERNEL_DIR_ENV, str(tmp_path))
    here = list(cache.kernel_dirs())
    assert here == list(cache.kernel_dirs())  # the same environment: the same folders
    assert here[0].parent == tmp_path and here[0].name == cache.environment_key()
    assert here[1] == Path.home() / ".cache" / "bayes-inerter" / "kernels" / cache.environment_key()
    others = {
        "another virtual environment": lambda m: m.setattr(sys, "prefix", "/elsewhere/.venv"),
        "another clone": lambda m: m.setattr(cache, "PACKAGE_DIR", Path("/elsewhere/clone/bayes_inerter")),
        "another numba": lambda m: m.setattr(numba, "__version__", "0.1.0"),
        "another numpy": lambda m: m.setattr(np, "__version__", "1.0.0"),
        "another Python": lambda m: m.setattr(sys, "version", "3.99.0"),
        "another architecture": lambda m: m.setattr(platform, "machine", lambda: "aarch64"),
        "another processor": lambda m: m.setattr(cache, "_cpu", lambda: "model name: another\nflags: sse2"),
        "numba told of another processor": lambda m: m.setenv("NUMBA_CPU_NAME", "generic"),
    }
    seen = {here[0]}
    for what, change in others.items():
        with pytest.MonkeyPatch.context() as m:  # each change undone at the end of its block
            change(m)
            folder = next(cache.kernel_dirs())
            assert folder.parent == tmp_path and folder not in seen, what
            seen.add(folder)
    assert list(cache.kernel_dirs()) == here


def test_the_cpu_is_read_where_the_system_says_it():
    cpu = cache._cpu()
    if Path("/proc/cpuinfo").exists() and platform.machine() in ("x86_64", "AMD64"):
        assert "flags: " in cpu and "sse2" in cpu


def test_kernels_call_their_folders_copy_of_the_helpers(monkeypatch, tmp_path):
    """No cached kernel carries machine code named as the package's own helpers (see
    ``cache``'s docstring): it calls the copies in its folder."""
    monkeypatch.setenv(cache.KERNEL_DIR_ENV, str(tmp_path))
    fn = cache.load(TABLES_SOURCE, header=TABLES_HEADER)
    A = np.array([[0.0, 1.0], [-4.0, -0.1]])
    from bayes_inerter.simulate._kernel._compiled import tables

    np.testing.assert_array_equal(fn(A, 1e-3, 3), tables(A, 1e-3, 3))
    helper = fn.py_func.__globals__["tables"]
    assert helper is not tables and Path(sys.modules[helper.py_func.__module__].__file__).parent == tmp_path / (
        cache.environment_key())
    code = fn.overloads[fn.signatures[0]].library.get_llvm_str()
    assert "13bayes_inerter7_kernel9_compiled" not in code and helper.py_func.__module__ in code


#: One process of the clash in ``test_a_helper_compiled_beside_a_cached_kernel_...``.
CLASH = f"""
import itertools, sys
import numpy as np
from bayes_inerter.simulate._kernel import _compiled, cache
kernel = cache.load({TABLES_SOURCE!r}, header={TABLES_HEADER!r})
A = np.array([[0.0, 1.0], [-4.0, -0.1]])
F = kernel(A, 1e-3, 3)
if sys.argv[1] == "compile":  # the uid the kernel's copy of tables was compiled with
    helper = kernel.py_func.__globals__["tables"]
    print(helper.overloads[helper.signatures[0]].fndesc.uid)
    sys.exit()
assert kernel.stats.cache_hits
if sys.argv[1] == "fresh":  # tables compiled now, by chance with the kernel's copy's uid
    from numba.core.bytecode import FunctionIdentity
    FunctionIdentity._unique_ids = itertools.count(int(sys.argv[2]))
assert np.array_equal(_compiled.tables(A, 1e-3, 3), F)
"""


@pytest.mark.slow  # three processes, about 15 s
def test_a_helper_compiled_beside_a_cached_kernel_keeps_its_constants(tmp_path):
    """The failure seen as ``RuntimeError: In 'NRT_adapt_ndarray_to_python', 'descr' is
    NULL`` from ``_compiled.tables`` once ``tests/test_kernel.py`` had run (see ``cache``'s
    docstring): a kernel is cached by one process; another, with a fresh cache of the
    package's helpers, loads it and compiles ``tables`` with the counter value the
    kernel's copy has; a third loads the kernel and then that ``tables``."""
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "numba"), cache.KERNEL_DIR_ENV: str(tmp_path / "kernels"),
           "PYTHONPATH": os.pathsep.join([str(Path(bayes_inerter.__file__).parents[1]), os.environ.get("PYTHONPATH", "")])}

    def run(*argv):
        done = subprocess.run([sys.executable, "-c", CLASH, *argv], env=env, capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
        return done.stdout.strip()

    uid = run("compile")
    for path in (tmp_path / "numba").rglob("_compiled.*"):  # the package's helpers' cache: as in a fresh clone
        path.unlink()
    run("fresh", uid)
    run("check")


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
