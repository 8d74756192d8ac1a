"""The layer rule of armlab: imports run only down the layer order, and no module imports itself
back through another (docs: ../shared/STYLE.md, "The shape of the house").

Every module under ``armlab/`` is parsed with ``ast``; every import counts, including imports
nested in functions and ``TYPE_CHECKING`` blocks, and relative imports. There is no allow-list.
"""

from __future__ import annotations

import ast
from collections.abc import Mapping
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1] / "armlab"

# Lowest first. A module takes the level of the longest name here that is it or a package above it,
# but ``armlab`` places armlab/__init__.py alone: a module under no other name here is a failure.
LAYERS: dict[str, int] = {
    "armlab": 0,
    "armlab.errors": 0,
    "armlab.cpus": 0,
    "armlab.progress": 0,
    "armlab.config": 0,
    "armlab.dsp": 0,
    "armlab.noise": 0,
    "armlab.models": 1,
    "armlab.perturbations": 2,
    "armlab.sensors": 2,
    "armlab.sim": 3,
    "armlab.data": 4,
    "armlab.estimation": 5,
    "armlab.diagnosis": 6,
    "armlab.protocols": 7,
    "armlab.reproduction": 8,
    "armlab.viz": 9,
    "armlab.cli": 10,
    "armlab.runner": 10,
    "armlab.api": 10,
}
# The one import allowed to run upward: the package's face offers the notebook API
# (armlab.run / load_run / diagnose) through a module __getattr__, imported on first use only, so
# that importing any module of armlab (which runs armlab/__init__.py) stays light.
LAZY_FACE = ("armlab", "armlab.api")


def scan(root: Path = ROOT) -> tuple[dict[str, str], set[str]]:
    """Sources of every module below ``root`` by dotted name, and the names that are packages."""
    sources: dict[str, str] = {}
    packages: set[str] = set()
    for path in sorted(root.rglob("*.py")):
        parts = (root.name, *path.relative_to(root).with_suffix("").parts)
        if parts[-1] == "__init__":
            parts = parts[:-1]
            packages.add(".".join(parts))
        sources[".".join(parts)] = path.read_text(encoding="utf-8")
    return sources, packages


def imports_of(name: str, source: str, packages: set[str], known: set[str]) -> set[str]:
    """The modules ``name`` imports: ``from p import m`` counts as ``p.m`` where that is a module."""
    package = name if name in packages else name.rpartition(".")[0]
    found: set[str] = set()
    for node in ast.walk(ast.parse(source)):
        if isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")[: len(package.split(".")) - node.level + 1]
                base = ".".join([*base, node.module] if node.module else base)
            else:
                base = node.module
            for alias in node.names:
                sub = f"{base}.{alias.name}"
                found.add(sub if sub in known else base)
    root = name.split(".")[0]
    return {m for m in found if m == root or m.startswith(root + ".")}


def level_of(module: str, layers: Mapping[str, int]) -> int | None:
    """The level of the longest name in ``layers`` that is ``module`` or a package above it, the top
    package excepted (its level is its ``__init__``'s alone); None where there is none."""
    if module in layers:
        return layers[module]
    parts = module.split(".")
    for n in range(len(parts) - 1, 1, -1):
        level = layers.get(".".join(parts[:n]))
        if level is not None:
            return level
    return None


def circles(graph: Mapping[str, set[str]]) -> list[list[str]]:
    """Strongly connected components of two or more modules (Tarjan), each sorted, sorted."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return sorted(found)


def violations(sources: Mapping[str, str], packages: set[str], layers: Mapping[str, int]) -> list[str]:
    """One line per unplaced module, per upward import and per circle; empty when the rule holds."""
    known = set(sources)
    graph = {name: imports_of(name, src, packages, known) - {name} for name, src in sources.items()}
    problems = [f"{m} is in no layer" for m in sorted(known) if level_of(m, layers) is None]
    for importer in sorted(graph):
        a = level_of(importer, layers)
        for imported in sorted(graph[importer]):
            b = level_of(imported, layers)
            if b is None and imported not in known:
                problems.append(f"{importer} -> {imported} (imports a module in no layer)")
            elif a is not None and b is not None and b > a:
                problems.append(f"{importer} -> {imported} (level {a} -> level {b})")
    for component in circles(graph):
        members = set(component)
        edges = [f"{v} -> {w}" for v in component for w in sorted(graph[v]) if w in members]
        problems.append(f"circle among {', '.join(component)}: {'; '.join(edges)}")
    return problems


def test_checker_reports_upward_imports_circles_and_unplaced_modules():
    sources = {
        "pkg": "from pkg.low import f\n",
        "pkg.low": "def f():\n    from pkg.high import g\n",
        "pkg.high": "import pkg.low\n",
        "pkg.side": "from . import low\n",
        "pkg.stray": "",
        "pkg.sub": "from pkg.sub.a import x\n",
        "pkg.sub.a": "from pkg.sub import y\n",  # back through its package's __init__
    }
    layers = {"pkg": 0, "pkg.low": 0, "pkg.side": 0, "pkg.sub": 0, "pkg.high": 1}
    assert violations(sources, {"pkg", "pkg.sub"}, layers) == [
        "pkg.stray is in no layer",
        "pkg.low -> pkg.high (level 0 -> level 1)",
        "circle among pkg.high, pkg.low: pkg.high -> pkg.low; pkg.low -> pkg.high",
        "circle among pkg.sub, pkg.sub.a: pkg.sub -> pkg.sub.a; pkg.sub.a -> pkg.sub",
    ]


def test_imports_resolve_relative_and_submodule_names():
    known = {"pkg", "pkg.a", "pkg.a.b", "pkg.a.c", "pkg.d"}
    source = "import os\nfrom . import c\nfrom .c import X\nfrom .. import d\nfrom pkg.a import Y\n"
    assert imports_of("pkg.a.b", source, {"pkg", "pkg.a"}, known) == {"pkg.a.c", "pkg.d", "pkg.a"}
    assert imports_of("pkg.a", "from . import b\n", {"pkg", "pkg.a"}, known) == {"pkg.a.b"}


def test_armlab_layers():
    sources, packages = scan()
    assert "armlab.errors" in sources and "armlab" in packages
    face, api = LAZY_FACE
    top_level = {n.module for n in ast.parse(sources[face]).body if isinstance(n, ast.ImportFrom)}
    assert api not in top_level  # only inside __getattr__, on first use
    allowed = f"{face} -> {api} (level {LAYERS[face]} -> level {LAYERS[api]})"
    problems = [p for p in violations(sources, packages, LAYERS) if p != allowed]
    assert not problems, f"{len(problems)} layer violations:\n" + "\n".join(problems)


def sibling_imports(sources: Mapping[str, str], packages: set[str], parent: str) -> list[str]:
    """Imports from one package below ``parent`` into another one below it (``a.x -> b.y``)."""
    known = set(sources)
    depth = len(parent.split(".")) + 1
    found = []
    for name, src in sorted(sources.items()):
        if not name.startswith(parent + ".") or len(name.split(".")) < depth:
            continue
        own = ".".join(name.split(".")[:depth])
        if own not in packages:  # a module beside the packages (the registry, the interface)
            continue
        for imported in sorted(imports_of(name, src, packages, known)):
            other = ".".join(imported.split(".")[:depth])
            if imported.startswith(parent + ".") and other in packages and other != own:
                found.append(f"{name} -> {imported}")
    return found


def test_sibling_check_reports_one_protocol_importing_another():
    sources = {
        "pkg.protocols": "",
        "pkg.protocols.base": "",
        "pkg.protocols.a": "from pkg.protocols.base import P\n",
        "pkg.protocols.a.x": "from pkg.protocols.b.y import f\n",
        "pkg.protocols.b": "",
        "pkg.protocols.b.y": "from pkg.protocols.a import x\n",
        "pkg.protocols.registry": "from pkg.protocols import a, b\n",
    }
    packages = {"pkg.protocols", "pkg.protocols.a", "pkg.protocols.b"}
    assert sibling_imports(sources, packages, "pkg.protocols") == [
        "pkg.protocols.a.x -> pkg.protocols.b.y",
        "pkg.protocols.b.y -> pkg.protocols.a.x",
    ]


def test_protocol_packages_do_not_import_each_other():
    # each protocol is a plug-in: it may use the interface, the core and the layers below, never
    # another protocol (the registry, at protocols level, imports them all and is no package)
    sources, packages = scan()
    assert sibling_imports(sources, packages, "armlab.protocols") == []
