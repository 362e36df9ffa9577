"""Byte-identical maps: a rebuild of unchanged inputs writes the same file, byte for byte, here
or on a fresh clone (nothing in it depends on the clock, the checkout, the workers or the
batches)."""

import subprocess

from pipeline_testing import FAKE, REPO, load
from snapmorph.cli import main
from snapmorph.maps import CI_MAP
from snapmorph.pipeline import preset
from snapmorph.pipeline.build import build_map
from snapmorph.pipeline.fingerprint import RECORDED_PROVENANCE


def test_two_builds_of_the_ci_grid_are_the_same_bytes(tmp_path):
    """The CI grid (with its b/L axis) built twice, with other workers and batches and a
    second apart, gives two files `cmp` finds equal; the file records no build time or
    checkout."""
    first, second = tmp_path / "one.nc", tmp_path / "two.nc"
    build_map(preset("ci"), first, solve=FAKE, workers=2, progress=False)
    build_map(preset("ci"), second, solve=FAKE, workers=1, batch_size=7, progress=False)
    r = subprocess.run(["cmp", str(first), str(second)], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    ds = load(first)
    assert ds.sizes["b_over_L"] == 2 and ds.attrs["schema_version"] == 3
    for key, value in RECORDED_PROVENANCE.items():
        assert ds.attrs[key] == value


def test_a_fresh_build_writes_the_committed_ci_map_byte_for_byte(tmp_path, capsys):
    """What `make maps-ci` on a fresh clone does: rebuild the CI map from the committed sources
    (the real solver) into a new file; it must equal maps/data/ci.nc byte for byte. (Fails
    when the committed map is stale: rebuild it with `make maps-ci`.)"""
    out = tmp_path / "ci.nc"
    assert main(["maps", "build", "--grid", "ci", "--out", str(out), "--no-progress"]) == 0
    capsys.readouterr()
    r = subprocess.run(["cmp", str(out), str(CI_MAP)], capture_output=True, text=True, cwd=REPO)
    assert r.returncode == 0, r.stdout + r.stderr + " (run `make maps-ci` and commit the map)"
    assert main(["maps", "check", "--grid", "ci", "--against", str(CI_MAP), "--no-progress"]) == 0
