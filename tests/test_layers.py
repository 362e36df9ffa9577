"""The import layers: data flows one way, solver <- units <- pipeline -> maps <- design <- snapmorph.

Every module of the installed packages is read with `ast` (imports inside functions
included, and ``importlib.import_module("...")`` with a literal name): a module may import
only from its own layer and from the layers below it, and no two files may import each other,
directly or around a loop. The package root ``snapmorph/__init__.py`` belongs to the top layer;
the old-name aliases (``legacy/``) are no part of the library.
"""

from __future__ import annotations

import ast
from pathlib import Path


ROOT = Path(__file__).resolve().parents[1]

#: folder of the repository -> its import name
PACKAGES = {"solver": "snapmorph.solver", "units": "snapmorph.units",
            "pipeline": "snapmorph.pipeline", "maps": "snapmorph.maps",
            "design": "snapmorph.design", "snapmorph": "snapmorph"}

#: layer -> the layers it may import (besides itself and the root)
MAY_IMPORT = {
    "solver": set(),
    "units": {"solver"},
    "maps": set(),
    "pipeline": {"solver", "units", "maps"},
    "design": {"solver", "units", "maps"},
    "snapmorph": {"solver", "units", "maps", "pipeline", "design"},
}


def library_modules() -> dict[str, Path]:
    """import name -> file, for every module of the installed packages."""
    out = {}
    for folder, name in PACKAGES.items():
        for path in sorted((ROOT / folder).rglob("*.py")):
            rel = path.relative_to(ROOT / folder).with_suffix("")
            parts = [p for p in rel.parts if p != "__init__"]
            out[".".join([name, *parts])] = path
    return out


def layer_of(module: str) -> str | None:
    """The layer of a project module name (None: not the project's)."""
    if not (module == "snapmorph" or module.startswith("snapmorph.")):
        return None
    parts = module.split(".")
    return parts[1] if len(parts) > 1 and parts[1] in MAY_IMPORT else "snapmorph"


def imports_of(module: str, path: Path, known: set[str]) -> list[tuple[int, str]]:
    """(line, imported project module) of every import in a file, lazy ones included."""
    tree = ast.parse(path.read_text(), filename=str(path))
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    found = []

    def add(line, name):
        # the longest known module the name starts with (a name imported from a package
        # may be a submodule or an attribute)
        while name and name not in known:
            name = name.rpartition(".")[0]
        if name:
            found.append((line, name))

    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for a in node.names:
                add(node.lineno, a.name)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")
                anchor = anchor[:len(anchor) - node.level + 1]
                base = ".".join([*anchor, *([base] if base else [])])
            for a in node.names:
                add(node.lineno, f"{base}.{a.name}" if f"{base}.{a.name}" in known else base)
        elif (isinstance(node, ast.Call) and getattr(node.func, "attr", getattr(node.func, "id", None))
              == "import_module" and node.args and isinstance(node.args[0], ast.Constant)
              and isinstance(node.args[0].value, str)):
            add(node.lineno, node.args[0].value)
    return sorted(set(found))


def import_graph():
    mods = library_modules()
    known = set(mods)
    return mods, {m: imports_of(m, p, known) for m, p in mods.items()}


def test_every_import_follows_the_flow():
    mods, graph = import_graph()
    wrong = []
    for m, edges in graph.items():
        own = layer_of(m)
        for line, target in edges:
            other = layer_of(target)
            if not (other is None or other == own or other in MAY_IMPORT[own]):
                wrong.append(f"{mods[m].relative_to(ROOT)}:{line}: {m} ({own}) imports {target} ({other})")
    assert not wrong, "imports against the flow:\n" + "\n".join(sorted(wrong))


def test_no_files_import_each_other():
    mods, graph = import_graph()
    edges = {m: sorted({t for _, t in e if t != m}) for m, e in graph.items()}
    cycles = _cycles(edges)
    text = ["  " + " -> ".join(str(mods[m].relative_to(ROOT)) for m in c) for c in cycles]
    assert not cycles, "files that import each other (strongly connected):\n" + "\n".join(text)


def _cycles(edges):
    """The strongly connected components with more than one file (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []

    def visit(v):
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in edges.get(v, ()):
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
            if len(comp) > 1:
                out.append(sorted(comp))

    for v in sorted(edges):
        if v not in index:
            visit(v)
    return out


def test_the_checker_sees_lazy_imports_and_cycles(tmp_path):
    """The checks themselves can fail: a lazy import against the flow and a two-file loop."""
    (tmp_path / "a.py").write_text("def f():\n    from snapmorph.design.units import Unit\n")
    found = imports_of("snapmorph.solver.a", tmp_path / "a.py",
                       {"snapmorph.design.units", "snapmorph.solver.a"})
    assert found == [(2, "snapmorph.design.units")]
    assert layer_of("snapmorph.design.units") not in MAY_IMPORT[layer_of("snapmorph.solver.a")]
    assert _cycles({"x": ["y"], "y": ["x"], "z": ["x"]}) == [["x", "y"]]
