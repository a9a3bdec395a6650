"""The on-disk cache of generated kernels.

A generated module is written to a folder and imported from there, so that numba's own
cache (``cache=True``) keeps its machine code between processes: the first use on a
machine compiles each network's kernel (seconds), later processes load it (tens of ms).

Where: ``<base>/<environment key>``, the base ``$BAYES_INERTER_KERNEL_DIR``, else
``~/.cache/bayes-inerter/kernels``, else one in the temporary directory; where none can be
written the module is compiled in memory. The environment key (:func:`environment_key`)
is a hash of what the machine code was made by and for (:func:`environment`): the Python
environment (``sys.prefix``), where this package is installed (a clone's own folder for
an editable install), the numba, numpy and Python versions, and the processor
(``platform.machine()``, its model and flags from ``/proc/cpuinfo`` where there is one,
numba's ``NUMBA_CPU_NAME`` and ``NUMBA_CPU_FEATURES``). So every virtual environment and
every clone of a user has its own folder: none loads machine code another compiled. A
folder can be deleted at any time (its kernels are compiled again).

Kernel files are named by a hash of their source and of the compiled helpers' dotted
names and source (``_compiled.py``, ``_rich.py``), so a changed kernel, or one whose
helpers moved, never meets an old cache.

**The helpers are copied into each folder** (``bayes_inerter_compiled_<tag>.py``,
``bayes_inerter_rich_<tag>.py``, the tag a hash of the helpers' names and source and of the folder)
and the kernels there call those copies, not the package's ``_compiled`` and ``_rich``
(the in-memory fallback still calls the package's). Why: numba links a compiled callee
into its caller's machine code and names it, and the *environment* holding the
constants its Python wrapper reads, by module, function, types and a counter of the
compiling process: unique within that process only. A kernel cached by one process
carried copies of ``_compiled``'s helpers named as another process could name its own
compilation of them, and numba gives a function whose environment name is taken that
environment. ``_compiled.tables`` compiled afresh (the package's numba cache of the
helpers is kept by their file's time, the kernels by their content: a new clone, or a
checkout, beside a filled kernel folder) after such a kernel was loaded put its
constant after the loaded copy's, into that environment; its numba cache entry then read
a constant that was not there in every later process that loaded a kernel with the
clashing copy first: ``RuntimeError: In 'NRT_adapt_ndarray_to_python', 'descr' is
NULL``, ``tests/test_simulate.py``'s direct call of ``tables`` after
``tests/test_kernel.py``. Now no cached kernel carries a name of the package's helpers;
the copies are compiled and cached in the folder with its kernels and are never called
from Python, so no wrapper of theirs reads an environment.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.util
import json
import os
import platform
import re
import sys
import tempfile
from pathlib import Path

from numba import njit

__all__ = ["KERNEL_DIR_ENV", "kernel_dirs", "load", "environment", "environment_key"]

KERNEL_DIR_ENV = "BAYES_INERTER_KERNEL_DIR"
#: Where this package is installed (for an editable install: the clone's folder).
PACKAGE_DIR = Path(__file__).resolve().parents[2]

#: The package's helper modules, which the kernel folders get copies of.
HELPERS = ("bayes_inerter.simulate._kernel._compiled", "bayes_inerter.simulate._kernel._rich")

HEADER = (
    "import numpy as np\n"
    "from numba import njit\n"
    "from bayes_inerter.simulate._kernel._compiled import (HERMITE_SLACK, STATUS_OK, STATUS_TOO_MANY_EVENTS, cubic_range,\n"
    "                                             setup, start, switch)\n\n"
)
#: The header of a kernel for piecewise-linear laws and dead zones: its setup, start and
#: switch are ``_rich``'s.
RICH_HEADER = (
    "import numpy as np\n"
    "from numba import njit\n"
    "from bayes_inerter.simulate._kernel._compiled import HERMITE_SLACK, STATUS_OK, STATUS_TOO_MANY_EVENTS, cubic_range\n"
    "from bayes_inerter.simulate._kernel._rich import setup, start, switch\n\n"
)


@functools.lru_cache(maxsize=1)
def _cpu() -> str:
    """The processor's model and flags as ``/proc/cpuinfo`` gives them for its first
    processor (x86: model name, flags; ARM: implementer, part, features), "" without it."""
    try:
        text = Path("/proc/cpuinfo").read_text(errors="replace")
    except OSError:
        return ""
    found: dict = {}
    for line in text.splitlines():
        key, sep, value = line.partition(":")
        key = key.strip()
        if sep and key in ("model name", "flags", "CPU implementer", "CPU part", "Features"):
            found.setdefault(key, value.strip())
    return "\n".join(f"{k}: {v}" for k, v in sorted(found.items()))


def environment() -> dict:
    """What a kernel folder is keyed by (see the module docstring)."""
    import numba
    import numpy

    return {"prefix": sys.prefix, "package": str(PACKAGE_DIR), "numba": numba.__version__,
            "numpy": numpy.__version__, "python": sys.version, "machine": platform.machine(), "cpu": _cpu(),
            "numba_cpu": [os.environ.get("NUMBA_CPU_NAME", ""), os.environ.get("NUMBA_CPU_FEATURES", "")]}


def environment_key() -> str:
    """The name of this environment's kernel folder: a hash of :func:`environment`."""
    return hashlib.sha256(json.dumps(environment(), sort_keys=True).encode()).hexdigest()[:16]


def kernel_dirs():
    """The folders tried in turn (see the module docstring)."""
    key = environment_key()
    if os.environ.get(KERNEL_DIR_ENV):
        yield Path(os.environ[KERNEL_DIR_ENV]) / key
    yield Path.home() / ".cache" / "bayes-inerter" / "kernels" / key
    yield Path(tempfile.gettempdir()) / f"bayes-inerter-kernels-{os.getuid() if hasattr(os, 'getuid') else 0}" / key


def _helper_path(module: str) -> Path:
    return Path(__file__).parent / (module.rsplit(".", 1)[1] + ".py")


def _helpers() -> bytes:
    """The helpers' dotted names and sources: what the copies' names and the kernels'
    digests hash. The names count too: numba's cache pickles the types a compiled helper
    was called with (the kernel's ``Net`` among them) under the module that defines them,
    and a cache written before the helpers moved could not be read after."""
    return b"".join(module.encode() + b"\n" + _helper_path(module).read_bytes() for module in HELPERS)


def _write(folder: Path, module_name: str, text: str) -> Path:
    """Write ``text`` as ``module_name`` into ``folder``, unless it is there already."""
    path = folder / f"{module_name}.py"
    if not path.exists() or path.read_text() != text:
        tmp = folder / f".{module_name}.{os.getpid()}.tmp"
        tmp.write_text(text)
        os.replace(tmp, path)
    return path


def _import(module_name: str, path: Path):
    spec = importlib.util.spec_from_file_location(module_name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[module_name] = module  # numba's cache finds a function's module by name
    spec.loader.exec_module(module)
    return module


def _folder_helpers(folder: Path, helpers: bytes) -> dict:
    """Copy the helper modules into ``folder`` and import the copies (once per process);
    return the package's helper module names mapped to the copies' names."""
    tag = hashlib.sha256(helpers + str(folder.resolve()).encode()).hexdigest()[:20]
    names = {module: f"bayes_inerter{module.rsplit('.', 1)[1]}_{tag}" for module in HELPERS}
    for module, name in names.items():
        text = _helper_path(module).read_text()
        for other, other_name in names.items():  # the helpers' imports of each other
            text = text.replace(f"from .{other.rsplit('.', 1)[1]} import", f"from {other_name} import")
        if re.search(r"^\s*from \.", text, re.MULTILINE):
            raise RuntimeError(f"{module} imports a module that the kernel folders have no copy of")
        path = _write(folder, name, text)
        if getattr(sys.modules.get(name), "__file__", None) != str(path):
            _import(name, path)
    return names


def load(source: str, name: str = "kernel", header: str = HEADER):
    """Compile the generated ``source`` (see ``generate``) after ``header`` (its imports)
    and return its function ``name``: from a module written to the first folder that can
    be written, with that folder's copies of the helpers, else in memory."""
    helpers = _helpers()
    digest = hashlib.sha256(helpers + header.encode() + source.encode()).hexdigest()[:20]
    module_name = f"bayes_inerter_kernel_{digest}"
    for folder in kernel_dirs():
        try:
            folder.mkdir(parents=True, exist_ok=True)
            own = header
            for module, copy in _folder_helpers(folder, helpers).items():
                own = own.replace(f"from {module} import", f"from {copy} import")
            path = _write(folder, module_name, own + "_jit = njit(cache=True)\n\n\n" + source)
        except OSError:
            continue
        return getattr(_import(module_name, path), name)
    namespace: dict = {"njit": njit}
    exec(compile(header + "_jit = njit\n\n\n" + source, module_name, "exec"), namespace)
    return namespace[name]
