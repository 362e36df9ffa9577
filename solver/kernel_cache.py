"""Keep numba's on-disk kernel cache consistent with the sources of this package.

Numba checks a cached function against its own source file only, not against the files of
the functions it calls: after an edit of `solver.banded`, the cached kernels of
`solver.iteration` (which inline its factorisation) would go on running the old code, and
the same input would give different numbers depending on what was cached. All cached
kernels live in this package, so when any of its sources changes, every cached kernel is
discarded (recompiled at first use). Covers numba's default cache location (the package's
``__pycache__``), not a ``NUMBA_CACHE_DIR`` set elsewhere.
"""

from __future__ import annotations

import hashlib
import os
import pathlib

HERE = pathlib.Path(__file__).resolve().parent
STAMP = "kernel-sources.sha256"


def sources_digest(package_dir=HERE) -> str:
    """SHA-256 over the names and contents of the package's ``*.py`` files."""
    h = hashlib.sha256()
    for path in sorted(pathlib.Path(package_dir).glob("*.py")):
        h.update(path.name.encode())
        h.update(path.read_bytes())
    return h.hexdigest()


def discard_stale_kernels(package_dir=HERE) -> bool:
    """Delete the cached kernels (``*.nbi``, ``*.nbc``) in ``package_dir/__pycache__`` when
    the sources differ from those the stamp there records, and record the current ones.
    Returns True when the cache was discarded. Never raises for file-system trouble (a
    read-only install simply keeps numba's own behaviour)."""
    cache = pathlib.Path(package_dir) / "__pycache__"
    stamp = cache / STAMP
    digest = sources_digest(package_dir)
    try:
        if stamp.read_text() == digest:
            return False
    except OSError:
        pass
    for pattern in ("*.nbi", "*.nbc"):
        for f in cache.glob(pattern):
            try:
                f.unlink()
            except OSError:
                pass
    try:
        cache.mkdir(exist_ok=True)
        tmp = cache / f"{STAMP}.{os.getpid()}.tmp"
        tmp.write_text(digest)
        os.replace(tmp, stamp)  # atomic: concurrent importers see one stamp or the other
    except OSError:
        pass
    return True
