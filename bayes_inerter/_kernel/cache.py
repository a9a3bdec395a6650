"""The on-disk cache of generated kernels.

A generated module is written to a folder and imported from there, so that numba's own
cache (``cache=True``) keeps its machine code between processes: the first use on a
machine compiles each network's kernel (seconds), later processes load it (tens of ms).

The folder is ``$BAYES_INERTER_KERNEL_DIR``, else ``~/.cache/bayes-inerter/kernels``, else
one in the temporary directory; where none can be written the module is compiled in
memory. Files are named by a hash of their source and of the compiled helpers'
(``_compiled.py``, ``_rich.py``), so a changed kernel never meets an old cache.
"""

from __future__ import annotations

import hashlib
import importlib.util
import os
import sys
import tempfile
from pathlib import Path

from numba import njit

__all__ = ["KERNEL_DIR_ENV", "kernel_dirs", "load"]

KERNEL_DIR_ENV = "BAYES_INERTER_KERNEL_DIR"

HEADER = (
    "import numpy as np\n"
    "from numba import njit\n"
    "from bayes_inerter._kernel._compiled import (HERMITE_SLACK, STATUS_OK, STATUS_TOO_MANY_EVENTS, cubic_range,\n"
    "                                             setup, start, switch)\n\n"
)
#: The header of a kernel for piecewise-linear laws and dead zones: its setup, start and
#: switch are ``_rich``'s.
RICH_HEADER = (
    "import numpy as np\n"
    "from numba import njit\n"
    "from bayes_inerter._kernel._compiled import HERMITE_SLACK, STATUS_OK, STATUS_TOO_MANY_EVENTS, cubic_range\n"
    "from bayes_inerter._kernel._rich import setup, start, switch\n\n"
)


def kernel_dirs():
    """The folders tried in turn (see the module docstring)."""
    if os.environ.get(KERNEL_DIR_ENV):
        yield Path(os.environ[KERNEL_DIR_ENV])
    yield Path.home() / ".cache" / "bayes-inerter" / "kernels"
    yield Path(tempfile.gettempdir()) / f"bayes-inerter-kernels-{os.getuid() if hasattr(os, 'getuid') else 0}"


def _helpers() -> bytes:
    return b"".join((Path(__file__).parent / name).read_bytes() for name in ("_compiled.py", "_rich.py"))


def load(source: str, name: str = "kernel", header: str = HEADER):
    """Compile the generated ``source`` (see ``generate``) after ``header`` (its imports)
    and return its function ``name``: from a module written to the first folder that can
    be written, else in memory."""
    digest = hashlib.sha256(_helpers() + header.encode() + source.encode()).hexdigest()[:20]
    module_name = f"bayes_inerter_kernel_{digest}"
    text = header + "_jit = njit(cache=True)\n\n\n" + source
    for folder in kernel_dirs():
        path = folder / f"{module_name}.py"
        try:
            folder.mkdir(parents=True, exist_ok=True)
            if not path.exists() or path.read_text() != text:
                tmp = folder / f".{module_name}.{os.getpid()}.tmp"
                tmp.write_text(text)
                os.replace(tmp, path)
        except OSError:
            continue
        spec = importlib.util.spec_from_file_location(module_name, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[module_name] = module  # numba's cache finds the function's module by name
        spec.loader.exec_module(module)
        return getattr(module, name)
    namespace: dict = {"njit": njit}
    exec(compile(header + "_jit = njit\n\n\n" + source, module_name, "exec"), namespace)
    return namespace[name]
