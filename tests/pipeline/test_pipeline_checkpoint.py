"""Checkpoints that prove their origin: every corrupted, foreign, duplicated or implausible batch
file is refused (with a warning) and its points recomputed, and the final map equals an
uninterrupted build byte for byte."""

import dataclasses
import shutil

import numpy as np
import pytest

import fake_unit_solver as fake
from pipeline_testing import FAKE, assert_matches_fake, fake_kind, load, sha, solve_batch
from snapmorph.pipeline.build import build_map, open_checkpoint
from snapmorph.pipeline.checkpoint import checkpoint_dir
from snapmorph.pipeline.fingerprint import block_checksum
from snapmorph.pipeline import preset
from snapmorph.pipeline.solvers import get_spec

from pipeline_testing import CI  # noqa: E402  (the three-axis CI grid of the fake solver)
COORDS = CI.points()
KEYS = get_spec("unit").block_keys()
KIND = fake_kind()
BATCHES = (np.arange(0, 6), np.arange(6, 12), np.arange(12, 18))  # 18 of 24 points checkpointed


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """An uninterrupted build of the CI grid with the fake solver."""
    out = tmp_path_factory.mktemp("ref") / "ci.nc"
    build_map(CI, out, kind=KIND, solve=FAKE, workers=1, progress=False)
    return out


def checkpointed(out, grid=CI, batches=BATCHES):
    """A checkpoint of `out` holding `batches`, as an interrupted build leaves it; their files."""
    ckpt = open_checkpoint(out, grid, FAKE, kind=KIND)
    opts = grid.options
    files = [ckpt.write(solve_batch(idx, COORDS[idx], opts["b_over_L"], ckpt.meta["resolution"],
                                    opts["samples"], fake.solve)) for idx in batches]
    ckpt.close()
    return files


def read(path):
    with np.load(path, allow_pickle=False) as z:
        return {k: z[k] for k in z.files}


def rewrite(path, arrays, forge_checksum):
    """Write `arrays` back; with forge_checksum the checksum is recomputed, as a buggy writer
    (not a damaged disk) would leave it."""
    if forge_checksum:
        arrays["checksum"] = np.asarray(block_checksum(arrays, KEYS))
    with open(path, "wb") as f:
        np.savez(f, **arrays)


def corrupt(kind, files, tmp_path):
    """Apply corruption `kind` to the checkpoint files; return the points it makes untrustworthy."""
    victim = files[1]
    a = read(victim)
    if kind in ("shifted", "shifted-forged"):
        a["index"] = a["index"] + 1  # 6..11 -> 7..12: each row claims its neighbour's point
        rewrite(victim, a, forge_checksum=kind.endswith("forged"))
    elif kind == "doubled":
        a["F_cr"] = 2 * a["F_cr"]
        a["theta"] = 2 * a["theta"]
        rewrite(victim, a, forge_checksum=False)
    elif kind == "nan-at-ok":
        k = int(np.flatnonzero(a["status"] == 0)[0])
        a["theta"][k] = np.nan
        rewrite(victim, a, forge_checksum=True)
    elif kind == "unknown-status":
        a["status"][0] = 9
        rewrite(victim, a, forge_checksum=True)
    elif kind == "out-of-range":
        a["index"][-1] = 10_000
        rewrite(victim, a, forge_checksum=True)
    elif kind == "no-fingerprint":
        del a["fingerprint"]
        rewrite(victim, a, forge_checksum=False)
    elif kind == "truncated":
        victim.write_bytes(victim.read_bytes()[:200])
    elif kind in ("duplicate-wrong-after", "duplicate-wrong-before"):
        # a second, valid-looking file about the same points with other values: neither wins
        a["theta"] = a["theta"] + 1.0
        name = "batch-9999999-ffffffff.npz" if kind.endswith("after") else "batch-0000000-00000000.npz"
        rewrite(victim.with_name(name), a, forge_checksum=True)
    elif kind == "foreign-resolution":
        # a batch of a build of the same grid at another solver resolution
        other = tmp_path / "other" / "ci.nc"
        other.parent.mkdir()
        foreign = checkpointed(other, CI.with_resolution(41), batches=(np.arange(18, 24),))[0]
        shutil.copy(foreign, victim.with_name("batch-0000018-foreign0.npz"))
        return set(range(18, 24))  # never in this build's checkpoint: computed anyway
    else:
        raise AssertionError(kind)
    return set(range(6, 12))


CASES = ["shifted", "shifted-forged", "doubled", "nan-at-ok", "unknown-status", "out-of-range",
         "no-fingerprint", "truncated", "duplicate-wrong-after", "duplicate-wrong-before",
         "foreign-resolution"]
WHY = {
    "shifted": "checksum", "shifted-forged": "shifted or foreign indices", "doubled": "checksum",
    "nan-at-ok": "not finite at .* status ok", "unknown-status": "unknown status codes \\[9\\]",
    "out-of-range": "outside the grid", "no-fingerprint": "no fingerprint", "truncated": "unreadable",
    "duplicate-wrong-after": "disagrees with another batch", "duplicate-wrong-before": "disagrees with another batch",
    "foreign-resolution": "another build",
}


@pytest.mark.slow
@pytest.mark.parametrize("kind", CASES)
def test_corrupted_checkpoint_is_refused_and_the_map_is_exact(kind, reference, tmp_path, monkeypatch):
    out = tmp_path / "ci.nc"
    files = checkpointed(out)
    untrusted = corrupt(kind, files, tmp_path)
    log = tmp_path / "calls.log"
    monkeypatch.setenv("FAKE_SOLVER_LOG", str(log))
    with pytest.warns(UserWarning, match=f"refusing checkpoint file .*{WHY[kind]}"):
        report = build_map(CI, out, kind=KIND, solve=FAKE, workers=1, progress=False)
    assert report.refused, report.summary()
    solved = {[tuple(p) for p in COORDS].index(tuple(map(float, line.split())))
              for line in log.read_text().splitlines()}
    assert solved == untrusted | set(range(18, 24))  # the refused points and the unfinished ones
    assert sha(out) == sha(reference)  # byte for byte the uninterrupted build
    assert_matches_fake(load(out))
    assert not checkpoint_dir(out).exists()


def test_identical_duplicate_is_harmless(reference, tmp_path, monkeypatch):
    out = tmp_path / "ci.nc"
    files = checkpointed(out)
    shutil.copy(files[0], files[0].with_name("batch-0000000-copy0000.npz"))
    log = tmp_path / "calls.log"
    monkeypatch.setenv("FAKE_SOLVER_LOG", str(log))
    report = build_map(CI, out, kind=KIND, solve=FAKE, workers=1, progress=False)
    assert report.refused == [] and report.resumed == 18
    assert len(log.read_text().splitlines()) == 6
    assert sha(out) == sha(reference)


def test_nothing_is_deleted_when_the_written_map_fails_its_check(tmp_path, monkeypatch):
    """The map is checked (here: a reader that refuses it) before the checkpoint is deleted."""
    import snapmorph.pipeline.build as build

    out = tmp_path / "ci.nc"
    checkpointed(out)
    spec = dataclasses.replace(KIND, validate_file="fake_unit_solver:refuse_map")
    with pytest.raises(ValueError, match="refused by the reader"):
        build.build_map(CI, out, kind=spec, solve=FAKE, workers=1, progress=False)
    assert len(list(checkpoint_dir(out).glob("batch-*.npz"))) >= 3  # every batch kept
