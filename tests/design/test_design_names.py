"""Names: a snap pattern is not a unit state (parse_snapped, all_snap_patterns; the 0.1 names
warn), and `design.tolerance` is the function, its module `design.fabrication_tolerance`."""

import subprocess
import sys
import warnings

import pytest

import snapmorph.design as design
from snapmorph.design import Unit, all_snap_patterns, parse_snapped

T, W = 0.5e-3, 5e-3


def test_old_snap_pattern_names_warn_and_answer_the_same(design_map):
    with pytest.warns(DeprecationWarning, match="parse_snapped"):
        assert design.parse_state("101", 3) == parse_snapped("101", 3) == [True, False, True]
    units = [Unit(L=0.1, h=0.02, t=T, w=W, side=1), Unit(L=0.1, h=0.02, t=T, w=W, side=-1)]
    with pytest.warns(DeprecationWarning, match="all_snap_patterns"):
        old = design.all_states(units, design_map=design_map)
    new = all_snap_patterns(units, design_map=design_map)
    assert list(old) == list(new) == ["00", "01", "10", "11"]
    assert all((old[k] == new[k]).all() for k in new)


def test_tolerance_is_the_function():
    from snapmorph.design import fabrication_tolerance

    assert design.tolerance is fabrication_tolerance.tolerance
    assert callable(design.tolerance)


def test_old_module_path_of_tolerance_warns_and_leaves_the_function():
    """``from design.tolerance import ...`` (0.1) still finds the module, with a warning;
    importing it does not replace `snapmorph.design.tolerance`, the function."""
    code = ("import warnings\n"
            "import snapmorph.design as d\n"
            "with warnings.catch_warnings(record=True) as caught:\n"
            "    warnings.simplefilter('always')\n"
            "    from design.tolerance import perturbed_units\n"
            "    import design.tolerance\n"
            "print([str(w.message) for w in caught if w.category is DeprecationWarning])\n"
            "print(perturbed_units is d.fabrication_tolerance.perturbed_units, callable(d.tolerance),"
            " d.tolerance is d.fabrication_tolerance.tolerance)\n")
    with warnings.catch_warnings():
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                             timeout=120)
    assert out.returncode == 0, out.stderr
    assert "'design.tolerance' is a deprecated import name" in out.stdout
    assert "snapmorph.design.fabrication_tolerance" in out.stdout
    assert out.stdout.strip().splitlines()[-1] == "True True True"
