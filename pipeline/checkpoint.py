"""Crash-safe checkpoint of a build: a directory `<out>.partial/` of per-batch result files.

Layout:
    build.json          what is being built (grid, solver, start time, versions); written once
    lock                flock-ed while a build runs (released by the kernel even on kill -9)
    batch-*.npz         one finished block each, written to a temp file and os.replace-d in
    *.tmp               leftovers of a write cut short; deleted on the next start

A kill at any moment leaves only whole batch files (os.replace is atomic) and possibly a
temp file, so a restart loses at most the batches that were being computed.
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

from pipeline.batch import BLOCK_KEYS, validate_block
from pipeline.grid import Grid
from pipeline.schema import SCHEMA_VERSION

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


class Checkpoint:
    """The checkpoint of one build; use `Checkpoint.open(...)`."""

    def __init__(self, directory: Path, meta: dict, lock_fd: int):
        self.dir = directory
        self.meta = meta
        self._lock_fd = lock_fd

    @classmethod
    def open(cls, out, grid: Grid, solver: str, new_meta: dict, restart: bool = False) -> "Checkpoint":
        """Open (resume) or create the checkpoint of `out`.

        new_meta: the "created", "package_version", "git_commit" to record if starting afresh,
        and the "resolution" the solver will use (must match when resuming).
        restart: discard an existing checkpoint. Raises CheckpointError if the existing one was
        made for another grid or solver, or if another build holds it.
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
            wanted = {"schema_version": SCHEMA_VERSION, "grid": grid.to_dict(), "solver": solver,
                      "resolution": new_meta.get("resolution", grid.resolution)}
            meta_path = d / META
            if meta_path.exists():
                meta = json.loads(meta_path.read_text())
                for key, value in wanted.items():
                    if meta.get(key) != value:
                        raise CheckpointError(
                            f"checkpoint {d} was started with another {key} ({meta.get(key)!r}, now "
                            f"{value!r}); pass restart=True (--restart) to discard it")
                for key in ("package_version", "git_commit"):
                    if meta.get(key) != new_meta.get(key):
                        warnings.warn(
                            f"resuming {d}: it was started with {key} {meta.get(key)!r}, now "
                            f"{new_meta.get(key)!r}; the map records the start's value", stacklevel=2)
            else:
                meta = {**wanted, **new_meta}
                atomic_write(meta_path, lambda f: f.write(json.dumps(meta, indent=1).encode()))
        except BaseException:
            os.close(fd)
            raise
        return cls(d, meta, fd)

    def load(self, n_points: int, samples: int) -> list[dict]:
        """The finished blocks. An unreadable or malformed file is deleted (its points are
        recomputed) with a warning."""
        blocks = []
        for p in sorted(self.dir.glob("batch-*.npz")):
            try:
                with np.load(p, allow_pickle=False) as z:
                    block = {k: z[k] for k in BLOCK_KEYS}
                block["message"] = block["message"].astype(object)
                validate_block(block, n_points, samples)
            except Exception as exc:
                warnings.warn(f"ignoring unreadable checkpoint file {p}: {exc}", stacklevel=2)
                p.unlink(missing_ok=True)
                continue
            blocks.append(block)
        return blocks

    def write(self, block: dict) -> Path:
        """Write one finished block atomically; returns its path."""
        first = int(block["index"][0])
        path = self.dir / f"batch-{first:07d}-{uuid.uuid4().hex[:8]}.npz"
        arrays = {k: block[k] for k in BLOCK_KEYS}
        arrays["message"] = np.asarray([str(m) for m in block["message"]], dtype=str)
        atomic_write(path, lambda f: np.savez(f, **arrays))
        return path

    def close(self) -> None:
        """Release the lock (the files stay)."""
        if self._lock_fd is not None:
            os.close(self._lock_fd)
            self._lock_fd = None

    def remove(self) -> None:
        """Delete the checkpoint (after the final map is in place)."""
        self.close()
        shutil.rmtree(self.dir, ignore_errors=True)
