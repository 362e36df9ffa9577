"""What determines a map: the build's inputs, their fingerprint, and checksums of result blocks.

The *inputs* of a build are the kind, its schema version, the grid (axes, name), the resolved
model options (e.g. the solver resolution actually used), the point solver's name and the
SHA-256 of the source code that computes the results (`SolverSpec.sources` plus the solver's own
module). Their *fingerprint* is the SHA-256 of their canonical JSON. Every checkpoint batch and
every map file carries it: a batch of another build is refused, and `maps build` leaves a map
alone when its recorded fingerprint equals the one it would build.

The per-point time limit is not an input: it decides only whether a slow point ends as
"timeout", never the value of a point that finishes.
"""

from __future__ import annotations

import datetime as _dt
import hashlib
import importlib.util
import json
import subprocess
from pathlib import Path

import numpy as np

REPO = Path(__file__).resolve().parents[1]


def _module_files(name: str) -> list[tuple[str, Path]]:
    """(relative name, path) of the source files of module or package `name`."""
    try:
        spec = importlib.util.find_spec(name)
    except (ImportError, ValueError):
        spec = None
    if spec is None or not spec.origin or spec.origin in ("built-in", "frozen"):
        return []
    origin = Path(spec.origin).resolve()
    if spec.submodule_search_locations:  # a package: every .py below it
        root = Path(list(spec.submodule_search_locations)[0]).resolve()
        files = sorted(p for p in root.rglob("*.py") if "__pycache__" not in p.parts)
        return [(str(Path(root.name, p.relative_to(root)).as_posix()), p) for p in files]
    # named as in the repository (snapmorph.units.planar -> units/planar.py)
    return [("/".join([*name.removeprefix("snapmorph.").split(".")[:-1], origin.name]), origin)]


def source_files(modules) -> list[tuple[str, Path]]:
    """The deduplicated, sorted source files of `modules` (module or package names)."""
    seen = {}
    for m in modules:
        for rel, path in _module_files(m):
            seen.setdefault(str(path), (rel, path))
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
    """The modules whose source determines a build's results: the kind's sources and the
    point solver's own module."""
    mod = getattr(fn, "__module__", None)
    return tuple(dict.fromkeys([*spec.sources, *([mod] if mod else [])]))


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
    }


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
        if key == "message":
            data = "\0".join(str(m) for m in v).encode()
            h.update(f"{key}|str|{len(v)}|".encode() + data)
            continue
        a = np.ascontiguousarray(v)
        h.update(f"{key}|{a.dtype.str}|{a.shape}|".encode())
        h.update(a.tobytes())
    return h.hexdigest()


def source_provenance(modules) -> dict:
    """{"git_commit", "created"} of the model source: the last commit that touched the files of
    `modules` ("+modified" appended when they differ from it) and that commit's date (ISO 8601
    UTC). Not the wall-clock time of the build, so that a rebuild is bit-identical. "unknown"
    without git."""
    files = [p for _, p in source_files(modules)]
    rel = []
    for p in files:
        try:
            rel.append(str(p.relative_to(REPO)))
        except ValueError:
            pass
    unknown = {"git_commit": "unknown", "created": "unknown"}
    if not rel:
        return unknown
    try:
        r = subprocess.run(["git", "log", "-1", "--format=%H %ct", "--", *rel], cwd=REPO,
                           capture_output=True, text=True, timeout=20)
        if r.returncode != 0 or not r.stdout.strip():
            return unknown
        commit, stamp = r.stdout.split()
        dirty = subprocess.run(["git", "status", "--porcelain", "--untracked-files=no", "--", *rel],
                               cwd=REPO, capture_output=True, text=True, timeout=20)
    except (OSError, subprocess.SubprocessError, ValueError):
        return unknown
    created = _dt.datetime.fromtimestamp(int(stamp), _dt.timezone.utc).isoformat()
    if dirty.returncode == 0 and dirty.stdout.strip():
        commit += "+modified"
    return {"git_commit": commit, "created": created}
