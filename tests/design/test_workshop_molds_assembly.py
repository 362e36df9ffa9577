"""STL molds (closed solids matching their DXF profiles) and the assembly sheet; the whole
workshop output in one call."""

import numpy as np
import pytest
import trimesh

from snapmorph.design import Unit
from snapmorph.design.assembly_sheet import assembly_sheet, assembly_steps
from snapmorph.design.drawings import mold_profile
from snapmorph.design.kerf import signed_area
from snapmorph.design.molds_stl import mold_mesh, write_stl_molds
from snapmorph.design.workshop import write_workshop

from five_units import FIVE, T, W


@pytest.mark.parametrize("u", [u for u in FIVE if not u.is_spacer] +
                         [Unit(L=0.1, h=0.045, t=0.75e-3, w=5e-3, side=1)])
def test_mold_is_a_closed_solid_of_its_profile(u):
    """Watertight, consistently wound, volume = profile area × width (the DXF profile
    extruded), as tall and long as the profile."""
    mesh = mold_mesh(u, width_mm=8.0, block_mm=4.0)
    assert mesh.is_watertight and mesh.is_winding_consistent and mesh.is_volume
    area = abs(signed_area(mold_profile(u, 4e-3) * 1e3))
    assert mesh.volume == pytest.approx(area * 8.0, rel=1e-9)
    lo, hi = mesh.bounds
    assert hi - lo == pytest.approx([u.L * 1e3, 8.0, u.h * 1e3 + 4.0], abs=1e-6)


def test_stl_files_read_back_watertight(tmp_path):
    paths = write_stl_molds(FIVE, tmp_path)
    assert [p.name for p in paths] == ["mold-1.stl", "mold-2.stl", "mold-4.stl", "mold-5.stl"]
    for p, u in zip(paths, [u for u in FIVE if not u.is_spacer]):
        mesh = trimesh.load(p)
        assert mesh.is_watertight and mesh.volume > 0
        assert mesh.bounds[1][1] == pytest.approx(u.w * 1e3 + 2.0)  # default width w + 2 mm
    with pytest.raises(ValueError, match="spacer"):
        mold_mesh(FIVE[2])


def test_assembly_steps_say_which_face_and_order():
    text = "\n".join(assembly_steps(FIVE, bed_length_mm=300.0))
    assert "arch 4 on unit 4 (129.4 mm), on the engraved face (+)" in text
    assert "arch 5 on unit 5 (133.2 mm), on the plain face (-); flat ends 7.0 mm long" in text
    assert "arch 3" not in text  # unit 3 is a spacer
    assert "J1: between units 3 and 4; glue tab T1 across it on the plain face (-)" in text
    assert "Snap the arches in this order, from the strip's start: 1, 2, 4, 5." in text
    assert "Join the base pieces" not in "\n".join(assembly_steps(FIVE))


def test_assembly_sheet_files(tmp_path):
    shape = np.stack([np.linspace(0, 0.4, 50), 0.05 * np.sin(np.linspace(0, 3, 50))], -1)
    paths = assembly_sheet(FIVE, tmp_path, shape_xy=shape)
    assert sorted(p.suffix for p in paths) == [".png", ".svg", ".txt"]
    assert all(p.stat().st_size > 500 for p in paths)
    assert "Snap the arches" in (tmp_path / "assembly.txt").read_text()


def test_write_workshop(tmp_path):
    ws = write_workshop(FIVE * 3, tmp_path / "bed", bed="600x400", kerf_mm=0.1)
    names = {p.name for p in ws.paths}
    assert {"sheet-1.dxf", "sheet-1.svg", "molds.dxf", "mold-1.stl", "assembly.txt",
            "assembly.png"} <= names
    assert ws.warnings == []
    assert "J1:" in (tmp_path / "bed" / "assembly.txt").read_text()
    ws = write_workshop(FIVE * 3, tmp_path / "nobed", stl=False, assembly=False)
    assert len(ws.warnings) == 1 and "600 x 400 mm" in ws.warnings[0]
    assert not any(p.suffix == ".stl" for p in ws.paths)
