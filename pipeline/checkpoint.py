"""Crash-safe checkpoint of a build: a directory `<out>.partial/` of per-batch result files
that prove where they came from.

Layout:
    build.json          what is being built (kind, grid, solver, inputs and their fingerprint,
                        provenance); written once
    lock                flock-ed while a build runs (released by the kernel even on kill -9)
    batch-*.npz         one finished block each, written to a temp file and os.replace-d in;
                        it carries the build's fingerprint and a SHA-256 of its arrays
    refused-*.npz       batch files that were refused (kept until the map is written)
    *.tmp               leftovers of a write cut short; deleted on the next start

A kill at any moment leaves only whole batch files (os.replace is atomic) and possibly a
temp file, so a restart loses at most the batches that were being computed. On resume a batch
file is used only if its fingerprint is this build's, its checksum matches its arrays, its
coordinates are the grid's at its indices, its status codes are known and its "ok" values
finite (`pipeline.batch.check_block`), and no other batch disagrees with it about a point;
otherwise it is refused with a warning and its points are recomputed.
"""

from __future__ import annotations

import fcntl
import json
import os
import shutil
import uuid
import warnings
from pathlib import Path

import numpy as np

from snapmorph.pipeline.batch import check_block
from snapmorph.pipeline.fingerprint import block_checksum, differences

META = "build.json"


def checkpoint_dir(out) -> Path:
    """The checkpoint directory of the map file `out`."""
    out = Path(out)
    return out.with_name(out.name + ".partial")


def _fsync_dir(path: Path) -> None:
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def atomic_write(path: Path, write) -> None:
    """Call write(fileobj) on a temp file next to `path`, fsync it, and os.replace it into place."""
    path = Path(path)
    tmp = path.with_name(f".{path.name}.{uuid.uuid4().hex[:8]}.tmp")
    try:
        with open(tmp, "wb") as f:
            write(f)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()
    _fsync_dir(path.parent)


class CheckpointError(ValueError):
    """The checkpoint belongs to another build, or another build is using it."""


def _same_rows(a: dict, ia, b: dict, ib, keys) -> bool:
    """Whether rows ia of block a equal rows ib of block b in every key (NaN equal to NaN)."""
    for key in keys:
        x, y = np.asarray(np.asarray(a[key])[ia]), np.asarray(np.asarray(b[key])[ib])
        if x.dtype.kind == "f" or y.dtype.kind == "f":
            if not np.array_equal(x, y, equal_nan=True):
                return False
        elif not np.array_equal(x, y):
            return False
    return True


class Checkpoint:
    """The checkpoint of one build; use `Checkpoint.open(...)`."""

    def __init__(self, directory: Path, meta: dict, lock_fd: int, spec=None):
        self.dir = directory
        self.meta = meta
        self._lock_fd = lock_fd
        self.spec = spec
        self.refused: list[tuple[str, str]] = []  # (file name, reason) refused by load()

    @property
    def fingerprint(self) -> str:
        return self.meta["fingerprint"]

    @classmethod
    def open(cls, out, grid, solver: str, new_meta: dict, restart: bool = False, *,
             spec, inputs: dict, fingerprint: str) -> "Checkpoint":
        """Open (resume) or create the checkpoint of `out` (`pipeline.build.open_checkpoint`
        computes the arguments).

        new_meta: provenance to record if starting afresh ("created", "package_version",
        "git_commit") and the "resolution" the solver will use; spec / inputs / fingerprint:
        the kind and the build's inputs (`pipeline.fingerprint`). restart: discard an existing
        checkpoint. Raises CheckpointError if the existing one was made for other inputs, or if
        another build holds it.
        """
        d = checkpoint_dir(out)
        d.mkdir(parents=True, exist_ok=True)
        fd = os.open(d / "lock", os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            os.close(fd)
            raise CheckpointError(f"another build is writing {out} (checkpoint {d} is locked)") from None
        try:
            for p in d.iterdir():
                if p.name.endswith(".tmp") or (restart and p.name != "lock"):
                    shutil.rmtree(p) if p.is_dir() else p.unlink()
            out = Path(out)
            for p in out.parent.glob(f".{out.name}.*.partial"):  # final write cut short
                p.unlink(missing_ok=True)
            wanted = {"schema_version": spec.schema_version, "grid": grid.to_dict(), "solver": solver,
                      "resolution": new_meta.get("resolution", getattr(grid, "resolution", None))}
            meta_path = d / META
            if meta_path.exists():
                meta = json.loads(meta_path.read_text())
                for key, value in wanted.items():
                    if meta.get(key) != value:
                        raise CheckpointError(
                            f"checkpoint {d} was started with another {key} ({meta.get(key)!r}, now "
                            f"{value!r}); pass restart=True (--restart) to discard it")
                if meta.get("fingerprint") != fingerprint:
                    which = ", ".join(differences(meta.get("inputs") or {}, inputs)) or "inputs"
                    raise CheckpointError(
                        f"checkpoint {d} was started with other inputs (differing: {which}); "
                        f"pass restart=True (--restart) to discard it")
            else:
                meta = {**wanted, "kind": spec.name, "inputs": inputs, "fingerprint": fingerprint,
                        **new_meta}
                atomic_write(meta_path, lambda f: f.write(json.dumps(meta, indent=1).encode()))
        except BaseException:
            os.close(fd)
            raise
        return cls(d, meta, fd, spec)

    # -- batches ---------------------------------------------------------------------------
    def _refuse(self, path: Path, reason: str) -> None:
        warnings.warn(f"refusing checkpoint file {path}: {reason}; its points will be recomputed",
                      stacklevel=3)
        self.refused.append((path.name, reason))
        if path.exists():
            os.replace(path, path.with_name("refused-" + path.name))

    def load(self, points: np.ndarray, options: dict) -> list[dict]:
        """The trustworthy finished blocks for a grid with points `points` ((N, ndim)).

        A file that is unreadable, of another build, altered, implausible or in conflict with
        another file about a point is refused (renamed refused-*, a warning) and its points are
        recomputed. Nothing is deleted here."""
        spec = self.spec
        keys = spec.block_keys()
        blocks, paths = [], []
        for p in sorted(self.dir.glob("batch-*.npz")):
            try:
                with np.load(p, allow_pickle=False) as z:
                    if "fingerprint" not in z or "checksum" not in z:
                        raise ValueError("no fingerprint or checksum (written by an older snapmorph)")
                    fp, checksum = str(z["fingerprint"]), str(z["checksum"])
                    missing = [k for k in keys if k not in z]
                    if missing:
                        raise ValueError(f"missing keys {missing}")
                    block = {k: z[k] for k in keys}
            except Exception as exc:
                self._refuse(p, f"unreadable ({exc})")
                continue
            for k in spec.text_keys:
                block[k] = block[k].astype(object)
            if fp != self.fingerprint:
                self._refuse(p, f"it belongs to another build (fingerprint {fp[:12]}, this build "
                                f"{self.fingerprint[:12]})")
                continue
            if block_checksum(block, keys) != checksum:
                self._refuse(p, "its values do not match its checksum (altered or damaged)")
                continue
            try:
                check_block(block, spec, options, points)
            except ValueError as exc:
                self._refuse(p, str(exc))
                continue
            blocks.append(block)
            paths.append(p)
        # two files about the same point must agree, else neither is trusted
        owner = np.full(len(points), -1)
        row = np.full(len(points), -1)
        compared = [k for k in keys if k not in ("index", "solve_time", "message")]
        conflicts = set()
        for b, block in enumerate(blocks):
            idx = block["index"]
            for k, i in enumerate(idx):
                a = owner[i]
                if a >= 0 and not _same_rows(blocks[a], row[i], block, k, compared):
                    conflicts.update((a, b))
                owner[i], row[i] = b, k
        for b in sorted(conflicts):
            self._refuse(paths[b], "it disagrees with another batch file about the same points")
        return [blk for b, blk in enumerate(blocks) if b not in conflicts]

    def write(self, block: dict) -> Path:
        """Write one finished block atomically, with this build's fingerprint and a checksum of
        its arrays; returns its path."""
        keys = self.spec.block_keys()
        first = int(block["index"][0])
        path = self.dir / f"batch-{first:07d}-{uuid.uuid4().hex[:8]}.npz"
        arrays = {k: block[k] for k in keys}
        for k in self.spec.text_keys:
            arrays[k] = np.asarray([str(m) for m in block[k]], dtype=str)
        arrays["fingerprint"] = np.asarray(self.fingerprint)
        arrays["checksum"] = np.asarray(block_checksum(arrays, keys))
        atomic_write(path, lambda f: np.savez(f, **arrays))
        return path

    def close(self) -> None:
        """Release the lock (the files stay)."""
        if self._lock_fd is not None:
            os.close(self._lock_fd)
            self._lock_fd = None

    def remove(self) -> None:
        """Delete the checkpoint (after the final map is in place and checked)."""
        self.close()
        shutil.rmtree(self.dir, ignore_errors=True)
