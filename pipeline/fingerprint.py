"""What determines a map: the build's inputs, their fingerprint, and checksums of result blocks.

The *inputs* of a build are the kind, its schema version, the grid (axes, name), the resolved
model options (e.g. the solver resolution actually used), the point solver's name and the
SHA-256 of the source code that computes the results: `SolverSpec.sources`, the solver's own
module and the pipeline modules that check records and write the file (`CORE`), with every
module they import, directly or lazily, inside the project (`source_files`). Their
*fingerprint* is the SHA-256 of their canonical JSON. Every checkpoint batch and every map file
carries it: a batch of another build is refused, and `maps build` leaves a map alone when its
recorded fingerprint equals the one it would build.

The per-point time limit is not an input: it decides only whether a slow point ends as
"timeout", never the value of a point that finishes.
"""

from __future__ import annotations

import ast
import hashlib
import importlib.util
import json
from importlib import metadata
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]
#: the pipeline modules whose source decides a map's values and bytes whatever its kind: the
#: record check (`SolverSpec.finalise_record`), the result blocks and the file's assembly
CORE = ("snapmorph.pipeline.solvers", "snapmorph.pipeline.batch", "snapmorph.pipeline.dataset")
ROOT_PACKAGE = "snapmorph"


def _find(name: str):
    try:
        return importlib.util.find_spec(name)
    except (ImportError, ValueError):
        return None


def _rel(name: str, path: Path) -> str:
    """A source file's name as in the repository (snapmorph.units.planar -> units/planar.py)."""
    return "/".join([*name.removeprefix(ROOT_PACKAGE + ".").split(".")[:-1], path.name])


def _module_files(name: str) -> list[tuple[str, str, Path]]:
    """(module name, relative name, path) of the source files of module or package `name`
    (a package: every .py below it)."""
    spec = _find(name)
    if spec is None or not spec.origin or spec.origin in ("built-in", "frozen"):
        return []
    origin = Path(spec.origin).resolve()
    if origin.suffix != ".py":
        return []
    if not spec.submodule_search_locations:
        return [(name, _rel(name, origin), origin)]
    root = Path(list(spec.submodule_search_locations)[0]).resolve()
    out = []
    for p in sorted(p for p in root.rglob("*.py") if "__pycache__" not in p.parts):
        parts = p.relative_to(root).with_suffix("").parts
        module = ".".join([name, *(q for q in parts if q != "__init__")])
        out.append((module, str(Path(root.name, p.relative_to(root)).as_posix()), p))
    return out


def _imports(module: str, path: Path) -> set[str]:
    """The names a source file imports (lazy imports and ``importlib.import_module("...")``
    with a literal name included), relative imports resolved."""
    try:
        tree = ast.parse(path.read_text(), filename=str(path))
    except (OSError, SyntaxError, ValueError):
        return set()
    package = module if path.name == "__init__.py" else module.rpartition(".")[0]
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(a.name for a in node.names)
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                anchor = package.split(".")[:len(package.split(".")) - node.level + 1]
                base = ".".join([*anchor, *([base] if base else [])])
            # a submodule, or an attribute of `base` (`_target` tells them apart)
            names.update(f"{base}.{a.name}" for a in node.names)
        elif (isinstance(node, ast.Call) and node.args and isinstance(node.args[0], ast.Constant)
              and isinstance(node.args[0].value, str)
              and getattr(node.func, "attr", getattr(node.func, "id", None)) == "import_module"):
            names.add(node.args[0].value)
    return names


def _target(name: str) -> str | None:
    """The module an imported name stands for: itself, or the module it is an attribute of."""
    while name:
        if _find(name) is not None:
            return name
        name = name.rpartition(".")[0]
    return None


def source_files(modules) -> list[tuple[str, Path]]:
    """The deduplicated, sorted (relative name, path) of the source files of `modules`
    (module or package names) and of every module they import from the same top-level
    package or from snapmorph, transitively; a package imported is taken whole, and the
    ``__init__`` of each package above a module (below the snapmorph root) is included."""
    tops = {m.partition(".")[0] for m in modules} | {ROOT_PACKAGE}
    seen: dict[str, tuple[str, Path]] = {}
    done, todo = set(), list(modules)
    while todo:
        name = todo.pop()
        if name in done:
            continue
        done.add(name)
        parent = name.rpartition(".")[0]
        while parent and parent != ROOT_PACKAGE:
            spec = _find(parent)
            if spec is not None and spec.origin and spec.origin.endswith(".py"):
                path = Path(spec.origin).resolve()
                seen.setdefault(str(path), (_rel(parent + ".__init__", path), path))
            parent = parent.rpartition(".")[0]
        for module, rel, path in _module_files(name):
            seen.setdefault(str(path), (rel, path))
            for imported in _imports(module, path):
                if imported.partition(".")[0] in tops and imported != ROOT_PACKAGE:
                    target = _target(imported)
                    if target and target != ROOT_PACKAGE and target not in done:
                        todo.append(target)
    return sorted(seen.values())


def source_hash(modules) -> str:
    """SHA-256 over the relative names and bytes of the source files of `modules`."""
    h = hashlib.sha256()
    for rel, path in source_files(modules):
        h.update(rel.encode() + b"\0")
        h.update(path.read_bytes())
        h.update(b"\0")
    return h.hexdigest()


def solver_modules(spec, fn) -> tuple:
    """The modules whose source determines a build's results: the kind's sources, the point
    solver's own module and the pipeline's `CORE` (each with what it imports: `source_files`)."""
    mod = getattr(fn, "__module__", None)
    return tuple(dict.fromkeys([*spec.sources, *([mod] if mod else []), *CORE]))


def canonical(obj) -> str:
    """Canonical JSON (sorted keys, no spaces); floats as repr, so exact values survive."""
    return json.dumps(obj, sort_keys=True, separators=(",", ":"), default=_json_default)


def _json_default(v):
    if isinstance(v, np.integer):
        return int(v)
    if isinstance(v, np.floating):
        return float(v)
    if isinstance(v, np.ndarray):
        return v.tolist()
    raise TypeError(f"{type(v).__name__} is not JSON-able")


def build_inputs(spec, grid, options: dict, solver: str, source_sha256: str) -> dict:
    """The inputs that determine a map (see the module docstring)."""
    return {
        "kind": spec.name,
        "schema_version": int(spec.schema_version),
        "grid": {"name": grid.name, "axes": {d: list(v) for d, v in grid.axes.items()}},
        "model_options": json.loads(canonical(options)),
        "solver": solver,
        "solver_source_sha256": source_sha256,
        # the version the file states is an input too, so that it cannot change the bytes of
        # a map that is up to date
        "package_version": package_version(),
    }


#: the package version recorded in a map when the installed metadata says none
UNKNOWN_VERSION = "unknown"


def package_version() -> str:
    """The installed snapmorph's version (its distribution metadata)."""
    try:
        return metadata.version("snapmorph")
    except metadata.PackageNotFoundError:
        return UNKNOWN_VERSION


def fingerprint(inputs: dict) -> str:
    """SHA-256 of the canonical JSON of `inputs`."""
    return hashlib.sha256(canonical(inputs).encode()).hexdigest()


def differences(recorded: dict, wanted: dict) -> list[str]:
    """The top-level input names whose values differ (for messages)."""
    keys = sorted(set(recorded) | set(wanted))
    return [k for k in keys if canonical(recorded.get(k)) != canonical(wanted.get(k))]


def block_checksum(block: dict, keys) -> str:
    """SHA-256 over the named arrays of a block: key, dtype, shape and bytes (messages as UTF-8)."""
    h = hashlib.sha256()
    for key in keys:
        v = block[key]
        if key == "message" or np.asarray(v).dtype.kind in "OU":
            data = "\0".join(str(m) for m in v).encode()
            h.update(f"{key}|str|{len(v)}|".encode() + data)
            continue
        a = np.ascontiguousarray(v)
        h.update(f"{key}|{a.dtype.str}|{a.shape}|".encode())
        h.update(a.tobytes())
    return h.hexdigest()


#: what a map says of its own build: "created" and "git_commit" are not recorded (the date,
#: the checkout and whether it was modified change between builds of the same inputs and
#: would make a rebuild differ from the committed file); `build_inputs`, `inputs_sha256` and
#: `solver_source_sha256` say what determined the map
RECORDED_PROVENANCE = {"created": "unknown",
                       "git_commit": "not recorded (a map records its inputs: see solver_source_sha256)"}
