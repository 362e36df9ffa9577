"""The kernel-cache guard: cached kernels go when any source of the package changes."""

from snapmorph import solver
from snapmorph.solver.kernel_cache import STAMP, discard_stale_kernels, sources_digest


def _package(tmp_path):
    (tmp_path / "a.py").write_text("x = 1\n")
    (tmp_path / "b.py").write_text("y = 2\n")
    cache = tmp_path / "__pycache__"
    cache.mkdir()
    return cache


def test_a_source_edit_discards_every_cached_kernel(tmp_path):
    cache = _package(tmp_path)
    (cache / "a.f-1.py311.nbi").write_text("index")
    (cache / "a.f-1.py311.1.nbc").write_text("code")
    (cache / "a.cpython-311.pyc").write_text("bytecode")
    assert discard_stale_kernels(tmp_path)  # no stamp yet: nothing is known to match
    assert sorted(p.name for p in cache.iterdir()) == ["a.cpython-311.pyc", STAMP]
    (cache / "b.g-2.py311.nbi").write_text("index")  # compiled against these sources
    assert not discard_stale_kernels(tmp_path)
    assert (cache / "b.g-2.py311.nbi").exists()
    # an edit of another file than the cached kernel's own (numba would keep it)
    (tmp_path / "a.py").write_text("x = 3\n")
    assert discard_stale_kernels(tmp_path)
    assert not (cache / "b.g-2.py311.nbi").exists()
    assert (cache / STAMP).read_text() == sources_digest(tmp_path)


def test_importing_the_solver_records_its_sources():
    from pathlib import Path

    pkg = Path(solver.__file__).parent
    assert (pkg / "__pycache__" / STAMP).read_text() == sources_digest(pkg)
