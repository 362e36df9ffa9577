"""The pre-0.2 import names (solver, units, pipeline, maps, design, solver.unit,
solver.unit_model): they warn and hand out the very modules of snapmorph.*, from the
repository folder and from anywhere else."""

import subprocess
import sys
import textwrap

import pytest

CHECK = textwrap.dedent("""
    import importlib.util, warnings
    warnings.simplefilter("error", DeprecationWarning)
    import snapmorph.solver, snapmorph.units.planar, snapmorph.units.geometry, snapmorph.design
    for old in ("solver", "units", "pipeline", "maps", "design", "solver.structure", "solver.unit"):
        try:
            __import__(old)
        except DeprecationWarning as w:
            assert "deprecated import name" in str(w), w
        else:
            raise SystemExit(f"no DeprecationWarning for {old}")
    warnings.simplefilter("ignore", DeprecationWarning)
    import solver, solver.structure, solver.unit, solver.unit_model
    assert solver is snapmorph.solver and solver.structure is snapmorph.solver.structure
    assert solver.unit is snapmorph.units.planar and solver.unit_model is snapmorph.units.geometry
    from solver import Structure
    assert Structure is snapmorph.solver.Structure
    # the new names keep their own specs (the fingerprints of the maps read them)
    assert importlib.util.find_spec("snapmorph.units.planar").origin.endswith("planar.py")
    print("ok")
""")


@pytest.mark.parametrize("where", ["repository", "elsewhere"])
def test_old_names_warn_and_are_the_same_modules(where, tmp_path):
    from tests.test_layers import ROOT

    cwd = ROOT if where == "repository" else tmp_path
    out = subprocess.run([sys.executable, "-c", CHECK], cwd=cwd, capture_output=True, text=True,
                         timeout=300)
    assert out.returncode == 0 and out.stdout.strip() == "ok", out.stderr[-2000:]
