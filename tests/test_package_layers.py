"""The package's layers point one way: no import cycle among its modules, and no private
name (``_x``) used outside the module, or private module outside the package, that owns
it. Imports inside functions count as much as those at the top: they hide a cycle, they
do not break it. Scripts (studies/, benchmarks/) use the package's public names only.

The checks read the source (``ast``), so they see what an import at run time would only
show when that line runs. Each check is tried on a planted violation first, so that it
cannot pass by finding nothing to look at.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = "bayes_inerter"

#: Scripts allowed a private name, and why.
SCRIPT_EXCEPTIONS = {
    "benchmarks/bench_kernel.py": "times the private kernel against its own earlier version read from git, "
                                  "with the arguments that version took",
}


def package_sources(root: Path = ROOT) -> dict[str, tuple[str, bool]]:
    """Every module of the package: dotted name -> (source, is a package's __init__)."""
    out = {}
    for path in sorted((root / PACKAGE).rglob("*.py")):
        parts = list(path.relative_to(root).with_suffix("").parts)
        is_init = parts[-1] == "__init__"
        if is_init:
            parts = parts[:-1]
        out[".".join(parts)] = (path.read_text(), is_init)
    return out


def _is_private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def _absolute(module: str, is_init: bool, node: ast.ImportFrom) -> str:
    if node.level == 0:
        return node.module or ""
    base = module.split(".")
    if not is_init:
        base = base[:-1]
    base = base[:len(base) - (node.level - 1)]
    return ".".join(base + ([node.module] if node.module else []))


def _owner(private_module: str) -> str:
    """The package a private module belongs to (its parent)."""
    return private_module.rsplit(".", 1)[0]


def _may_use_module(user: str, target: str, modules) -> bool:
    """Whether ``user`` may import ``target``: every private component of ``target``'s
    path must lie inside a package that also holds ``user``."""
    parts = target.split(".")
    for i, part in enumerate(parts):
        if _is_private(part):
            owner = ".".join(parts[:i])
            if not (user == owner or user.startswith(owner + ".")):
                return False
    return True


def imports(sources: dict[str, tuple[str, bool]]):
    """(graph, violations): the package's import graph (module -> the package modules it
    imports, anywhere in its source) and every private name or module used from outside
    its owner, as readable strings."""
    modules = set(sources)
    graph = {m: set() for m in modules}
    bad = []
    for m, (source, is_init) in sources.items():
        aliases = {}  # a name bound to a package module in this file -> that module
        tree = ast.parse(source)
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom):
                target = _absolute(m, is_init, node)
                for a in node.names:
                    full = f"{target}.{a.name}"
                    if full in modules:  # a module
                        graph[m].add(full)
                        aliases[a.asname or a.name] = full
                        if not _may_use_module(m, full, modules):
                            bad.append(f"{m} imports the private module {full}")
                    elif target == PACKAGE and a.name == "__version__":
                        continue  # metadata, not a layer's code
                    elif target in modules:  # a name of a module
                        graph[m].add(target)
                        if not _may_use_module(m, target, modules):
                            bad.append(f"{m} imports from the private module {target}")
                        if _is_private(a.name) and target != m:
                            bad.append(f"{m} imports the private name {a.name} of {target}")
            elif isinstance(node, ast.Import):
                for a in node.names:
                    if a.name in modules:
                        graph[m].add(a.name)
                        if a.asname:
                            aliases[a.asname] = a.name
                        if not _may_use_module(m, a.name, modules):
                            bad.append(f"{m} imports the private module {a.name}")
        for node in ast.walk(tree):
            if (isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id in aliases
                    and _is_private(node.attr)):
                owner = aliases[node.value.id]
                full = f"{owner}.{node.attr}"
                if full in modules:
                    if not _may_use_module(m, full, modules):
                        bad.append(f"{m} uses the private module {full}")
                elif owner != m:
                    bad.append(f"{m} uses the private name {node.attr} of {owner}")
    return graph, bad


def cycles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan), each sorted."""
    index, low, on, stack, found = {}, {}, set(), [], []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in sorted(graph[v]):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1 or v in graph[v]:
                found.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return found


def script_violations(path: Path) -> list[str]:
    """A script's imports of private package names or modules, and its edits of
    ``sys.path`` (a script imports the installed package and its own folder's helpers,
    never another folder's)."""
    bad = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.Attribute) and node.attr == "path" and getattr(node.value, "id", None) == "sys":
            bad.append("sys.path")
        if isinstance(node, ast.ImportFrom) and node.level == 0 and (node.module or "").split(".")[0] == PACKAGE:
            if any(_is_private(p) for p in node.module.split(".")):
                bad.append(f"from {node.module} import ...")
            bad += [f"from {node.module} import {a.name}" for a in node.names if _is_private(a.name)]
        elif isinstance(node, ast.Import):
            bad += [f"import {a.name}" for a in node.names
                    if a.name.split(".")[0] == PACKAGE and any(_is_private(p) for p in a.name.split("."))]
    return bad


#: The package's layers, lowest first: a module imports only from its own layer and the
#: ones below (docs/development.md, "Layout"). A group is a top-level module or folder of
#: the package, inference/ split into its three layers and its entry points above them.
LAYERS = (
    ("device", "friction", "executor", "lock", "arviz_import"),
    ("network",),
    ("networks",),
    ("simulate",),
    ("records",),
    ("masses", "device_file", "plots"),
    ("inference.posterior",),
    ("inference.sampling",),
    ("inference.summaries",),
    ("inference",),
    ("study",),
    ("demo", "cli_progress"),
    ("cli",),
    ("",),  # the package's own __init__, which gathers the public names
)


def group(module: str) -> str:
    """The layer group of a package module (see :data:`LAYERS`)."""
    parts = module.split(".")[1:]
    if parts[:1] == ["inference"] and len(parts) > 1 and parts[1] in ("posterior", "sampling", "summaries"):
        return ".".join(parts[:2])
    return parts[0] if parts else ""


def upward(graph: dict[str, set[str]]) -> list[str]:
    """Imports that reach a higher layer, or a group no layer names."""
    rank = {g: i for i, layer in enumerate(LAYERS) for g in layer}
    bad = [f"{group(m)} is in no layer" for m in graph if group(m) not in rank]
    for m, deps in graph.items():
        for d in deps:
            a, b = group(m), group(d)
            if a in rank and b in rank and a != b and rank[a] < rank[b]:
                bad.append(f"{m} ({a}) imports {d} ({b}), a layer above it")
    return sorted(set(bad))


# --- the checks, each tried on a planted violation first ---------------------------------

PLANTED = {
    "pkg": ("", True),
    "pkg.a": ("from .b import helper\n", False),
    "pkg.b": ("def helper():\n    from .a import x\n", False),  # the cycle hides in a function
    "pkg.c": ("from .d import _secret\nfrom . import d\nd._other\n", False),
    "pkg.d": ("_secret = 1\n_other = 2\n", False),
    "pkg.sim": ("", True),
    "pkg.sim._core": ("", False),
    "pkg.sim.api": ("from . import _core\n", False),  # inside its package: allowed
    "pkg.e": ("from .sim import _core\n", False),  # outside it: not
}


def test_the_checks_find_planted_violations():
    graph, bad = imports(PLANTED)
    assert cycles(graph) == [["pkg.a", "pkg.b"]]
    assert sorted(bad) == ["pkg.c imports the private name _secret of pkg.d",
                           "pkg.c uses the private name _other of pkg.d",
                           "pkg.e imports the private module pkg.sim._core"]


def test_the_package_has_no_import_cycle():
    sources = package_sources()
    graph, _ = imports(sources)
    assert len(sources) > 50 and sum(map(len, graph.values())) > 150  # it read the package
    assert cycles(graph) == []


def test_the_layers_point_down():
    planted = {"bayes_inerter.records.io": {"bayes_inerter.inference.posterior.model"},
               "bayes_inerter.inference.posterior.model": {"bayes_inerter.records.io"},
               "bayes_inerter.newcomer": set()}
    assert upward(planted) == ["bayes_inerter.records.io (records) imports bayes_inerter.inference.posterior.model "
                               "(inference.posterior), a layer above it", "newcomer is in no layer"]
    graph, _ = imports(package_sources())
    assert {group(m) for m in graph} >= {"inference.posterior", "inference.sampling", "simulate", "cli"}
    assert upward(graph) == []


def test_no_private_name_is_used_outside_its_owner():
    _, bad = imports(package_sources())
    assert bad == []


@pytest.mark.parametrize("folder", ["studies", "benchmarks"])
def test_scripts_use_public_names(folder, tmp_path):
    planted = tmp_path / "planted.py"
    planted.write_text(f"from {PACKAGE}.simulate import _contacts\nimport {PACKAGE}.simulate._kernel\n"
                       "import sys\nsys.path.insert(0, 'tests')\n")
    assert len(script_violations(planted)) == 3
    scripts = sorted((ROOT / folder).glob("*.py"))
    assert len(scripts) > 5
    found = {str(p.relative_to(ROOT)): script_violations(p) for p in scripts}
    assert {p: v for p, v in found.items() if v and p not in SCRIPT_EXCEPTIONS} == {}
    for p in SCRIPT_EXCEPTIONS:  # an exception no longer needed goes
        if p.startswith(folder + "/"):
            assert found[p], f"{p} no longer needs its exception"
